#include "sapmvs/block/export_frame.h"

#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"

namespace sapmvs {
namespace fs = std::filesystem;

void WriteExportFrame(const fs::path& dir, const ExportFrame& frame) {
  nlohmann::json j = {
      {"format", frame.format},
      {"level", frame.level},
      {"origin", {frame.origin.x(), frame.origin.y(), frame.origin.z()}},
      {"crs", frame.crs},
      {"source", frame.source},
      {"sapmvs_version", frame.sapmvs_version},
      {"images", frame.images},
  };
  if (frame.ground_height) j["ground_height"] = *frame.ground_height;
  if (!frame.dem.empty()) j["dem"] = frame.dem;
  // nlohmann writes doubles with round-trip precision: the origin comes back
  // bit for bit.
  WriteTextAtomically(dir / kExportFrameFile, j.dump(2) + "\n");
}

std::optional<ExportFrame> ReadExportFrame(const fs::path& dir) {
  const fs::path path = dir / kExportFrameFile;
  if (!fs::is_regular_file(path)) {
    if (fs::is_regular_file(dir / kExportMarkerFile)) {
      throw Error(dir.string() + ": unfinished sapmvs export (no " + kExportFrameFile +
                  "); export it again");
    }
    return std::nullopt;
  }
  const std::string file = path.string();
  std::ifstream in(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, 0, std::string("expected JSON (") + e.what() + ")");
  }
  ExportFrame f;
  try {
    f.format = j.at("format").get<std::string>();
    f.level = j.at("level").get<int>();
    const auto& o = j.at("origin");
    if (!o.is_array() || o.size() != 3) throw InputError(file, 0, "expected origin: [x, y, z]");
    f.origin = {o[0].get<double>(), o[1].get<double>(), o[2].get<double>()};
    f.crs = j.value("crs", "");
    f.source = j.value("source", "");
    f.sapmvs_version = j.value("sapmvs_version", "");
    f.images = j.value("images", std::vector<std::string>{});
    if (j.contains("ground_height")) f.ground_height = j.at("ground_height").get<double>();
    f.dem = j.value("dem", "");
  } catch (const nlohmann::json::exception& e) {
    throw InputError(file, 0, std::string("expected a sapmvs export side file (") + e.what() + ")");
  }
  if (!f.origin.allFinite()) throw InputError(file, 0, "expected a finite origin");
  return f;
}

void ApplyExportFrame(const ExportFrame& frame, const fs::path& frame_dir,
                      const std::string& format, Block* block) {
  if (frame.format != format) {
    throw InputError(
        (frame_dir / kExportFrameFile).string(), 0,
        "written for a " + frame.format + " export, but the folder was read as " + format);
  }
  for (BlockImage& im : block->images) im.camera = im.camera.Translated(-frame.origin);
  for (Eigen::Vector3d& p : block->sparse_points) p += frame.origin;
  block->crs = frame.crs;
  block->frame_note = "local frame of a sapmvs export, moved back by its origin";
  if (frame.ground_height) block->ground_height = frame.ground_height;
  // The DEM is in the world frame, which the block is back in.
  if (!frame.dem.empty() && fs::is_regular_file(frame.dem)) block->dem = frame.dem;
  // PMVS numbers the images and COLMAP's names carry an extension; a model
  // edited since (images dropped) keeps the names it has.
  if (frame.images.size() == block->images.size()) {
    for (size_t i = 0; i < frame.images.size(); ++i) block->images[i].name = frame.images[i];
  }
}

std::vector<fs::path> ReadExportMarker(const fs::path& dir) {
  std::vector<fs::path> files;
  std::ifstream in(dir / kExportMarkerFile);
  std::string line;
  while (std::getline(in, line)) {
    const fs::path p = fs::path(line).lexically_normal();
    // The list decides what a re-export deletes: nothing outside `dir`.
    if (line.empty() || p.is_absolute() || p.empty() || *p.begin() == "..") continue;
    files.push_back(p);
  }
  return files;
}

void WriteExportMarker(const fs::path& dir, const std::vector<fs::path>& files) {
  std::ostringstream s;
  for (const fs::path& f : files) s << f.generic_string() << "\n";
  WriteTextAtomically(dir / kExportMarkerFile, s.str());
}

}  // namespace sapmvs
