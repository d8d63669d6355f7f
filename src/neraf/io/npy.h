#pragma once
// NumPy .npy files (format versions 1.0, 2.0 and 3.0): little-endian float32 / float64 arrays in
// C order, as `np.save` writes them (SoundSpaces magnitude files are [2, 257, T] float32).
// Anything else (big-endian, Fortran order, integer or object dtypes) is rejected with an error
// naming the file.
#include <cstdint>
#include <string>
#include <vector>

namespace neraf::io {

struct NpyHeader {
  std::vector<int64_t> shape;  // empty for a scalar
  int element_size = 0;        // 4 (float32) or 8 (float64)
  int64_t data_offset = 0;     // byte offset of the first element

  int64_t num_elements() const;
};

// Reads and checks only the header (cheap: used to learn the shapes of many files).
NpyHeader read_npy_header(const std::string& path);

struct NpyArray {
  std::vector<int64_t> shape;
  std::vector<float> data;  // C order; float64 files are converted to float32
};

NpyArray read_npy(const std::string& path);

}  // namespace neraf::io
