// neraf_rt_make_test_model OUT.nrf [--channels C] [--frames T] [--relative-geometry] [--bf16]
//                                  [--seed N]
// Writes a small model with random weights in the SoundSpaces audio format (22.05 kHz, n_fft 512,
// hop 128): for the install test and for trying the runtime and its examples by hand. Its box is
// [-1, 3] x [0, 2.5] x [-2, 1.5] m.
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>

#include "../random_model.h"

int main(int argc, char** argv) {
  if (argc < 2 || argv[1][0] == '-') {
    std::fprintf(stderr,
                 "usage: %s OUT.nrf [--channels C] [--frames T] [--relative-geometry] [--bf16] "
                 "[--seed N]\n",
                 argv[0]);
    return 2;
  }
  neraf::rt::testing::RandomModelOptions o;
  o.n_fft = 512;
  o.win_length = 512;
  o.hop_length = 128;
  o.max_len = 24;
  o.trunk = {32, 32};
  for (int i = 2; i < argc; ++i) {
    const std::string a = argv[i];
    const bool has_value = i + 1 < argc;
    if (a == "--channels" && has_value) {
      o.channels = std::atoi(argv[++i]);
    } else if (a == "--frames" && has_value) {
      o.max_len = std::atoi(argv[++i]);
    } else if (a == "--seed" && has_value) {
      o.seed = uint32_t(std::strtoul(argv[++i], nullptr, 10));
    } else if (a == "--relative-geometry") {
      o.relative_geometry = true;
    } else if (a == "--bf16") {
      o.bf16 = true;
    } else {
      std::fprintf(stderr, "%s: unknown or incomplete option '%s'\n", argv[0], a.c_str());
      return 2;
    }
  }
  try {
    neraf::rt::write_model_file(argv[1], neraf::rt::testing::random_model(o));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
  return 0;
}
