#include "neraf/cli/system_info.h"

#include <sched.h>
#include <torch/torch.h>
#include <unistd.h>

#include <algorithm>
#include <climits>
#include <cstdlib>
#include <fstream>
#include <string>

#include "neraf/util/log.h"
#include "neraf/util/number_text.h"

namespace neraf::cli {

std::string own_executable() {
  char path[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
  return n > 0 ? std::string(path, size_t(n)) : std::string();
}

void run_again_with_short_openmp_spin(char** argv) {
  if (std::getenv("GOMP_SPINCOUNT") || std::getenv("OMP_WAIT_POLICY")) return;
  const std::string exe = own_executable();
  if (exe.empty() || setenv("GOMP_SPINCOUNT", "1000", 1) != 0) return;
  execv(exe.c_str(), argv);
  unsetenv("GOMP_SPINCOUNT");  // the exec failed (the binary replaced?): carry on as we are
}

std::string openmp_wait_text() {
  std::string out;
  for (const char* name : {"OMP_WAIT_POLICY", "GOMP_SPINCOUNT"})
    if (const char* value = std::getenv(name))
      out += (out.empty() ? "" : ", ") + std::string(name) + "=" + value;
  return out.empty() ? "libgomp default" : out;
}

void use_all_cores() {
  cpu_set_t allowed;
  const int cores =
      std::max(1, sched_getaffinity(0, sizeof(allowed), &allowed) == 0 ? CPU_COUNT(&allowed) : 1);
  if (const char* env = std::getenv("OMP_NUM_THREADS")) {
    // The user's count, if it is one --threads would take: 100000 threads crashed in libgomp, 0
    // or text made LibTorch print raw warnings.
    std::string count;
    const std::string why = check_integer(env, 1, max_thread_count(), &count);
    if (why.empty()) {
      torch::set_num_threads(std::stoi(count));
      return;
    }
    warn("OMP_NUM_THREADS=" + std::string(env) + ": ignored (" + why + "); using the " +
         std::to_string(cores) + " cores (--threads sets the count where a command has it)");
  }
  torch::set_num_threads(cores);
}

std::string loaded_blas_library() {
  // A product large enough to go through BLAS (small ones may take a native path).
  auto a = torch::ones({64, 64});
  (void)torch::mm(a, a);
  std::ifstream maps("/proc/self/maps");
  std::string line;
  while (std::getline(maps, line)) {
    const auto slash = line.find('/');
    if (slash == std::string::npos) continue;
    const std::string path = line.substr(slash);
    if (path.find("blas") != std::string::npos) return path;
  }
  return "";
}

std::string version_text() {
  const std::string blas = loaded_blas_library();
  return std::string("neraf " NERAF_VERSION "\nLibTorch ") + TORCH_VERSION + ", " +
         std::to_string(torch::get_num_threads()) + " threads\nOpenMP wait " + openmp_wait_text() +
         "\nBLAS " + (blas.empty() ? "(none loaded)" : blas);
}

}  // namespace neraf::cli
