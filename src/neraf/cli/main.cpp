// neraf: the one program. Parses the command line and dispatches to a subcommand.
// Exit codes: 0 success, 1 runtime error (one "error: ..." line), 2 usage error (message + usage).
#include <fftw3.h>
#include <malloc.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>

#include "neraf/cli/commands.h"
#include "neraf/cli/system_info.h"
#include "neraf/util/error.h"

namespace {

// Large per-step tensors would otherwise go through mmap/munmap every step and page-fault each
// time; keeping freed memory in the heap measured ~2× faster training steps on 2 cores.
void tune_malloc() {
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

constexpr const char* kOutOfMemory =
    "error: out of memory: the command needs more memory than this machine has free; use smaller "
    "sizes (--rays, --threads, the dataset or scene) or free memory";

// The deepest subcommand the user named, so a usage error prints that subcommand's usage.
const CLI::App* selected_command(const CLI::App& app) {
  const CLI::App* current = &app;
  for (;;) {
    auto subs = current->get_subcommands();
    if (subs.empty()) return current;
    current = subs.front();
  }
}

}  // namespace

int main(int argc, char** argv) {
  tune_malloc();
  // neraf_dsp and neraf_rt plan FFTs under their own locks; eval and render trajectory use both
  // from several threads, so FFTW's (process-global) planner must be safe across them.
  fftwf_make_planner_thread_safe();
  neraf::cli::use_all_cores();
  CLI::App app{
      "neraf: neural radiance and acoustic fields (NeRAF) on the CPU.\n"
      "Learns a room's pictures and impulse responses jointly; renders, evaluates and auralizes."};
  app.name("neraf");
  app.require_subcommand(1, 1);
  app.set_version_flag("--version", [] { return neraf::cli::version_text(); });
  app.footer("Run 'neraf <command> --help' for a command's options.");

  neraf::cli::register_metrics(app);
  neraf::cli::register_auralize(app);
  neraf::cli::register_train(app);
  neraf::cli::register_launch(app);
  neraf::cli::register_render(app);
  neraf::cli::register_eval(app);
  neraf::cli::register_export(app);
  neraf::cli::register_calibrate(app);
  neraf::cli::register_info(app);
  neraf::cli::register_synth(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    std::printf("%s", selected_command(app)->help().c_str());
    return 0;
  } catch (const CLI::CallForAllHelp& e) {
    std::printf("%s", app.help("", CLI::AppFormatMode::All).c_str());
    return 0;
  } catch (const CLI::CallForVersion& e) {
    std::printf("%s\n", e.what());
    return 0;
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "error: %s\n\n%s", e.what(), selected_command(app)->help().c_str());
    return 2;
  } catch (const neraf::cli::ExitCode& e) {
    return e.code;
  } catch (const neraf::Error& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  } catch (const std::bad_alloc&) {
    // Sizes are bounded before work starts; this is what is left (a machine with little free
    // memory), said in one line instead of "std::bad_alloc".
    std::fprintf(stderr, "%s\n", kOutOfMemory);
    return 1;
  } catch (const std::exception& e) {
    // LibTorch and the standard library: keep the first line, which carries the reason.
    std::string what = e.what();
    what = what.substr(0, what.find('\n'));
    // LibTorch's allocator: "DefaultCPUAllocator: can't allocate memory: you tried to allocate
    // N bytes. Error code 12 (...)" (and its source location), as one neraf line.
    if (what.find("can't allocate memory") != std::string::npos) {
      std::fprintf(stderr, "%s\n", kOutOfMemory);
      return 1;
    }
    std::fprintf(stderr, "error: %s\n", what.c_str());
    return 1;
  }
  // What went to standard output (--json, --print-scene) must have arrived: `> file` on a full
  // disk fails here, not silently.
  if (std::fflush(stdout) != 0 || std::ferror(stdout)) {
    std::fprintf(stderr,
                 "error: cannot write to standard output (%s); free disk space or "
                 "redirect it elsewhere\n",
                 std::strerror(errno));
    return 1;
  }
  return 0;
}
