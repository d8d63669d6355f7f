#include "neraf/util/number_text.h"

#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>
#include <thread>

namespace neraf {
namespace {

// What the text looks like, before any value is computed.
enum class Shape { none, integer, real };

// integer: [+-]?digits. real: [+-]?(digits[.digits]|.digits)([eE][+-]?digits)?, or nan/inf
// spellings (which strtod accepts; the callers reject them with a clear reason).
Shape shape_of(const std::string& s) {
  size_t i = 0;
  const size_t n = s.size();
  if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
  const size_t digits_start = i;
  while (i < n && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
  const size_t int_digits = i - digits_start;
  if (i == n && int_digits > 0) return Shape::integer;
  size_t frac_digits = 0;
  if (i < n && s[i] == '.') {
    ++i;
    const size_t f = i;
    while (i < n && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    frac_digits = i - f;
  }
  if (int_digits + frac_digits == 0) {
    // nan, inf, infinity in any case: a number, but not a finite one.
    std::string word;
    for (size_t k = digits_start; k < n; ++k)
      word += static_cast<char>(std::tolower(static_cast<unsigned char>(s[k])));
    return (word == "nan" || word == "inf" || word == "infinity") ? Shape::real : Shape::none;
  }
  if (i < n && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < n && (s[i] == '+' || s[i] == '-')) ++i;
    const size_t e = i;
    while (i < n && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    if (i == e) return Shape::none;
  }
  return i == n ? Shape::real : Shape::none;
}

std::string got(const std::string& text) { return "; got " + (text.empty() ? "\"\"" : text); }

std::string format_real(double v) {
  std::ostringstream s;
  s.precision(10);
  s << v;
  return s.str();
}

}  // namespace

std::string range_text(int64_t lo, int64_t hi) {
  return "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
}

std::string range_text(double lo, double hi, bool lo_open) {
  return (lo_open ? "(" : "[") + format_real(lo) + ", " + format_real(hi) + "]";
}

std::string check_integer(const std::string& text, int64_t lo, int64_t hi, std::string* canonical) {
  const std::string want = "must be a whole number in " + range_text(lo, hi);
  const Shape shape = shape_of(text);
  if (shape == Shape::none) return want + got(text);
  long long value = 0;
  if (shape == Shape::integer) {
    errno = 0;
    char* end = nullptr;
    value = std::strtoll(text.c_str(), &end, 10);
    if (errno == ERANGE) return want + got(text);  // beyond int64: out of range either way
  } else {
    errno = 0;
    const long double v = std::strtold(text.c_str(), nullptr);
    if (!std::isfinite(v) || v != std::floor(v)) return want + got(text);
    // Compared as long double before converting, so 1e30 is an error rather than a wrap.
    if (v < static_cast<long double>(lo) || v > static_cast<long double>(hi))
      return want + got(text);
    value = static_cast<long long>(v);
  }
  if (value < lo || value > hi) return want + got(text);
  if (canonical) *canonical = std::to_string(value);
  return "";
}

std::string check_unsigned(const std::string& text, uint64_t hi, std::string* canonical) {
  const std::string want = "must be a whole number in [0, " + std::to_string(hi) + "]";
  const Shape shape = shape_of(text);
  if (shape == Shape::none || text[0] == '-') return want + got(text);  // strtoull wraps "-1"
  unsigned long long value = 0;
  if (shape == Shape::integer) {
    errno = 0;
    char* end = nullptr;
    value = std::strtoull(text.c_str(), &end, 10);
    if (errno == ERANGE) return want + got(text);
  } else {
    const long double v = std::strtold(text.c_str(), nullptr);
    if (!std::isfinite(v) || v != std::floor(v) || v < 0 || v > static_cast<long double>(hi))
      return want + got(text);
    value = static_cast<unsigned long long>(v);
  }
  if (value > hi) return want + got(text);
  if (canonical) *canonical = std::to_string(value);
  return "";
}

std::string check_real(const std::string& text, double lo, double hi, bool lo_open) {
  const std::string want = "must be a finite number in " + range_text(lo, hi, lo_open);
  if (shape_of(text) == Shape::none) return want + got(text);
  const double v = std::strtod(text.c_str(), nullptr);  // ERANGE overflow gives inf: refused
  if (!std::isfinite(v)) return want + got(text);
  if (lo_open ? !(v > lo) : !(v >= lo)) return want + got(text);
  if (!(v <= hi)) return want + got(text);
  return "";
}

int max_thread_count() {
  const unsigned hw = std::thread::hardware_concurrency();  // 0 when unknown
  return 4 * static_cast<int>(hw > 0 ? hw : 1);
}

}  // namespace neraf
