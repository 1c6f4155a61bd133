#include "util/text_lines.h"

#include <cmath>
#include <sstream>

#include "util/input_file.h"

namespace sapmvs {

std::vector<std::string> SplitWhitespace(const std::string& line) {
  std::vector<std::string> out;
  std::istringstream in(line);
  std::string token;
  while (in >> token) out.push_back(token);
  return out;
}

TextLines::TextLines(const std::filesystem::path& path)
    : in_(OpenInputFile(path)), file_(path.string()) {}

bool TextLines::NextRaw(std::string* line, bool skip_comments) {
  while (std::getline(in_, *line)) {
    ++line_;
    if (!line->empty() && line->back() == '\r') line->pop_back();
    const size_t first = line->find_first_not_of(" \t");
    if (skip_comments && first != std::string::npos && (*line)[first] == '#') continue;
    return true;
  }
  return false;
}

bool TextLines::Next(std::vector<std::string>* tokens) {
  std::string line;
  while (NextRaw(&line)) {
    *tokens = SplitWhitespace(line);
    if (!tokens->empty()) return true;
  }
  return false;
}

double TextLines::Double(const std::string& text, const std::string& what) const {
  size_t used = 0;
  double v = 0;
  try {
    v = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || used == 0) {
    throw Fail("expected a number for " + what + ", got '" + text + "'");
  }
  if (!std::isfinite(v))
    throw Fail("expected a finite number for " + what + ", got '" + text + "'");
  return v;
}

int TextLines::Int(const std::string& text, const std::string& what) const {
  size_t used = 0;
  long v = 0;
  try {
    v = std::stol(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || used == 0) {
    throw Fail("expected an integer for " + what + ", got '" + text + "'");
  }
  return static_cast<int>(v);
}

void TextLines::ExpectCount(const std::vector<std::string>& tokens, size_t n,
                            const std::string& layout, bool at_least) const {
  if (tokens.size() == n || (at_least && tokens.size() > n)) return;
  throw Fail("expected " + std::string(at_least ? "at least " : "") + std::to_string(n) +
             " fields (" + layout + "), got " + std::to_string(tokens.size()));
}

}  // namespace sapmvs
