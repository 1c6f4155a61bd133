// sapmvs against the real PMVS2 (Furukawa and Ponce's program, the paper's
// baseline) on the same images, side by side in one run: the block is
// exported once as a PMVS folder (`sapmvs export --format pmvs`), PMVS2 and
// `sapmvs run` in each mode match that folder, each as a child process timed
// through wait4(), and the clouds are compared with each other and, for
// simulated blocks, with the true surface.
//
//   versus_pmvs2 BLOCK [--out DIR] [--level 1] [--threads N] [--truth DSM]
//                [--modes sapmvs,pmvs] [--max-images N] [--markdown FILE]
//                [--pmvs2 PATH] [--sapmvs PATH] [--exported PMVS_DIR]
//                [--pmvs2-cloud PLY] [--run-flags "FLAGS"]
//                [--openmvs [--openmvs-bin DIR] | --openmvs-cloud PLY]
//
// --openmvs adds OpenMVS's DensifyPointCloud (CPU build) as a second anchor
// on a COLMAP undistorted folder: a denser, smoother surface than PMVS2's
// at several times its time; its row compares with PMVS2's like sapmvs's,
// and the second table gives its noise and ground. Its time is
// DensifyPointCloud's alone (InterfaceCOLMAP reads the folder first, as
// `sapmvs export` writes PMVS2's).
//
// --pmvs2-cloud compares with the cloud of an earlier PMVS2 run on the same
// folder (models/option.ply) instead of running PMVS2 again, to try sapmvs
// flags (--run-flags) against it; that row has no times. A claim of speed
// needs PMVS2 run in the same benchmark run.
//
// PMVS2 is not part of this repository. It is looked for under the build
// folder (build/anchors/, built by hand there), else $SAPMVS_PMVS2; without
// it the sapmvs rows still run.
//
// Frames: the export writes coordinates in the block's local frame and the
// offset to world in sapmvs_frame.json. PMVS2's cloud is in that local frame
// and is moved by the offset; sapmvs's PMVS reader applies the side file, so
// its cloud is in the world frame already.
// Same inputs: sapmvs matches the exported folder with its images and
// cameras only, as PMVS2 does; the surface prior an export records (the
// block's DEM or ground height) is taken out of sapmvs_frame.json, so sapmvs
// finds its depths from tie points, as PMVS2 from its own seeds.
//
// Memory: the peak RSS is wait4()'s, as `/usr/bin/time` gives it. Beside it,
// from the child's /proc/PID/status sampled every 10 ms (RunTimed), the two
// parts of the largest sample: files mapped (the libraries, PoCL's LLVM
// among them) and anonymous memory (what the program allocated and wrote).
//
// Distances: cloud-to-cloud coverage is counted within 1 and 2 GSD of the
// matched level (the median full-resolution GSD at the scene times
// 2^level), the spacing both matchers emit points at. Against the truth the
// numbers are compare_modes' and end_to_end's (truth_check.h).
#include <unistd.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <optional>
#include <sstream>
#include <thread>

#include "sapmvs/block/block_geometry.h"
#include "sapmvs/block/block_reader.h"
#include "sapmvs/block/export_frame.h"
#include "sapmvs/io/ply_io.h"
#include "sapmvs/run/cloud_merge.h"
#include "sapmvs/util/error.h"
#include "surface_table.h"
#include "timed_child.h"
#include "truth_check.h"
#include "util/build_info.h"
#include "util/machine_info.h"

using namespace sapmvs;
namespace fs = std::filesystem;

namespace {

// How far from one of the other cloud's points a point may be and still be
// compared with its tangent plane: twice PMVS2's sample spacing (2 pixels).
constexpr double kSurfaceReachGsd = 4.0;

struct Row {
  std::string name;  // "PMVS2" or "sapmvs --mode M"
  ChildUsage usage;
  bool timed = true;  // false: a cloud of an earlier run
  PointCloud cloud;   // world frame
  // Where the cloud is read from, once every tool has run, and the offset
  // that takes it to the world frame. Read between runs, a cloud raised the
  // next child's peak RSS: fork() copies the benchmark's resident pages and
  // exec() keeps their high-water mark in the child's ru_maxrss (OpenMVS's
  // 8.6 M points, held while sapmvs ran, made its peak read 443 MiB, 263
  // without them).
  fs::path cloud_file;
  Eigen::Vector3d cloud_offset = Eigen::Vector3d::Zero();
  std::optional<double> from_pmvs2[2], to_pmvs2[2];  // at 1 and 2 GSD
  // Within 2 GSD of the other cloud's surface: of a point of it within
  // kSurfaceReachGsd, along its normal. PMVS2 samples every second pixel, so
  // a denser cloud's points between its samples can lie more than 2 GSD from
  // each on the surface they sample; this tells those from points off it.
  std::optional<double> from_pmvs2_surface, to_pmvs2_surface;
  // With truth: of PMVS2's points within 1 GSD of the true surface, the share
  // with one of ours within 2 GSD. PMVS2's points that ours miss are often
  // its wrong ones; this says how many of its right ones ours miss.
  std::optional<double> right_from_pmvs2;
  // The same of PMVS2's points within 2 GSD (3D, walls included) of the true
  // surface: its points on walls, which the vertical test above counts as
  // wrong, are right here (8 % of its points on `small`, 12 % on `city`).
  std::optional<double> right3d_from_pmvs2;
  std::optional<SurfaceCheck> truth;
  // With truth: the share of the row's points within 2 GSD (3D, walls
  // included) of the true surface. On PMVS2's row it is the most of PMVS2's
  // points that any accurate cloud can have a point within 2 GSD of.
  std::optional<double> near_truth;
  // sapmvs: its output folder (report.json, groups/).
  fs::path run;
  // sapmvs: CPU / wall over its matching stages (report.json), without the
  // reading, planning, merging and writing around them.
  std::optional<double> matching_busy;
};

// CPU / wall over the matching stages of a sapmvs run's report.json: the
// stages with cpu_seconds, less the run's own ("run merge", ...; older
// binaries timed only the matching stages); none when the binary does not
// record CPU time.
std::optional<double> MatchingBusy(const fs::path& report) {
  std::ifstream f(report);
  const nlohmann::json j = nlohmann::json::parse(f, nullptr, false);
  if (j.is_discarded() || !j.contains("stages")) return std::nullopt;
  double wall = 0, cpu = 0;
  for (const nlohmann::json& s : j["stages"]) {
    if (!s.contains("cpu_seconds") || s.value("stage", "").rfind("run ", 0) == 0) continue;
    wall += s["wall_seconds"].get<double>();
    cpu += s["cpu_seconds"].get<double>();
  }
  if (!(wall > 0 && cpu > 0)) return std::nullopt;
  return cpu / wall;
}

// The folder of the build that holds this binary (build/profiling/x -> build).
fs::path BuildDir() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path() : self.parent_path().parent_path();
}

bool IsExecutable(const fs::path& p) {
  return fs::is_regular_file(p) && access(p.c_str(), X_OK) == 0;
}

// build/anchors/ is where the anchors are built by hand (never committed);
// any executable `name` below it will do.
fs::path FindAnchor(const fs::path& build, const std::string& name) {
  const fs::path anchors = build / "anchors";
  std::error_code ec;
  if (fs::is_directory(anchors)) {
    for (auto it = fs::recursive_directory_iterator(anchors, ec);
         !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
      if (it->path().filename() == name && IsExecutable(it->path())) return it->path();
    }
  }
  return {};
}

fs::path FindPmvs2(const fs::path& build) {
  if (fs::path found = FindAnchor(build, "pmvs2"); !found.empty()) return found;
  if (const char* env = std::getenv("SAPMVS_PMVS2"); env && IsExecutable(env)) return env;
  return {};
}

// DensifyPointCloud in `dir` when InterfaceCOLMAP is beside it, both
// executable; else empty.
fs::path OpenMvsIn(const fs::path& dir) {
  const fs::path densify = dir / "DensifyPointCloud";
  if (!IsExecutable(densify) || !IsExecutable(dir / "InterfaceCOLMAP")) return {};
  return densify;
}

// OpenMVS's programs as profiling/anchors/build_openmvs.sh leaves them, else
// in the folder $SAPMVS_OPENMVS.
fs::path FindOpenMvs(const fs::path& build) {
  if (fs::path found = FindAnchor(build, "DensifyPointCloud"); !found.empty()) {
    return OpenMvsIn(found.parent_path());
  }
  if (const char* env = std::getenv("SAPMVS_OPENMVS")) return OpenMvsIn(env);
  return {};
}

// The cloud `program` should have written, or an error naming its log.
fs::path WrittenCloud(const fs::path& cloud, const fs::path& program, const fs::path& log) {
  if (!fs::is_regular_file(cloud)) {
    throw Error(program.string() + " wrote no " + cloud.string() + "; see " + log.string());
  }
  return cloud;
}

// OpenMVS reads COLMAP's undistorted folder (images/, sparse/) and needs its
// points' tracks to choose each image's neighbours, which an export of
// sapmvs does not write: only such a folder is given to it.
bool IsColmapUndistorted(const fs::path& block) {
  std::error_code ec;
  return fs::is_directory(block / "images", ec) && fs::is_directory(block / "sparse", ec);
}

std::vector<fs::path> CameraFiles(const fs::path& pmvs) {
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(pmvs / "txt")) {
    if (e.path().extension() == ".txt") files.push_back(e.path());
  }
  std::sort(files.begin(), files.end());
  return files;
}

Eigen::Matrix<double, 3, 4> ReadPmvsMatrix(const fs::path& file) {
  std::ifstream in(file);
  std::string contour;
  Eigen::Matrix<double, 3, 4> p;
  in >> contour;
  for (int i = 0; i < 12; ++i) in >> p(i / 4, i % 4);
  if (!in || contour != "CONTOUR") throw InputError(file.string(), 1, "expected CONTOUR and P");
  return p;
}

// PMVS2 builds each pyramid level from the one below with a 1-3-3-1 filter
// sampled at even pixels (Cimage::buildImage), so pixel x of level L shows
// level 0 at 2^L x + (2^L - 1) / 2, yet it only halves P per level
// (Ccamera::updateProjection): every image is read (2^L - 1) / 2 pixels off,
// which biases its heights at L > 0 (+1.2 GSD on the tiny preset at level 1).
// This writes `dir`, a copy of the folder for PMVS2 whose matrices are
// shifted by that much (images linked, not copied).
void WritePyramidShiftedFolder(const fs::path& pmvs, int level, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir / "txt");
  fs::create_directories(dir / "models");
  fs::create_directory_symlink(fs::absolute(pmvs / "visualize"), dir / "visualize");
  fs::copy_file(pmvs / "option", dir / "option");
  const double shift = 0.5 * (std::ldexp(1.0, level) - 1);
  for (const fs::path& file : CameraFiles(pmvs)) {
    Eigen::Matrix<double, 3, 4> p = ReadPmvsMatrix(file);
    p.row(0) -= shift * p.row(2);
    p.row(1) -= shift * p.row(2);
    std::ofstream out(dir / "txt" / file.filename());
    out << "CONTOUR\n" << std::setprecision(17) << p << "\n";
    if (!out) throw Error((dir / "txt" / file.filename()).string() + ": write failed");
  }
}

// A folder for a second PMVS2 run on the same input: everything PMVS2 reads
// (images, matrices, a vis.dat where there is one) linked, the option file
// copied, and models/ its own.
void WriteRepeatFolder(const fs::path& input, const fs::path& dir) {
  fs::remove_all(dir);
  fs::create_directories(dir / "models");
  for (const fs::directory_entry& e : fs::directory_iterator(input)) {
    const fs::path name = e.path().filename();
    if (name == "models") continue;
    if (name == "option") {
      fs::copy_file(e.path(), dir / name);
    } else {
      fs::create_symlink(fs::absolute(e.path()), dir / name);
    }
  }
}

// Takes the surface prior out of an exported folder's side file (see the
// top of this file).
// Returns the folder's offset to world (zero for a folder without a side
// file, already in world coordinates).
Eigen::Vector3d StripSurfacePrior(const fs::path& pmvs) {
  std::optional<ExportFrame> frame = ReadExportFrame(pmvs);
  if (!frame) return Eigen::Vector3d::Zero();
  frame->ground_height.reset();
  frame->dem.clear();
  WriteExportFrame(pmvs, *frame);
  return frame->origin;
}

// PMVS2 takes level and CPU from its option file: both are set to the run's,
// so that the two tools match the same pyramid level with the same threads.
void SetPmvsOptions(const fs::path& file, int level, int threads) {
  std::ifstream in(file);
  if (!in) throw Error(file.string() + ": no PMVS2 option file");
  std::ostringstream out;
  std::string line;
  while (std::getline(in, line)) {
    std::istringstream s(line);
    std::string key;
    s >> key;
    if (key == "level") line = "level " + std::to_string(level);
    if (key == "CPU") line = "CPU " + std::to_string(threads);
    out << line << "\n";
  }
  in.close();
  std::ofstream(file) << out.str();
}

void Translate(PointCloud* cloud, const Eigen::Vector3d& by) {
  for (CloudPoint& p : cloud->points) p.position += by;
}

// Runs one step; a failing child ends the benchmark, naming its log.
ChildUsage Step(const ChildCommand& c, std::vector<std::string>* commands) {
  std::cerr << "+ " << c.ShellLine() << "\n";
  const ChildUsage u = RunTimed(c);
  std::ostringstream line;
  line << c.ShellLine() << "   # " << std::fixed << std::setprecision(1) << u.wall_seconds << " s";
  commands->push_back(line.str());
  if (!u.Ok()) {
    throw Error(c.argv[0] + " failed (" + u.Describe() + "); see " + c.log.string());
  }
  return u;
}

std::string Fixed(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}
// A sampled memory figure, "–" where none was sampled (< 0).
std::string MiB(double v) { return v >= 0 ? Fixed(v, 0) : "–"; }
std::string Share(const std::optional<double>& v) { return v ? Fixed(100 * *v, 1) + " %" : "–"; }

std::string Table(const std::vector<Row>& rows, bool with_truth) {
  std::ostringstream t;
  t << "| tool / mode | wall s | CPU s | CPU/wall | matching CPU/wall | host steal | peak RSS MiB "
       "| of it files MiB | of it anonymous MiB | points "
       "| PMVS2→ours 1 GSD | PMVS2→ours 2 GSD | ours→PMVS2 1 GSD | ours→PMVS2 2 GSD | PMVS2→our "
       "surface 2 GSD | ours→PMVS2's surface 2 GSD |";
  if (with_truth) {
    t << " PMVS2's right points→ours 2 GSD | PMVS2's right points (3D)→ours 2 GSD | within 1 GSD | "
         "median \\|dz\\| | coverage | within 2 "
         "GSD (3D) |";
  }
  t << "\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    << (with_truth ? "---|---|---|---|---|---|" : "") << "\n";
  for (const Row& r : rows) {
    const ChildUsage& u = r.usage;
    if (r.timed) {
      t << "| " << r.name << " | " << Fixed(u.wall_seconds, 1) << " | " << Fixed(u.cpu_seconds, 1)
        << " | " << Fixed(u.cpu_seconds / std::max(u.wall_seconds, 1e-9), 2) << " | "
        << (r.matching_busy ? Fixed(*r.matching_busy, 2) : "–") << " | "
        << (u.host_steal >= 0 ? Fixed(100 * u.host_steal, 0) + " %" : "–") << " | "
        << Fixed(u.peak_rss_mib, 0) << " | " << MiB(u.files_at_peak_mib) << " | "
        << MiB(u.anonymous_at_peak_mib) << " | ";
    } else {
      t << "| " << r.name << " | – | – | – | – | – | – | – | – | ";
    }
    t << r.cloud.points.size() << " | " << Share(r.from_pmvs2[0]) << " | " << Share(r.from_pmvs2[1])
      << " | " << Share(r.to_pmvs2[0]) << " | " << Share(r.to_pmvs2[1]) << " | "
      << Share(r.from_pmvs2_surface) << " | " << Share(r.to_pmvs2_surface) << " |";
    if (with_truth) {
      t << " " << Share(r.right_from_pmvs2) << " | " << Share(r.right3d_from_pmvs2) << " |";
      if (r.truth) {
        t << " " << Fixed(100 * r.truth->share_within, 1) << " % | "
          << Fixed(r.truth->median_abs_dz, 3) << " | " << Fixed(100 * r.truth->coverage, 1)
          << " % |";
      } else {
        t << " – | – | – |";
      }
      t << " " << Share(r.near_truth) << " |";
    }
    t << "\n";
  }
  return t.str();
}

// Whether `sapmvs run --help` lists `flag`: binaries of earlier commits,
// compared in the same run, may not have it.
bool TakesFlag(const fs::path& sapmvs, const std::string& flag) {
  const std::string command = "'" + sapmvs.string() + "' run --help 2>/dev/null";
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return false;
  std::string text;
  char buffer[4096];
  for (size_t n; (n = fread(buffer, 1, sizeof buffer, pipe)) > 0;) text.append(buffer, n);
  pclose(pipe);
  return text.find(flag) != std::string::npos;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("sapmvs against PMVS2 on the same exported images, in one run");
  std::string block_path, out_dir = "/tmp/versus_pmvs2", truth_path, markdown_path;
  std::string pmvs2_path, sapmvs_path, exported_dir, pmvs2_cloud, run_flags;
  int level = 1, max_images = 0;
  int threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::vector<std::string> modes = {"sapmvs", "pmvs"};
  app.add_option("block", block_path, "Block file or folder (any format sapmvs reads)")->required();
  app.add_option("--out", out_dir, "Work folder: pmvs/, run_<mode>/, logs/")->capture_default_str();
  app.add_option("--level", level, "Pyramid level for both tools")->capture_default_str();
  app.add_option("--threads", threads, "Threads for both: PMVS2's CPU, PoCL's POCL_CPU_MAX_CU_NUM")
      ->capture_default_str();
  app.add_option("--truth", truth_path, "True surface raster (a simulated block's truth/dsm.tif)");
  app.add_option("--modes", modes, "sapmvs run modes")->delimiter(',')->capture_default_str();
  app.add_option("--max-images", max_images,
                 "sapmvs run --max-images (default: all images, one group, as PMVS2)");
  app.add_option("--markdown", markdown_path, "Append the table and commands to this file");
  app.add_option("--pmvs2", pmvs2_path,
                 "PMVS2 binary (default: build/anchors/**/pmvs2, else $SAPMVS_PMVS2)");
  app.add_option("--sapmvs", sapmvs_path, "sapmvs binary (default: build/sapmvs)");
  app.add_option("--exported", exported_dir,
                 "Use this PMVS folder of BLOCK instead of exporting one (its option "
                 "file gets --level and --threads; PMVS2 writes its models/)");
  app.add_option("--pmvs2-cloud", pmvs2_cloud,
                 "Compare with this cloud of an earlier PMVS2 run on the same folder "
                 "(models/option.ply) instead of running PMVS2; its row has no times")
      ->check(CLI::ExistingFile);
  app.add_option("--run-flags", run_flags,
                 "More flags for each `sapmvs run`, in one argument (\"--refill-cut --no-edges\")");
  bool again = false;
  app.add_flag("--pmvs2-again", again,
               "Run PMVS2 a second time (OUT/pmvs2_again) and compare its cloud with the first's "
               "as a row of its own: how far PMVS2 agrees with itself");
  bool shift_pyramid = false;
  app.add_flag("--shift-pmvs2-pyramid", shift_pyramid,
               "Give PMVS2 matrices shifted by (2^level - 1)/2 px, undoing its pyramid's offset "
               "(OUT/pmvs2_shifted)");
  bool openmvs_run = false;
  app.add_flag("--openmvs", openmvs_run,
               "Also run OpenMVS's DensifyPointCloud at --level and --threads (built by "
               "profiling/anchors/build_openmvs.sh, else in the folder $SAPMVS_OPENMVS) on BLOCK, "
               "which must be COLMAP's undistorted folder: a second anchor row");
  std::string openmvs_bin;
  app.add_option("--openmvs-bin", openmvs_bin,
                 "Folder holding DensifyPointCloud and InterfaceCOLMAP for --openmvs (default: "
                 "build/anchors/**, else $SAPMVS_OPENMVS)");
  std::string openmvs_cloud;
  app.add_option("--openmvs-cloud", openmvs_cloud,
                 "Compare with this cloud of an earlier DensifyPointCloud run on BLOCK "
                 "(scene_dense.ply) instead of running it; its row has no times")
      ->check(CLI::ExistingFile);
  CLI11_PARSE(app, argc, argv);
  try {
    if (level < 0 || threads < 1 || max_images < 0) {
      throw Error("expected --level >= 0, --threads >= 1, --max-images >= 0");
    }
    if (again && !pmvs2_cloud.empty()) {
      throw Error("expected --pmvs2-again without --pmvs2-cloud (it runs PMVS2 twice itself)");
    }
    if (openmvs_run && !openmvs_cloud.empty()) {
      throw Error("expected --openmvs or --openmvs-cloud, not both");
    }
    if (openmvs_run && !IsColmapUndistorted(block_path)) {
      throw Error(block_path +
                  ": expected COLMAP's undistorted folder (images/, sparse/) for --openmvs");
    }
    const fs::path build = BuildDir();
    if (!openmvs_bin.empty() && !openmvs_run) throw Error("expected --openmvs-bin with --openmvs");
    fs::path openmvs;
    if (!openmvs_bin.empty()) {
      openmvs = OpenMvsIn(openmvs_bin);
      if (openmvs.empty()) {
        throw Error(openmvs_bin +
                    ": expected executables DensifyPointCloud and InterfaceCOLMAP (--openmvs-bin)");
      }
    } else if (openmvs_run) {
      openmvs = FindOpenMvs(build);
    }
    if (openmvs_run && openmvs.empty()) {
      throw Error("--openmvs: no DensifyPointCloud with InterfaceCOLMAP beside it under " +
                  (build / "anchors").string() +
                  " or in $SAPMVS_OPENMVS (profiling/anchors/build_openmvs.sh builds them)");
    }
    const fs::path sapmvs = sapmvs_path.empty() ? build / "sapmvs" : fs::path(sapmvs_path);
    if (!IsExecutable(sapmvs)) throw Error(sapmvs.string() + ": no sapmvs binary (--sapmvs)");
    const fs::path pmvs2 = pmvs2_path.empty() ? FindPmvs2(build) : fs::path(pmvs2_path);
    if (!pmvs2_path.empty() && !IsExecutable(pmvs2)) {
      throw Error(pmvs2_path + ": not an executable (--pmvs2)");
    }
    const fs::path out = out_dir, logs = out / "logs";
    fs::create_directories(logs);
    std::vector<std::string> commands;
    const std::string level_arg = std::to_string(level);

    const fs::path pmvs = exported_dir.empty() ? out / "pmvs" : fs::path(exported_dir);
    if (exported_dir.empty()) {
      fs::remove_all(pmvs);
      Step({{sapmvs.string(), "export", block_path, "--format", "pmvs", "--out", pmvs.string(),
             "--level", level_arg},
            {},
            logs / "export.log"},
           &commands);
    }
    const Eigen::Vector3d origin = StripSurfacePrior(pmvs);
    const int images = static_cast<int>(CameraFiles(pmvs).size());
    const Block block = ReadBlock(block_path);
    if (images != static_cast<int>(block.images.size())) {
      throw Error(pmvs.string() + ": " + std::to_string(images) + " cameras, the block has " +
                  std::to_string(block.images.size()));
    }
    const BlockGeometry geometry = EstimateBlockGeometry(block);
    const double gsd = geometry.gsd_median;
    if (!(gsd > 0)) throw Error(block_path + ": no GSD estimate (no surface for the cameras)");
    const double gsd_level = std::ldexp(gsd, level);

    std::vector<Row> rows;
    // A row for the cloud of an earlier run of `tool`: no times.
    auto earlier = [&](const std::string& tool, const std::string& file,
                       const Eigen::Vector3d& offset) {
      Row r;
      r.name = tool + " (" + file + ", earlier run)";
      r.timed = false;
      r.cloud_file = file;
      r.cloud_offset = offset;
      rows.push_back(std::move(r));
    };
    if (!pmvs2_cloud.empty()) {
      earlier("PMVS2", pmvs2_cloud, origin);
    } else if (pmvs2.empty()) {
      std::cout << "PMVS2 not built: skipped\n";
    } else {
      SetPmvsOptions(pmvs / "option", level, threads);
      fs::path input = pmvs;
      if (shift_pyramid) {
        input = out / "pmvs2_shifted";
        WritePyramidShiftedFolder(pmvs, level, input);
      }
      fs::create_directories(input / "models");
      fs::remove(input / "models" / "option.ply");
      // PMVS2 on `folder` as the row `name`, logged to logs/`log`.
      auto run_pmvs2 = [&](std::string name, const fs::path& folder, const std::string& log) {
        Row r;
        r.name = std::move(name);
        // PMVS2 joins the prefix and its file names as strings.
        r.usage =
            Step({{pmvs2.string(), folder.string() + "/", "option"}, {}, logs / log}, &commands);
        r.cloud_file = WrittenCloud(folder / "models" / "option.ply", pmvs2, logs / log);
        r.cloud_offset = origin;
        rows.push_back(std::move(r));
      };
      run_pmvs2(shift_pyramid ? "PMVS2, P shifted for its pyramid" : "PMVS2", input, "pmvs2.log");
      // Its threads take the patches in whatever order they finish, so two
      // runs on the same input differ: the second one's row is how much of
      // PMVS2's cloud PMVS2 itself covers, the scale of the other rows'.
      if (again) {
        const fs::path repeat = out / "pmvs2_again";
        WriteRepeatFolder(input, repeat);
        run_pmvs2(rows.back().name + ", second run", repeat, "pmvs2_again.log");
      }
    }
    // OpenMVS's cloud is in the COLMAP model's frame: sapmvs's world frame
    // for COLMAP's own folder, the local one of a folder sapmvs exported.
    const std::optional<ExportFrame> colmap_frame =
        openmvs_run || !openmvs_cloud.empty() ? ReadExportFrame(block_path) : std::nullopt;
    const Eigen::Vector3d colmap_origin =
        colmap_frame ? colmap_frame->origin : Eigen::Vector3d::Zero();
    if (!openmvs_cloud.empty()) {
      earlier("OpenMVS", openmvs_cloud, colmap_origin);
    } else if (openmvs_run) {
      const fs::path work = fs::absolute(out / "openmvs");
      const fs::path colmap = fs::absolute(block_path);
      // DensifyPointCloud takes up the depth maps it finds in its folder.
      fs::remove_all(work);
      fs::create_directories(work);
      Step({{(openmvs.parent_path() / "InterfaceCOLMAP").string(), "-i", colmap.string(), "-o",
             (work / "scene.mvs").string(), "--image-folder", (colmap / "images").string() + "/",
             "-w", work.string()},
            {},
            logs / "openmvs_interface.log"},
           &commands);
      Row r;
      r.name = "OpenMVS DensifyPointCloud";
      r.usage = Step({{openmvs.string(), "-i", (work / "scene.mvs").string(), "-o",
                       (work / "scene_dense.mvs").string(), "--resolution-level", level_arg,
                       "--max-threads", std::to_string(threads), "-w", work.string()},
                      {},
                      logs / "openmvs_densify.log"},
                     &commands);
      r.cloud_file = WrittenCloud(work / "scene_dense.ply", openmvs, logs / "openmvs_densify.log");
      r.cloud_offset = colmap_origin;
      rows.push_back(std::move(r));
    }
    for (const std::string& mode : modes) {
      const fs::path run = out / ("run_" + mode);
      Row r;
      r.name = "sapmvs --mode " + mode;
      ChildCommand c{{sapmvs.string(), "run", pmvs.string(), "--out", run.string(), "--level",
                      level_arg, "--max-images", std::to_string(max_images ? max_images : images),
                      "--mode", mode, "--restart", "-q"},
                     {{"POCL_CPU_MAX_CU_NUM", std::to_string(threads)}},
                     logs / ("run_" + mode + ".log")};
      // PMVS2 writes a cloud only: the orthophoto, which a binary before it
      // does not know to leave out, is not part of the comparison.
      if (TakesFlag(sapmvs, "--no-ortho")) c.argv.push_back("--no-ortho");
      std::istringstream extra(run_flags);
      for (std::string flag; extra >> flag;) c.argv.push_back(flag);
      if (!run_flags.empty()) r.name += " " + run_flags;
      r.usage = Step(c, &commands);
      r.cloud_file = run / "cloud.ply";
      r.matching_busy = MatchingBusy(run / "report.json");
      r.run = run;
      rows.push_back(std::move(r));
    }

    for (Row& r : rows) {
      r.cloud = ReadPly(r.cloud_file);
      Translate(&r.cloud, r.cloud_offset);
    }
    const bool have_pmvs2 = !pmvs2.empty() || !pmvs2_cloud.empty();
    std::optional<Truth> truth;
    if (!truth_path.empty()) truth = ReadTruth(truth_path);
    for (Row& r : rows) {
      if (have_pmvs2 && &r != &rows.front()) {
        const PointCloud& theirs = rows.front().cloud;
        for (int k = 0; k < 2; ++k) {
          const double radius = (k + 1) * gsd_level;
          if (!theirs.points.empty()) {
            std::vector<bool> has;
            r.from_pmvs2[k] =
                static_cast<double>(CountWithNeighbour(theirs, r.cloud, radius, &has)) /
                theirs.points.size();
            // PMVS2's row comes first, so its own check is done by now.
            const std::optional<SurfaceCheck>& all = rows.front().truth;
            if (k == 1 && all && all->within > 0) {
              PointCloud missed = theirs;
              missed.points.clear();
              for (size_t i = 0; i < has.size(); ++i) {
                if (!has[i]) missed.points.push_back(theirs.points[i]);
              }
              const SurfaceCheck miss = CheckAgainstTruth(missed, *truth, block, gsd, level);
              r.right_from_pmvs2 = 1.0 - static_cast<double>(miss.within) / all->within;
              const std::optional<double>& near = rows.front().near_truth;
              if (near && *near > 0) {
                const double missed_near =
                    ShareNearSurface(missed, truth->surface, 2 * gsd_level) * missed.points.size();
                r.right3d_from_pmvs2 = 1.0 - missed_near / (*near * theirs.points.size());
              }
            }
          }
          if (!r.cloud.points.empty()) {
            r.to_pmvs2[k] = static_cast<double>(CountWithNeighbour(r.cloud, theirs, radius)) /
                            r.cloud.points.size();
          }
        }
        const double reach = kSurfaceReachGsd * gsd_level;
        if (!theirs.points.empty() && r.cloud.has_normals) {
          r.from_pmvs2_surface =
              static_cast<double>(CountNearSurface(theirs, r.cloud, 2 * gsd_level, reach)) /
              theirs.points.size();
        }
        if (!r.cloud.points.empty() && theirs.has_normals) {
          r.to_pmvs2_surface =
              static_cast<double>(CountNearSurface(r.cloud, theirs, 2 * gsd_level, reach)) /
              r.cloud.points.size();
        }
      }
      if (truth) {
        r.truth = CheckAgainstTruth(r.cloud, *truth, block, gsd, level);
        r.near_truth = ShareNearSurface(r.cloud, truth->surface, 2 * gsd_level);
      }
    }

    std::ostringstream md;
    md << "### " << block_path << ", level " << level << ", " << images << " images, " << threads
       << " threads\n\n";
    // What a results file needs to be read alone: the commit, the machine
    // and the command that made the table.
    const MachineInfo machine = DescribeMachine();
    ChildCommand self;
    self.argv.assign(argv, argv + argc);
    md << "sapmvs " << BuildVersion() << " (commit " << BuildCommit() << "); "
       << (machine.cpu_model.empty() ? "unknown CPU" : machine.cpu_model) << ", " << machine.cores
       << " logical CPUs; `" << self.ShellLine() << "`.\n\n"
       << "GSD " << Fixed(gsd, 4) << " at full resolution, " << Fixed(gsd_level, 4) << " at level "
       << level << " (the cloud-to-cloud distances)";
    if (truth) md << "; truth " << truth_path << " (within 1 full-resolution GSD)";
    md << ".\n\n" << Table(rows, truth.has_value()) << "\n";
    std::vector<SurfaceRow> surface;
    for (const Row& r : rows) surface.push_back({r.name, &r.cloud, r.run});
    md << "Without truth (distances in CRS units; noise within " << Fixed(4 * gsd_level, 4)
       << ", 4 GSD):\n\n"
       << SurfaceTable(surface, gsd_level) << "\n";
    if (!have_pmvs2) md << "PMVS2 not built: skipped.\n\n";
    if (!pmvs2_cloud.empty())
      md << "PMVS2's cloud from an earlier run: its times are not shown.\n\n";
    if (!openmvs_cloud.empty())
      md << "OpenMVS's cloud from an earlier run: its times are not shown.\n\n";
    md << "Commands (cwd " << fs::current_path().string() << "):\n\n```sh\n";
    for (const std::string& c : commands) md << c << "\n";
    md << "```\n\n";
    std::cout << md.str();
    if (!markdown_path.empty()) {
      std::ofstream f(markdown_path, std::ios::app);
      f << md.str();
      if (!f) throw Error(markdown_path + ": write failed");
    }
  } catch (const std::exception& e) {
    std::cerr << "versus_pmvs2: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
