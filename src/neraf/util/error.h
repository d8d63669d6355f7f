#pragma once
// One exception type for every error a user can cause. Its message is a single line that names the
// file (or flag) at fault and says how to fix it; the CLI prints it as "error: <message>", exit 1.
#include <stdexcept>
#include <string>

namespace neraf {

class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// The user stopped a command (Ctrl-C, SIGTERM) and it stopped cleanly, having saved what it could;
// the CLI prints "interrupted: <message>" and exits 130 (as a shell reports a SIGINT), so scripts
// can tell a stopped run from a finished one.
class Interrupted : public Error {
 public:
  explicit Interrupted(const std::string& message) : Error(message) {}
};

// Throws Error(message) when `condition` is false. For user-facing checks, not for invariants.
inline void require(bool condition, const std::string& message) {
  if (!condition) throw Error(message);
}

}  // namespace neraf
