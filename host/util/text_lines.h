#pragma once
// Line-oriented reading of text formats with the file:line of every value, so
// that a malformed file fails with a message naming the place.

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "sapmvs/util/error.h"

namespace sapmvs {

class TextLines {
 public:
  // Opens `path`; throws sapmvs::Error naming it when it cannot be read.
  explicit TextLines(const std::filesystem::path& path);

  // Next line that is neither blank nor a `#` comment, split on whitespace.
  // Returns false at the end of the file.
  bool Next(std::vector<std::string>* tokens);
  // Like Next, but the raw line (trailing CR removed), including blank lines;
  // comment lines are still skipped when `skip_comments`.
  bool NextRaw(std::string* line, bool skip_comments = true);

  int line() const { return line_; }
  const std::string& file() const { return file_; }
  // An InputError at the current line.
  InputError Fail(const std::string& message) const { return InputError(file_, line_, message); }

  // Parses token `text` as a finite double; `what` names the field.
  double Double(const std::string& text, const std::string& what) const;
  int Int(const std::string& text, const std::string& what) const;
  // Requires exactly (or, with `at_least`, at least) `n` tokens.
  void ExpectCount(const std::vector<std::string>& tokens, size_t n, const std::string& layout,
                   bool at_least = false) const;

 private:
  std::ifstream in_;
  std::string file_;
  int line_ = 0;
};

std::vector<std::string> SplitWhitespace(const std::string& line);

}  // namespace sapmvs
