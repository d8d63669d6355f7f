#pragma once
// Each subcommand lives in its own file and registers itself on the root app. A subcommand's
// callback does the work; user errors are thrown as neraf::Error and turned into
// "error: ..." + exit 1 by main().
#include <CLI/CLI.hpp>

namespace neraf::cli {

void register_metrics(CLI::App& app);
void register_auralize(CLI::App& app);
void register_train(CLI::App& app);
void register_render(CLI::App& app);
void register_eval(CLI::App& app);
void register_info(CLI::App& app);
void register_synth(CLI::App& app);
void register_export(CLI::App& app);
void register_calibrate(CLI::App& app);
void register_launch(CLI::App& app);

// Thrown by a command to exit with `code` without printing anything more (launch passes on a
// failed child's exit code; the child printed its own error).
struct ExitCode {
  int code;
};

}  // namespace neraf::cli
