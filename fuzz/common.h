#pragma once
// What the fuzz targets share: handing an input to a parser that only takes a path, and failing
// loudly when a parser breaks a promise of its header.
#include <stdlib.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace neraf::fuzz {

// A private folder for the inputs of this process, removed at exit. libFuzzer runs one input at a
// time per process, so one file per suffix is enough and no name is ever reused concurrently
// (several fuzzer processes each get their own folder).
class InputFolder {
 public:
  InputFolder() {
    std::string tmpl = (std::filesystem::temp_directory_path() / "neraf_fuzz_XXXXXX").string();
    if (!::mkdtemp(tmpl.data())) {
      std::perror("neraf fuzz: mkdtemp");
      std::abort();  // not a finding: the target cannot run at all
    }
    path_ = tmpl;
  }
  ~InputFolder() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  InputFolder(const InputFolder&) = delete;
  InputFolder& operator=(const InputFolder&) = delete;

  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// Writes the input to "<folder>/input<suffix>" (replacing the previous one) and returns its path.
// The suffix matters to parsers that look at the extension.
inline std::string write_input(const uint8_t* data, size_t size, const std::string& suffix) {
  static const InputFolder folder;  // the one piece of state: created on the first input
  const std::string path = (folder.path() / ("input" + suffix)).string();
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  out.close();
  if (!out) {
    std::fprintf(stderr, "neraf fuzz: cannot write %s\n", path.c_str());
    std::abort();  // not a finding either: the disk is full or the folder went away
  }
  return path;
}

// A broken promise of a parser's header (an invariant of its result): a finding, reported as a
// crash so that libFuzzer saves the input.
#define NERAF_FUZZ_CHECK(cond)                                                            \
  do {                                                                                    \
    if (!(cond)) {                                                                        \
      std::fprintf(stderr, "%s:%d: invariant violated: %s\n", __FILE__, __LINE__, #cond); \
      std::abort();                                                                       \
    }                                                                                     \
  } while (0)

}  // namespace neraf::fuzz
