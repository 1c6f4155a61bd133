// CLI11's parse errors as the one line every other error of the tool is:
// "sapmvs: " and what was wrong, naming the flag or value, in the words of
// the rest of the tool, and where to look (the subcommand's --help).
#include <CLI/CLI.hpp>

#include <cctype>
#include <regex>
#include <string>
#include <vector>

#include "cli/cli.h"

namespace sapmvs::cli {
namespace {

std::string OneLine(std::string s) {
  for (char& c : s) {
    if (c == '\n' || c == '\r') c = ' ';
  }
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

// What a CLI11 type name asks for, in words.
std::string Expected(const std::string& type) {
  if (type == "INT") return "an integer";
  if (type == "UINT") return "a non-negative integer";
  if (type == "FLOAT") return "a number";
  if (type == "[INT]") return "integers separated by commas";
  if (type == "[FLOAT]") return "numbers separated by commas";
  if (type == "TEXT") return "a value";
  return "a value (" + type + ")";
}

const CLI::Option* FindOption(const CLI::App& app, const CLI::App* sub, const std::string& name) {
  if (sub) {
    if (const CLI::Option* o = sub->get_option_no_throw(name)) return o;
  }
  return app.get_option_no_throw(name);
}

std::string SubcommandNames(const CLI::App& app) {
  std::string names;
  for (const CLI::App* s : app.get_subcommands({})) {
    names += (names.empty() ? "" : ", ") + s->get_name();
  }
  return names;
}

}  // namespace

std::string DescribeParseError(const CLI::App& app, const CLI::ParseError& error) {
  const std::vector<CLI::App*> parsed = app.get_subcommands();
  const CLI::App* sub = parsed.empty() ? nullptr : parsed.front();
  // "info: ..." as the subcommands' own errors begin ("run: expected ...").
  const std::string where = sub ? sub->get_name() + ": " : std::string();
  const std::string help =
      " (see sapmvs" + (sub ? " " + sub->get_name() : std::string()) + " --help)";
  const std::string what = OneLine(error.what());
  std::smatch m;

  // CLI11 gives some errors the app's name instead of the error's, so the
  // type is told by cast, not by get_name().
  if (dynamic_cast<const CLI::ConversionError*>(&error) &&
      std::regex_match(what, m, std::regex(R"(Could not convert: (\S+) = (.*))"))) {
    const std::string name = m[1];
    const CLI::Option* option = FindOption(app, sub, name);
    const std::string type = option ? option->get_type_name() : "";
    return name + ": expected " + (type.empty() ? std::string("a valid value") : Expected(type)) +
           ", got '" + std::string(m[2]) + "'" + help;
  }
  if (dynamic_cast<const CLI::ExtrasError*>(&error) &&
      std::regex_match(what, m, std::regex(R"(.*not expected: (.*))"))) {
    const std::string extras = m[1];
    const bool option = !extras.empty() && extras[0] == '-';
    return where + (option ? "unknown option '" : "unexpected argument '") + extras + "'" + help;
  }
  if (dynamic_cast<const CLI::RequiredError*>(&error)) {
    if (!sub) {
      // A word that is no subcommand is left over, not an error of its own.
      const std::vector<std::string> left = app.remaining();
      if (!left.empty() && !left.front().empty() && left.front()[0] != '-') {
        return "unknown subcommand '" + left.front() + "', expected one of " +
               SubcommandNames(app) + help;
      }
      return "expected a subcommand, one of " + SubcommandNames(app) + help;
    }
    if (std::regex_match(what, m, std::regex(R"((\S+) is required)"))) {
      const CLI::Option* option = FindOption(app, sub, m[1]);
      if (option && option->get_positional() && option->get_name()[0] != '-') {
        std::string name = m[1];
        for (char& c : name) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
        return where + "missing argument " + name + help;
      }
      return where + "missing option " + std::string(m[1]) + help;
    }
    return where + what + help;
  }
  if (dynamic_cast<const CLI::ArgumentMismatch*>(&error) &&
      std::regex_match(what, m, std::regex(R"((\S+): \d+ required (\S+) missing)"))) {
    return std::string(m[1]) + ": expected " + Expected(m[2]) + " after it" + help;
  }
  return where + what + help;
}

}  // namespace sapmvs::cli
