// `sapmvs report RUN`: makes RUN/report.html again from the run folder's
// files, e.g. after the DSM picture or the evaluation beside it changed.
#include <CLI/CLI.hpp>

#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

#include "cli/cli.h"
#include "sapmvs/report/report_html.h"

namespace sapmvs::cli {

void RegisterReportCommand(CLI::App& app, const GlobalFlags& /*global*/) {
  auto run = std::make_shared<std::string>();
  CLI::App* cmd = app.add_subcommand(
      "report", "Make a run folder's report.html again from its report.json and pictures");
  cmd->add_option("run", *run, "A folder `sapmvs run` wrote (it holds report.json)")->required();
  cmd->callback([run] {
    const std::filesystem::path html = WriteReportHtml(*run);
    std::cout << "wrote         " << html.string() << "\n";
  });
}

}  // namespace sapmvs::cli
