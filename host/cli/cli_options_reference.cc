// `sapmvs options-reference`: prints docs/options.md (options_reference.h).
// Hidden from --help: it is for keeping the docs current, not for users.
#include <CLI/CLI.hpp>

#include <iostream>

#include "cli/cli.h"
#include "run/options_reference.h"

namespace sapmvs::cli {

void RegisterOptionsReferenceCommand(CLI::App& app, const GlobalFlags& /*global*/) {
  CLI::App* cmd = app.add_subcommand(
      "options-reference", "Print docs/options.md, the reference of every command's options");
  cmd->group("");
  cmd->callback([] { std::cout << OptionsReference(); });
}

}  // namespace sapmvs::cli
