#include "neraf/io/npy.h"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "neraf/util/error.h"

namespace neraf::io {
namespace {

// Text of the value that follows `'key':` in the header dict, or "" when the key is absent.
std::string dict_value(const std::string& header, const std::string& key) {
  for (const char quote : {'\'', '"'}) {
    const std::string k = std::string(1, quote) + key + std::string(1, quote);
    size_t pos = header.find(k);
    if (pos == std::string::npos) continue;
    pos = header.find(':', pos + k.size());
    if (pos == std::string::npos) return "";
    size_t start = header.find_first_not_of(" \t", pos + 1);
    if (start == std::string::npos) return "";
    size_t end;
    if (header[start] == '(') {
      end = header.find(')', start);
      if (end == std::string::npos) return "";
      return header.substr(start, end - start + 1);
    }
    if (header[start] == '\'' || header[start] == '"') {
      end = header.find(header[start], start + 1);
      if (end == std::string::npos) return "";
      return header.substr(start, end - start + 1);
    }
    end = header.find_first_of(",}", start);
    if (end == std::string::npos) end = header.size();
    std::string v = header.substr(start, end - start);
    while (!v.empty() && (v.back() == ' ' || v.back() == '\t')) v.pop_back();
    return v;
  }
  return "";
}

std::vector<int64_t> parse_shape(const std::string& path, const std::string& text) {
  // "(2, 257, 78)", "(5,)" or "()"
  require(text.size() >= 2 && text.front() == '(' && text.back() == ')',
          path + ": malformed .npy header (shape " + text + "); re-save the array with numpy.save");
  std::vector<int64_t> shape;
  std::string inner = text.substr(1, text.size() - 2);
  size_t pos = 0;
  while (pos < inner.size()) {
    size_t comma = inner.find(',', pos);
    if (comma == std::string::npos) comma = inner.size();
    std::string item = inner.substr(pos, comma - pos);
    const size_t a = item.find_first_not_of(" \t");
    if (a != std::string::npos) {
      item = item.substr(a, item.find_last_not_of(" \t") - a + 1);
      char* end = nullptr;
      errno = 0;
      const long long v = std::strtoll(item.c_str(), &end, 10);
      require(
          errno == 0 && end && *end == '\0' && v >= 0,
          path + ": malformed .npy header (shape " + text + "); re-save the array with numpy.save");
      shape.push_back(v);
    }
    pos = comma + 1;
  }
  return shape;
}

}  // namespace

int64_t NpyHeader::num_elements() const {
  int64_t n = 1;
  for (const int64_t d : shape) n *= d;
  return n;
}

NpyHeader read_npy_header(const std::string& path) {
  std::error_code ec;
  require(!std::filesystem::is_directory(path, ec), path + ": is a folder, expected a .npy file");
  // A FIFO or device would block the reader; the size check below needs a file.
  require(!std::filesystem::exists(path, ec) || std::filesystem::is_regular_file(path, ec),
          path + ": is not a regular file (a pipe or device?); pass a .npy file");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path + ": cannot open (" + std::strerror(errno) + "); check that it exists");
  char magic[8];
  in.read(magic, 8);
  require(in.gcount() == 8 && std::memcmp(magic, "\x93NUMPY", 6) == 0,
          path + ": not a NumPy .npy file (bad magic); re-save the array with numpy.save");
  const int major = static_cast<unsigned char>(magic[6]);
  require(major >= 1 && major <= 3, path + ": unsupported .npy format version " +
                                        std::to_string(major) + "; re-save it with numpy.save");
  uint32_t header_len = 0;
  int64_t prefix = 0;
  if (major == 1) {
    unsigned char b[2];
    in.read(reinterpret_cast<char*>(b), 2);
    require(in.gcount() == 2, path + ": truncated .npy header; the file is damaged, re-create it");
    header_len = b[0] | (uint32_t(b[1]) << 8);
    prefix = 10;
  } else {
    unsigned char b[4];
    in.read(reinterpret_cast<char*>(b), 4);
    require(in.gcount() == 4, path + ": truncated .npy header; the file is damaged, re-create it");
    header_len = b[0] | (uint32_t(b[1]) << 8) | (uint32_t(b[2]) << 16) | (uint32_t(b[3]) << 24);
    prefix = 12;
  }
  require(header_len < (1u << 24), path + ": implausible .npy header length; the file is damaged");
  std::string header(header_len, '\0');
  in.read(header.data(), header_len);
  require(in.gcount() == static_cast<std::streamsize>(header_len),
          path + ": truncated .npy header; the file is damaged, re-create it");

  const std::string descr = dict_value(header, "descr");
  const std::string fortran = dict_value(header, "fortran_order");
  const std::string shape_text = dict_value(header, "shape");
  require(!descr.empty() && !fortran.empty() && !shape_text.empty(),
          path + ": malformed .npy header (" + header + "); re-save the array with numpy.save");
  const std::string d = descr.substr(1, descr.size() - 2);  // strip quotes
  NpyHeader h;
  if (d == "<f4" || d == "=f4") {
    h.element_size = 4;
  } else if (d == "<f8" || d == "=f8") {
    h.element_size = 8;
  } else {
    throw Error(path + ": .npy dtype '" + d +
                "' is not supported (need little-endian float32 '<f4' or float64 '<f8'); convert "
                "it with arr.astype('<f4')");
  }
  require(fortran == "False", path +
                                  ": .npy array is in Fortran order; re-save it with "
                                  "numpy.save(path, np.ascontiguousarray(arr))");
  h.shape = parse_shape(path, shape_text);
  h.data_offset = prefix + header_len;
  // The element count is checked before it is multiplied out: a hostile shape must not overflow
  // (and wrap around to a size the file seems to hold). The zero sizes are left out, so that no
  // partial product of num_elements() can overflow either.
  {
    const int64_t max_bytes = std::numeric_limits<int64_t>::max() - h.data_offset;
    int64_t n = 1;
    for (const int64_t d : h.shape) {
      if (d == 0) continue;
      require(n <= max_bytes / h.element_size / d,
              path + ": .npy shape " + shape_text +
                  " is too large for any array; the file is damaged, re-create it");
      n *= d;
    }
  }

  in.seekg(0, std::ios::end);
  const int64_t file_size = static_cast<int64_t>(in.tellg());
  const int64_t need = h.data_offset + h.num_elements() * h.element_size;
  require(file_size >= need, path + ": truncated .npy file (" + std::to_string(file_size) +
                                 " bytes, the header promises " + std::to_string(need) +
                                 "); the file is damaged, re-create it");
  return h;
}

NpyArray read_npy(const std::string& path) {
  const NpyHeader h = read_npy_header(path);
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  in.seekg(h.data_offset);
  const int64_t n = h.num_elements();
  NpyArray a;
  a.shape = h.shape;
  a.data.resize(static_cast<size_t>(n));
  if (h.element_size == 4) {
    in.read(reinterpret_cast<char*>(a.data.data()), n * 4);
  } else {
    std::vector<double> tmp(static_cast<size_t>(n));
    in.read(reinterpret_cast<char*>(tmp.data()), n * 8);
    for (int64_t i = 0; i < n; ++i) a.data[i] = static_cast<float>(tmp[i]);
  }
  require(in.gcount() == n * h.element_size,
          path + ": truncated .npy data; the file is damaged, re-create it");
  return a;
}

}  // namespace neraf::io
