#pragma once
// Temporaries that must not outlive a Ctrl-C. Outputs are built under temporary names
// (atomic_file.h); a SIGINT, SIGTERM or SIGHUP that ends the process would otherwise leave them
// until the next command writing beside them removes them as stale. While a RemoveOnSignal
// lives, such a signal deletes its path (a file or a whole folder) and then ends the process as
// the signal would have.
#include <string>

namespace neraf::io {

// Installs the handler for SIGINT, SIGTERM and SIGHUP, except where a signal is ignored (as under
// nohup). main() calls it once, before any work; handlers installed later (training's Ctrl-C
// guard) take over and hand the signal back to this one.
void install_signal_cleanup();

// Registers `path` for deletion by the handler until destroyed. Registering never fails: beyond
// the fixed number of slots a path is simply not registered (then only the stale-temporary sweep
// removes it after a kill).
class RemoveOnSignal {
 public:
  explicit RemoveOnSignal(const std::string& path);
  ~RemoveOnSignal();
  RemoveOnSignal(const RemoveOnSignal&) = delete;
  RemoveOnSignal& operator=(const RemoveOnSignal&) = delete;

 private:
  int slot_ = -1;
};

}  // namespace neraf::io
