#pragma once
// Strict checks of numbers typed by a user (command-line flags): no wrap-around, no silent clamp,
// no partial parse. Each returns "" when the text is acceptable, else the reason as the tail of a
// one-line message ("must be a whole number in [1, 1024]; got -5"), for the caller to prefix with
// the flag's name.
#include <cstdint>
#include <string>

namespace neraf {

// A whole number in [lo, hi]: decimal digits with an optional sign, or scientific notation that
// denotes a whole number ("1e6"). No spaces, hex or fractions. On success `canonical` (when
// given) receives the plain decimal form, so "1e3" can be handed on as "1000".
std::string check_integer(const std::string& text, int64_t lo, int64_t hi,
                          std::string* canonical = nullptr);

// A whole number in [0, hi] for unsigned 64-bit values (seeds): a minus sign is an error, not
// 2^64 - 1.
std::string check_unsigned(const std::string& text, uint64_t hi, std::string* canonical = nullptr);

// A finite number in [lo, hi] (or (lo, hi] when lo_open); NaN and infinities are errors.
std::string check_real(const std::string& text, double lo, double hi, bool lo_open = false);

// Range text as the messages and --help show it: "[1, 1024]", "(0, 1]", "[0.01, 120]".
std::string range_text(int64_t lo, int64_t hi);
std::string range_text(double lo, double hi, bool lo_open = false);

// The most worker threads a --threads flag accepts: 4 x the machine's hardware threads (more
// only adds contention; 100000 threads stalled the machine). At least 4.
int max_thread_count();

}  // namespace neraf
