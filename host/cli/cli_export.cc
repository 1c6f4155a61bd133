// `sapmvs export BLOCK --out DIR --format pmvs|colmap`: a block for other
// dense matchers. Flags map one to one onto ExportOptions; the block is read
// with the flags of `info`, its format flag named --input-format here.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <iostream>
#include <memory>

#include "cli/cli.h"
#include "sapmvs/block/block_export.h"
#include "sapmvs/util/error.h"

namespace sapmvs::cli {
namespace {

struct ExportArgs {
  std::string block;
  std::string format;
  int level = 0;
  BlockFlags flags;
  ExportOptions options;
};

void PrintSummary(const ExportSummary& s, std::ostream& out) {
  char origin[128];
  std::snprintf(origin, sizeof(origin), "X %.3f  Y %.3f  Z %.3f", s.origin.x(), s.origin.y(),
                s.origin.z());
  out << "exported      " << s.images << " images, " << s.cameras << " camera(s)";
  if (s.format == ExportFormat::kColmap) out << ", " << s.points << " sparse points";
  out << "\n";
  out << "to            " << s.out.string() << " (" << ToString(s.format) << ", level " << s.level
      << ")\n";
  out << "local origin  " << origin << " (subtracted; see sapmvs_frame.json)\n";
  if (s.format == ExportFormat::kPmvs) {
    out << "run           pmvs2 " << (s.out / "").string() << " option\n";
  }
}

}  // namespace

void RegisterExportCommand(CLI::App& app, const GlobalFlags& global) {
  auto args = std::make_shared<ExportArgs>();
  CLI::App* cmd = app.add_subcommand(
      "export", "Write a block for PMVS2/CMVS or COLMAP: undistorted images, local frame");
  cmd->add_option("block", args->block,
                  "Block: block.yaml, or a PMVS / COLMAP / Strecha / OpenSfM folder")
      ->required();
  cmd->add_option("--out", args->options.out, "Output folder (new, empty, or an earlier export)")
      ->required();
  cmd->add_option("--format", args->format, "What to write: pmvs or colmap")->required();
  CLI::Option* level = cmd->add_option(
      "--level", args->level,
      "pmvs: PMVS2's level (default 1); colmap: images scaled by 2^-level (default 0)");
  AddBlockFlags(cmd, &args->flags, "--input-format");
  cmd->callback([args, level, &global] {
    ExportOptions& o = args->options;
    o.format = ParseExportFormat(args->format);
    if (level->count() > 0) o.level = args->level;
    o.progress = !global.quiet;
    if (const std::string p = o.Problem(); !p.empty()) throw Error("export: expected " + p);
    // Refuse a foreign folder before reading the block, which may be large.
    CheckExportTarget(o.out);
    const Block block = ReadBlockWithFlags(args->block, args->flags);
    PrintSummary(ExportBlock(block, o), std::cout);
  });
}

}  // namespace sapmvs::cli
