#include "neraf/data/problem.h"

#include <algorithm>

#include "neraf/util/error.h"
#include "neraf/util/log.h"

namespace neraf::data {

std::string Problem::to_string() const {
  std::string s = file.empty() ? what : file + ": " + what;
  if (!fix.empty()) s += "; " + fix;
  return s;
}

void ProblemList::error(std::string file, std::string what, std::string fix) {
  items_.push_back({Problem::Severity::error, std::move(file), std::move(what), std::move(fix)});
}

void ProblemList::warning(std::string file, std::string what, std::string fix) {
  items_.push_back({Problem::Severity::warning, std::move(file), std::move(what), std::move(fix)});
}

void ProblemList::error_from_message(const std::string& file, const std::string& message) {
  const std::string prefix = file + ": ";
  std::string what =
      message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
  std::string fix;
  const size_t semi = what.rfind("; ");
  if (semi != std::string::npos) {
    fix = what.substr(semi + 2);
    what.resize(semi);
  }
  error(file, std::move(what), std::move(fix));
}

void ProblemList::append(const std::vector<Problem>& more) {
  items_.insert(items_.end(), more.begin(), more.end());
}

int64_t ProblemList::num_errors() const {
  return std::count_if(items_.begin(), items_.end(), [](const Problem& p) { return p.is_error(); });
}

int64_t ProblemList::num_warnings() const {
  return static_cast<int64_t>(items_.size()) - num_errors();
}

void ProblemList::throw_if_errors(const std::string& dataset) const {
  const int64_t n = num_errors();
  if (n == 0) return;
  const auto first =
      std::find_if(items_.begin(), items_.end(), [](const Problem& p) { return p.is_error(); });
  std::string msg = first->to_string();
  if (n > 1)
    msg += " (and " + std::to_string(n - 1) + " more error" + (n > 2 ? "s" : "") +
           "; run 'neraf info " + dataset + "' to list them all)";
  throw Error(msg);
}

void ProblemList::print_warnings(int max_lines) const {
  int shown = 0, total = 0;
  for (const Problem& p : items_) {
    if (p.is_error()) continue;
    ++total;
    if (shown < max_lines) {
      warn(p.to_string());
      ++shown;
    }
  }
  if (total > shown) warn(std::to_string(total - shown) + " more warnings not shown");
}

}  // namespace neraf::data
