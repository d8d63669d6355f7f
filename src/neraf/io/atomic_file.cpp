#include "neraf/io/atomic_file.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "neraf/util/error.h"

namespace fs = std::filesystem;

namespace neraf::io {

void write_atomically(const std::string& path, const std::function<void(const std::string&)>& write) {
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) {
    fs::create_directories(target.parent_path(), ec);
    require(!ec, path + ": cannot create the folder " + target.parent_path().string() + " (" +
                     ec.message() + "); choose a writable output path");
  }
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  try {
    write(tmp);
  } catch (...) {
    fs::remove(tmp, ec);
    throw;
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw Error(path + ": cannot write the file (" + ec.message() + "); choose a writable output path");
  }
}

void write_text_atomically(const std::string& path, const std::string& text) {
  write_atomically(path, [&](const std::string& tmp) {
    std::ofstream out(tmp, std::ios::binary);
    require(out.good(), path + ": cannot open for writing (" + std::strerror(errno) +
                            "); choose a writable output path");
    out << text;
    out.flush();
    require(out.good(), path + ": write failed (disk full?); free space and retry");
  });
}

std::string read_text_file(const std::string& path) {
  std::error_code ec;
  require(fs::exists(path, ec), path + ": no such file; check the path");
  require(!fs::is_directory(path, ec), path + ": is a folder, expected a file");
  std::ifstream in(path, std::ios::binary);
  require(in.good(), path + ": cannot open (" + std::strerror(errno) + "); check its permissions");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace neraf::io
