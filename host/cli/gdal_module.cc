// The binary's side of the GDAL module (gdal_module.h): the functions whose
// code calls GDAL, defined as calls into the module, which the first of them
// loads.
#include "cli/gdal_module.h"

#include <dlfcn.h>
#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>
#include <utility>

#include "sapmvs/util/error.h"

namespace sapmvs {
namespace {

namespace fs = std::filesystem;

// The module's file, beside the binary or in ../lib/sapmvs; throws naming
// both places when it is in neither.
fs::path FindModule() {
  constexpr const char* kName = "libsapmvs_gdal.so";
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) {
    throw Error(std::string(kName) + ": cannot find the sapmvs binary's folder (" + ec.message() +
                ")");
  }
  const fs::path candidates[] = {
      exe.parent_path() / kName,
      (exe.parent_path() / ".." / "lib" / "sapmvs" / kName).lexically_normal()};
  for (const fs::path& file : candidates) {
    if (fs::is_regular_file(file, ec)) return file;
  }
  throw Error(std::string(kName) + ": cannot load the GDAL module (" + candidates[0].string() +
              " and " + candidates[1].string() +
              " missing; expected it beside the sapmvs binary or in ../lib/sapmvs)");
}

const GdalModuleFunctions* LoadModule() {
  const fs::path file = FindModule();
  // Never closed: the table, vtables and GDAL's state live as long as the
  // process.
  void* handle = dlopen(file.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (!handle) throw Error(file.string() + ": cannot load the GDAL module (" + dlerror() + ")");
  using Entry = const GdalModuleFunctions* (*)();
  auto entry = reinterpret_cast<Entry>(dlsym(handle, "sapmvs_gdal_module"));
  const GdalModuleFunctions* table = entry ? entry() : nullptr;
  if (!table || table->version != kGdalModuleVersion ||
      table->size != sizeof(GdalModuleFunctions)) {
    throw Error(file.string() +
                ": not this build's GDAL module (expected the libsapmvs_gdal.so built with this "
                "sapmvs; rebuild or reinstall)");
  }
  return table;
}

std::atomic<bool> loaded{false};

const GdalModuleFunctions& Gdal() {
  static const GdalModuleFunctions* table = [] {
    const GdalModuleFunctions* t = LoadModule();
    loaded = true;
    return t;
  }();
  return *table;
}

}  // namespace

double GdalBytesToLoad() {
  // What GDAL and its libraries held resident at the end of a run on
  // `small`, once they had written its outputs with the drivers those need
  // (util/gdal_drivers.h): 30.4 MiB (39.9 with every driver registered).
  constexpr double kGdalResidentBytes = 32.0 * (1 << 20);
  return loaded ? 0 : kGdalResidentBytes;
}

int CheckCrsMain(const char* crs) {
  try {
    CrsToWkt(crs);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}

GeoOutputsCheck::GeoOutputsCheck(std::string crs, std::string source)
    : crs_(std::move(crs)), source_(std::move(source)) {
  FindModule();                        // the DSM rasters need it
  if (crs_.empty() || loaded) return;  // Wait() checks in this process
  // A child (posix_spawn: safe with this process's threads, and it leaves
  // its memory alone) loads GDAL and checks; this process does not load it.
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
    throw Error("CRS '" + crs_ + "': cannot check it (pipe: " + std::strerror(errno) + ")");
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  const std::string exe = "/proc/self/exe";
  char* const argv[] = {const_cast<char*>("sapmvs"), const_cast<char*>(kCheckCrsArgument),
                        const_cast<char*>(crs_.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, exe.c_str(), &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  if (spawned != 0) {
    close(pipe_fds[0]);
    throw Error("CRS '" + crs_ + "': cannot check it (" + std::strerror(spawned) + ")");
  }
  child_ = pid;
  child_stderr_ = pipe_fds[0];
}

GeoOutputsCheck::~GeoOutputsCheck() {
  // Closing first ends a child still writing (EPIPE); then it is reaped.
  if (child_stderr_ >= 0) close(child_stderr_);
  int status = 0;
  if (child_ > 0) {
    while (waitpid(child_, &status, 0) < 0 && errno == EINTR) {
    }
  }
}

void GeoOutputsCheck::Wait() {
  if (crs_.empty()) return;
  if (child_ <= 0) {
    try {
      CrsToWkt(crs_);
    } catch (const Error& e) {
      throw Error(source_ + ": " + e.what());
    }
    return;
  }
  std::string said;
  char buffer[4096];
  for (ssize_t n; (n = read(child_stderr_, buffer, sizeof(buffer))) != 0;) {
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) break;
    said.append(buffer, static_cast<size_t>(n));
  }
  close(child_stderr_);
  child_stderr_ = -1;
  int status = 0;
  while (waitpid(child_, &status, 0) < 0 && errno == EINTR) {
  }
  child_ = -1;
  if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
  while (!said.empty() && (said.back() == '\n' || said.back() == '\r')) said.pop_back();
  if (const size_t line = said.rfind('\n'); line != std::string::npos) said = said.substr(line + 1);
  throw Error(source_ + ": " +
              (said.empty()
                   ? "CRS '" + crs_ + "': the check failed (status " + std::to_string(status) + ")"
                   : said));
}

cv::Mat DecodeImageWithGdal(const fs::path& path) { return Gdal().decode_image(path); }
cv::Size ReadImageSizeWithGdal(const fs::path& path) { return Gdal().read_image_size(path); }
std::vector<unsigned char> EncodeImage(const cv::Mat& image, ImageEncoding encoding,
                                       const std::string& what, int jpeg_quality) {
  return Gdal().encode_image(image, encoding, what, jpeg_quality);
}
bool CanEncode(ImageEncoding encoding) { return Gdal().can_encode(encoding); }
Dem Dem::Load(const fs::path& path, long max_cells) { return Gdal().load_dem(path, max_cells); }
std::unique_ptr<EcefToUtm> MakeEcefToUtm(int epsg) { return Gdal().make_ecef_to_utm(epsg); }
void WriteGeoTiff(const fs::path& path, const GeoRaster& raster) {
  Gdal().write_geotiff(path, raster);
}
void WriteColorGeoTiff(const fs::path& path, const GeoRaster& grid,
                       const std::vector<uint8_t>& rgba) {
  Gdal().write_color_geotiff(path, grid, rgba);
}
GeoRaster ReadGeoRaster(const fs::path& path) { return Gdal().read_geo_raster(path); }
std::string CrsToWkt(const std::string& crs) {
  // Most blocks have no CRS: that needs no module.
  return crs.empty() ? std::string() : Gdal().crs_to_wkt(crs);
}
CrsIdentity IdentifyCrs(const std::string& crs) { return Gdal().identify_crs(crs); }
WktFacts ReadWktFacts(const std::string& wkt) { return Gdal().read_wkt_facts(wkt); }
std::string CrsLinearUnit(const std::string& crs) { return Gdal().crs_linear_unit(crs); }
DsmPictures WriteDsmPictures(const GeoRaster& dsm, const fs::path& color_tif, const fs::path& png,
                             const DsmPictureOptions& options) {
  return Gdal().write_dsm_pictures(dsm, color_tif, png, options);
}

}  // namespace sapmvs
