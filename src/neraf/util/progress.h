#pragma once
// A progress bar with rate and ETA for long work. On a terminal it redraws one line on stderr; when
// stderr is a file or pipe it prints a plain line at most every few seconds, so logs stay readable.
#include <chrono>
#include <cstdint>
#include <string>

namespace neraf {

struct ProgressOptions {
  std::string unit = "it";       // shown in the rate, e.g. "RIR/s"
  double min_redraw_s = 0.1;     // terminal redraw interval
  double min_log_s = 5.0;        // interval between lines when not a terminal
  bool enabled = true;           // false: print nothing (tests, --quiet)
};

class Progress {
 public:
  Progress(std::string label, int64_t total, ProgressOptions options = {});
  ~Progress();  // finishes the line if finish() was not called

  // Sets the number of finished items; `status` is appended (e.g. "loss 0.012  PSNR 24.1").
  void update(int64_t done, const std::string& status = "");
  void finish(const std::string& status = "");

  double elapsed_s() const;

 private:
  void draw(bool final_line);

  std::string label_;
  int64_t total_;
  int64_t done_ = 0;
  std::string status_;
  ProgressOptions options_;
  bool is_tty_;
  bool finished_ = false;
  std::chrono::steady_clock::time_point start_;
  std::chrono::steady_clock::time_point last_draw_;
};

// "1:02:03", "4:05" or "12.3s".
std::string format_duration(double seconds);

}  // namespace neraf
