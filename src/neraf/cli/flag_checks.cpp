#include "neraf/cli/flag_checks.h"

#include <string>

#include "neraf/util/number_text.h"

namespace neraf::cli {

CLI::Validator whole_number(int64_t lo, int64_t hi) {
  return CLI::Validator(
      [lo, hi](std::string& text) {
        std::string canonical;
        std::string why = check_integer(text, lo, hi, &canonical);
        if (why.empty()) text = canonical;  // CLI11 converts only plain decimal
        return why;
      },
      range_text(lo, hi));
}

CLI::Validator seed_number(uint64_t hi) {
  return CLI::Validator(
      [hi](std::string& text) {
        std::string canonical;
        std::string why = check_unsigned(text, hi, &canonical);
        if (why.empty()) text = canonical;
        return why;
      },
      "[0, " + std::to_string(hi) + "]");
}

CLI::Validator real_number(double lo, double hi, bool lo_open) {
  return CLI::Validator(
      [lo, hi, lo_open](std::string& text) { return check_real(text, lo, hi, lo_open); },
      range_text(lo, hi, lo_open));
}

CLI::Validator thread_count() {
  const int most = max_thread_count();
  return CLI::Validator(
      [most](std::string& text) {
        std::string canonical;
        std::string why = check_integer(text, 1, most, &canonical);
        if (!why.empty())
          return why + " (at most 4 x the " + std::to_string(most / 4) +
                 " hardware threads of this machine)";
        text = canonical;
        return why;
      },
      range_text(int64_t{1}, int64_t{most}));
}

}  // namespace neraf::cli
