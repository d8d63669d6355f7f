#include "neraf/train/image_output.h"

// stb_image_write's implementation is compiled into Debian's libstb (linked through neraf_data).
#include <stb/stb_image_write.h>
#include <torch/torch.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

#include "neraf/io/atomic_file.h"
#include "neraf/util/error.h"

namespace neraf::train {

torch::Tensor to_uint8(const torch::Tensor& image) {
  return (image.to(torch::kFloat32).clamp(0.0, 1.0) * 255.0).round().to(torch::kUInt8);
}

namespace {
void append_bytes(void* context, void* data, int size) {
  auto* out = static_cast<std::vector<unsigned char>*>(context);
  const auto* p = static_cast<const unsigned char*>(data);
  out->insert(out->end(), p, p + size);
}
}  // namespace

void write_png(const std::string& path, const torch::Tensor& image) {
  TORCH_CHECK(image.dim() == 3 && (image.size(2) == 3 || image.size(2) == 1),
              "write_png: expected [H, W, 3] or [H, W, 1]");
  const torch::Tensor u8 =
      (image.scalar_type() == torch::kUInt8 ? image : to_uint8(image)).cpu().contiguous();
  const int h = static_cast<int>(u8.size(0)), w = static_cast<int>(u8.size(1));
  const int c = static_cast<int>(u8.size(2));
  std::vector<unsigned char> bytes;
  const int ok = stbi_write_png_to_func(append_bytes, &bytes, w, h, c, u8.data_ptr<uint8_t>(), w * c);
  require(ok != 0 && !bytes.empty(), path + ": PNG encoding failed");
  io::write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    require(out.good(), path + ": cannot open for writing (" + std::strerror(errno) +
                            "); choose a writable output path");
    out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    out.flush();
    require(out.good(), path + ": write failed (disk full?); free space and retry");
  });
}

}  // namespace neraf::train
