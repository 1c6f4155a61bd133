#pragma once
// An options struct as JSON, from its description (option_spec.h): one key
// per described field, named as the field, enums by name. What a checkpoint
// records of the options it was matched with: a field at its AsVersion1
// value, or UnusedWhen its stage is off, is left out (option_spec.h).
#include <nlohmann/json.hpp>
#include <type_traits>

#include "sapmvs/util/option_spec.h"

namespace sapmvs {

template <class Options>
nlohmann::json OptionsJson(const Options& options) {
  Options copy = options;  // VisitFields takes the struct it may bind flags to
  nlohmann::json j = nlohmann::json::object();
  VisitFields(copy, [&](const auto& field) {
    using T = std::remove_pointer_t<decltype(field.value)>;
    if (field.unused || (field.as_version1 && *field.value == *field.as_version1)) return;
    if constexpr (std::is_enum_v<T>)
      j[field.name] = OptionText(*field.value);
    else
      j[field.name] = *field.value;
  });
  return j;
}

}  // namespace sapmvs
