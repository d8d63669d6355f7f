#pragma once
// Dataset problems found while loading or validating: each names the file at fault, what is wrong
// and how to fix it. Loaders collect them and throw one neraf::Error summarising the errors;
// `neraf info` prints them all.
#include <string>
#include <vector>

namespace neraf::data {

struct Problem {
  enum class Severity { error, warning };
  Severity severity = Severity::error;
  std::string file;  // the file (or folder) at fault
  std::string what;  // what is wrong
  std::string fix;   // how to fix it

  bool is_error() const { return severity == Severity::error; }
  std::string to_string() const;  // "<file>: <what>; <fix>"
};

class ProblemList {
 public:
  void error(std::string file, std::string what, std::string fix);
  void warning(std::string file, std::string what, std::string fix);
  // An error from a neraf::Error's one-line message "<file>: <what>; <fix>": the leading file is
  // dropped (the Problem names it) and the text after the last "; " becomes the fix.
  void error_from_message(const std::string& file, const std::string& message);
  void add(Problem p) { items_.push_back(std::move(p)); }
  void append(const std::vector<Problem>& more);

  const std::vector<Problem>& items() const { return items_; }
  int64_t num_errors() const;
  int64_t num_warnings() const;

  // Throws neraf::Error if there is any error: the first error's line, plus "(and N more
  // problems; run 'neraf info <dataset>' to list them all)" when there are more. `dataset` is the
  // folder named in that hint.
  void throw_if_errors(const std::string& dataset) const;
  // Prints the warnings with neraf::warn (at most `max_lines`, then a count).
  void print_warnings(int max_lines = 5) const;

 private:
  std::vector<Problem> items_;
};

}  // namespace neraf::data
