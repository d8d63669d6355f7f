// neraf: the one program. Parses the command line and dispatches to a subcommand.
// Exit codes: 0 success, 1 runtime error (one "error: ..." line), 2 usage error (message + usage),
// 130 stopped by Ctrl-C / SIGTERM after saving what it could (training's checkpoint).
#include <fftw3.h>
#include <sys/resource.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <new>
#include <string>
#include <vector>

#include "neraf/cli/commands.h"
#include "neraf/cli/system_info.h"
#include "neraf/io/signal_cleanup.h"
#include "neraf/util/error.h"
#include "neraf/util/heap.h"

namespace {

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

// "neraf render rir": the command as the user types it.
std::string command_path(const CLI::App& command) {
  std::string path;
  for (const CLI::App* c = &command; c->get_parent(); c = c->get_parent())
    path = " " + c->get_name() + path;
  return "neraf" + path;
}

// Edit distance with adjacent transpositions ("stpes" is one edit from "steps"), for "did you
// mean" on a mistyped command or option.
size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<size_t>> d(a.size() + 1, std::vector<size_t>(b.size() + 1));
  for (size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (size_t i = 1; i <= a.size(); ++i)
    for (size_t j = 1; j <= b.size(); ++j) {
      d[i][j] = std::min(
          {d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + (a[i - 1] != b[j - 1] ? 1 : 0)});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[a.size()][b.size()];
}

// " (did you mean 'train'?)" when an argument the command did not expect is close to one of its
// subcommands (`args`: the command line, when no subcommand was recognised) or long options;
// "" otherwise.
std::string suggestion(const CLI::App& command, const std::vector<std::string>& args) {
  const bool at_root = command.get_parent() == nullptr;
  for (const std::string& arg : at_root ? args : command.remaining()) {
    const bool is_option = arg.rfind("--", 0) == 0;
    if (at_root == is_option) continue;  // the root has subcommands, the others options
    const std::string word = is_option ? arg.substr(2, arg.find('=') - 2) : arg;
    std::vector<std::string> names;
    if (is_option) {
      for (const CLI::Option* o : command.get_options())
        for (const std::string& name : o->get_lnames()) names.push_back(name);
    } else {
      for (const CLI::App* sub : command.get_subcommands({})) names.push_back(sub->get_name());
    }
    std::string best;
    size_t best_distance = std::max<size_t>(1, word.size() / 3) + 1;
    for (const std::string& name : names) {
      const size_t d = edit_distance(word, name);
      if (d < best_distance) best_distance = d, best = name;
    }
    if (!best.empty())
      return " (did you mean '" + std::string(is_option ? "--" : "") + best + "'?)";
    if (at_root) break;  // only the first word names a command
  }
  return "";
}

// An option given an empty value (`--out ""`, `--checkpoint=`) is a usage error everywhere:
// taken as "not given" it made synth write a whole dataset for `--plan-only ""` and render use
// the latest checkpoint for `--checkpoint ""`.
void refuse_empty_values(CLI::App& command) {
  const CLI::Validator non_empty(
      [](std::string& text) {
        return text.empty() ? std::string("empty value; give one, or leave the option out")
                            : std::string();
      },
      "");
  for (CLI::Option* option : command.get_options())
    if (option->get_type_size_max() > 0) option->check(non_empty);
  for (CLI::App* sub : command.get_subcommands([](CLI::App*) { return true; }))
    refuse_empty_values(*sub);
}

// OpenBLAS and LibTorch reserve address space when they start; under a small `ulimit -v` OpenBLAS
// retries its failing reservation for ever (a hang at 1 GB). "" when the limit is absent or ample.
std::string address_space_problem() {
  constexpr rlim_t kNeeded = rlim_t{2} << 30;
  struct rlimit limit {};
  if (::getrlimit(RLIMIT_AS, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY ||
      limit.rlim_cur >= kNeeded)
    return "";
  return "the address-space limit (ulimit -v) is " + std::to_string(limit.rlim_cur >> 20) +
         " MiB; neraf needs at least " + std::to_string(kNeeded >> 20) +
         " MiB (LibTorch and OpenBLAS reserve address space at start): raise it with ulimit -v";
}

}  // namespace

int main(int argc, char** argv) {
  neraf::cli::run_again_with_short_openmp_spin(argv);
  // A file-size limit (ulimit -f) then fails the write with EFBIG, which the writers report and
  // clean up after, instead of killing the process mid-write.
  std::signal(SIGXFSZ, SIG_IGN);
  if (const std::string why = address_space_problem(); !why.empty()) {
    std::fprintf(stderr, "error: %s\n", why.c_str());
    return 1;
  }
  neraf::util::keep_freed_memory_in_heap();
  // neraf_dsp and neraf_rt plan FFTs under their own locks; eval and render trajectory use both
  // from several threads, so FFTW's (process-global) planner must be safe across them.
  fftwf_make_planner_thread_safe();
  neraf::cli::use_all_cores();
  // Ctrl-C anywhere deletes the temporaries of the output being written (training's own guard
  // takes over while it runs, to save a checkpoint first).
  neraf::io::install_signal_cleanup();
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
  refuse_empty_values(app);

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
    // The error, then one line on where the usage is: a whole help page after it would scroll
    // the error out of sight.
    const CLI::App* command = selected_command(app);
    const std::string path = command_path(*command);
    std::fprintf(stderr, "error: %s%s\nUsage: %s%s [OPTIONS]; '%s --help' explains them\n",
                 e.what(),
                 suggestion(*command, std::vector<std::string>(argv + 1, argv + argc)).c_str(),
                 path.c_str(), command->get_parent() ? "" : " COMMAND", path.c_str());
    return 2;
  } catch (const neraf::Interrupted& e) {
    std::fprintf(stderr, "interrupted: %s\n", e.what());
    return 130;
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
