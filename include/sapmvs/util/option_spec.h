#pragma once
// One description per options struct. Each XxxOptions header declares
//   template <class F> void VisitFields(XxxOptions& o, F&& f);
// which calls f(OptionField<T>) once per field, in the order of `run --help`:
// the field, its name (the checkpoint's JSON key, and the name range errors
// use), its flag, unit, range and help. From that one list come the range
// checks (RangeProblem below), the CLI flags of every command that takes the
// struct (option_flags.h), the checkpoint JSON (option_json.h) and
// docs/options.md (`sapmvs options-reference`), so none of them can drift
// from the others. Conditions between fields (threshold_before <= threshold)
// stay hand-written in the struct's Problem(), after the ranges, in the same
// "what was expected (name = value)" form.
//
// A run resumes from its checkpoint only when the options it records equal
// the new ones (run_checkpoint.h). A field added after version 1 of the
// checkpoints says, with AsVersion1, the value at which it matches as
// version 1 did; there it is not recorded, so version-1 runs still resume.
// A field without effect at the others' values (a setting of a stage that
// another field turns off) says so with UnusedWhen, and is not recorded
// either: its value cannot change what is matched.
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <vector>

namespace sapmvs {

// The values a number (or each number of a list) may take. NaN and, for
// doubles, infinities are outside every range.
struct OptionRange {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false, max_open = false;
  bool odd = false;

  bool Contains(double v, bool integer) const {
    if (!integer && !std::isfinite(v)) return false;
    if (min_open ? !(v > min) : !(v >= min)) return false;
    if (max_open ? !(v < max) : !(v <= max)) return false;
    return !odd || std::fmod(v, 2.0) != 0;
  }
  // "in 0..6", "odd in 3..21", "in (-1, 1]", ">= 1", "> 0"; "" for any.
  std::string Text(bool integer) const {
    std::ostringstream s;
    const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
    if (odd) s << "odd ";
    if (has_min && has_max) {
      if (integer && !min_open && !max_open)
        s << "in " << min << ".." << max;
      else
        s << "in " << (min_open ? "(" : "[") << min << ", " << max << (max_open ? ")" : "]");
    } else if (has_min) {
      s << (min_open ? "> " : ">= ") << min;
    } else if (has_max) {
      s << (max_open ? "< " : "<= ") << max;
    }
    return s.str();
  }
};
inline OptionRange AnyValue() { return {}; }
inline OptionRange Between(double lo, double hi) { return {lo, hi}; }
inline OptionRange AtLeast(double lo) { return {lo}; }
inline OptionRange Above(double lo) { return {lo, std::numeric_limits<double>::infinity(), true}; }
inline OptionRange OddBetween(double lo, double hi) { return {lo, hi, false, false, true}; }
// An interval with either end open: Interval(-1, 1, true, false) is (-1, 1].
inline OptionRange Interval(double lo, double hi, bool lo_open, bool hi_open) {
  return {lo, hi, lo_open, hi_open};
}

// How a field's flag is written on the command line.
enum class FlagStyle {
  kValue,     // --flag VALUE (a bool: --flag alone sets it)
  kList,      // comma-separated list
  kByteSize,  // 8G, 512M, ... (ParseByteSize)
};

template <class T>
struct OptionField {
  T* value;
  const char* name;
  const char* flag = "";  // "" = no flag
  const char* unit = "";
  const char* help = "";
  const char* section = "";  // the help section of `run`
  // A condition the range cannot say (checked in Problem()), for the docs.
  const char* rule = "";
  OptionRange range;
  FlagStyle style = FlagStyle::kValue;
  // The value that matches as version 1 of the checkpoints (before the field
  // existed) did; none for the fields version 1 had.
  std::optional<std::remove_const_t<T>> as_version1;
  // No effect at the values of the struct VisitFields was given.
  bool unused = false;

  OptionField& Flag(const char* f) { return flag = f, *this; }
  OptionField& Unit(const char* u) { return unit = u, *this; }
  OptionField& Help(const char* h) { return help = h, *this; }
  OptionField& In(const char* s) { return section = s, *this; }
  OptionField& Rule(const char* r) { return rule = r, *this; }
  OptionField& Range(OptionRange r) { return range = r, *this; }
  OptionField& Style(FlagStyle s) { return style = s, *this; }
  OptionField& AsVersion1(const std::remove_const_t<T>& v) { return as_version1 = v, *this; }
  OptionField& UnusedWhen(bool u) { return unused = u, *this; }
};
template <class T>
OptionField<T> Field(T& value, const char* name) {
  OptionField<T> f;
  f.value = &value;
  f.name = name;
  return f;
}

// A value as flags, messages and docs write it. Enums need
// `std::string ToString(E)` beside them.
inline std::string OptionText(const std::string& v) { return v; }
inline std::string OptionText(bool v) { return v ? "true" : "false"; }
inline std::string OptionText(int v) { return std::to_string(v); }
inline std::string OptionText(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}
inline std::string OptionText(const std::vector<int>& v) {
  std::string s;
  for (size_t i = 0; i < v.size(); ++i) s += (i ? "," : "") + std::to_string(v[i]);
  return s;
}
template <class E, class = std::enable_if_t<std::is_enum_v<E>>>
std::string OptionText(E v) {
  return ToString(v);
}

// A byte count as --memory-budget takes it: "8G", "512M", or plain bytes.
inline std::string ByteSizeText(double bytes) {
  const char* units = "KMGT";
  std::string text = OptionText(bytes);
  for (int i = 0; i < 4; ++i) {
    const double unit = std::ldexp(1.0, 10 * (i + 1));
    if (bytes >= unit && std::fmod(bytes, unit) == 0) text = OptionText(bytes / unit) + units[i];
  }
  return text;
}

// The field's value as its flag would take it.
template <class T>
std::string ValueText(const OptionField<T>& f) {
  if constexpr (std::is_same_v<std::remove_const_t<T>, double>) {
    if (f.style == FlagStyle::kByteSize) return ByteSizeText(*f.value);
  }
  return OptionText(*f.value);
}

// The field's value outside its range, as "name RANGE (name = value)"; ""
// when it is inside (or the field has no range).
template <class T>
std::string RangeProblem(const OptionField<T>& f) {
  using V = std::remove_const_t<T>;
  if constexpr (std::is_same_v<V, int> || std::is_same_v<V, double>) {
    if (f.range.Contains(*f.value, std::is_same_v<V, int>)) return "";
    return std::string(f.name) + " " + f.range.Text(std::is_same_v<V, int>) + " (" + f.name +
           " = " + OptionText(*f.value) + ")";
  } else if constexpr (std::is_same_v<V, std::vector<int>>) {
    for (const int v : *f.value) {
      if (!f.range.Contains(v, true))
        return std::string(f.name) + " each " + f.range.Text(true) + " (" + f.name + " = " +
               OptionText(*f.value) + ")";
    }
  }
  return "";
}

// The first field of `options` outside its range, or "".
template <class Options>
std::string FirstRangeProblem(const Options& options) {
  Options copy = options;  // VisitFields takes the struct it may bind flags to
  std::string problem;
  VisitFields(copy, [&](const auto& field) {
    if (problem.empty()) problem = RangeProblem(field);
  });
  return problem;
}

}  // namespace sapmvs
