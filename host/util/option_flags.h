#pragma once
// CLI11 flags from an options struct's description (option_spec.h): one flag
// per described field, with its help, section and default, writing straight
// into the struct. Every command that takes the struct (run, plan, the
// profiling tools) adds its flags this way, so they cannot drift apart.
// Values are range-checked later, by the struct's Problem(), in one place.
#include <CLI/CLI.hpp>

#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "sapmvs/util/byte_size.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/option_spec.h"

namespace sapmvs::cli {

// Which fields of a struct get flags: all described ones, only those named in
// `only` (when not empty), never those named in `skip`.
struct FieldFilter {
  std::set<std::string> only;
  std::set<std::string> skip;
  bool Takes(const std::string& name) const {
    return (only.empty() || only.count(name) > 0) && skip.count(name) == 0;
  }
};

// The matcher's fields `plan` takes: those a plan depends on (the memory
// estimate's level, cells and wave; the views a patch needs).
inline FieldFilter PlanMatcherFields() {
  return {{"level", "min_image_num", "cell_size", "max_wave"}, {}};
}
// The profiling tool compare_modes runs both modes itself (--only).
inline FieldFilter CompareModesMatcherFields() { return {{}, {"mode"}}; }

template <class T>
CLI::Option* AddOptionFlag(CLI::App* cmd, const OptionField<T>& f) {
  T* v = f.value;
  const std::string flag = f.flag;
  CLI::Option* opt = nullptr;
  if constexpr (std::is_same_v<T, bool>) {
    opt = cmd->add_flag(flag, *v, f.help);
  } else if constexpr (std::is_enum_v<T>) {
    // The enum's own parser names the bad value and the expected ones.
    opt = cmd->add_option_function<std::string>(
                 flag, [v](const std::string& s) { ParseOptionValue(s, v); }, f.help)
              ->default_str(ValueText(f));
  } else if constexpr (std::is_same_v<T, double>) {
    if (f.style == FlagStyle::kByteSize) {
      opt = cmd->add_option_function<std::string>(
                   flag,
                   [v, flag](const std::string& s) {
                     try {
                       *v = ParseByteSize(s);
                     } catch (const Error& e) {
                       throw Error(flag + ": " + e.what());
                     }
                   },
                   f.help)
                ->default_str(ValueText(f));
    } else {
      opt = cmd->add_option(flag, *v, f.help)->capture_default_str();
    }
  } else if constexpr (std::is_same_v<T, std::vector<int>>) {
    opt = cmd->add_option(flag, *v, f.help)->delimiter(',')->capture_default_str();
  } else {
    opt = cmd->add_option(flag, *v, f.help);
    if constexpr (!std::is_same_v<T, std::string>) opt->capture_default_str();
  }
  return opt->group(f.section);
}

// Adds the flags of the fields `filter` takes, in the description's order.
// `options` must outlive the parse.
template <class Options>
void AddOptionFlags(CLI::App* cmd, Options* options, const FieldFilter& filter = {}) {
  VisitFields(*options, [&](const auto& field) {
    if (*field.flag && filter.Takes(field.name)) AddOptionFlag(cmd, field);
  });
}

}  // namespace sapmvs::cli
