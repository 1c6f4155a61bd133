#pragma once
// docs/options.md: every described option (option_spec.h) of every command
// that takes it, generated from the descriptions themselves by
// `sapmvs options-reference`; options_reference_test fails when the file in
// the repository is not what this returns.
#include <string>

namespace sapmvs {

std::string OptionsReference();

}  // namespace sapmvs
