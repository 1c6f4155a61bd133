#pragma once
// Helpers shared by the test files: where the checkout's test data and the
// shared datasets lie, and a skip (never a silent pass) when data is missing.

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <cstdlib>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "sapmvs/block/camera.h"
#include "sapmvs/block/image_io.h"
#include "sapmvs/simulate/simulate.h"

namespace sapmvs::test {

// tests/ in the source tree.
std::filesystem::path TestDir();
// ../shared beside the checkout (as in CI); SAPMVS_SHARED_DIR overrides it.
std::filesystem::path SharedDir();
// Strecha's Herz-Jesu-P8 under SharedDir().
std::filesystem::path HerzJesu();
// The bytes of `path`; "" when it cannot be read.
std::string Slurp(const std::filesystem::path& path);
// Replaces `path` with `bytes` (a test's own files; no atomic write).
void WriteFileBytes(const std::filesystem::path& path, const std::string& bytes);
// The entries of `dir`, sorted; none when it does not exist.
std::vector<std::filesystem::path> FolderEntries(const std::filesystem::path& dir);
// A fresh, empty directory under the system temp dir, unique per test.
std::filesystem::path ScratchDir();

// Sets (or, with nullopt, unsets) an environment variable for one scope.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, std::optional<std::string> value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old;
    Set(value);
  }
  ~ScopedEnv() { Set(old_); }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  void Set(const std::optional<std::string>& value) {
    if (value) {
      setenv(name_.c_str(), value->c_str(), 1);
    } else {
      unsetenv(name_.c_str());
    }
  }

  std::string name_;
  std::optional<std::string> old_;
};

// A folder that `make` fills once for every test process of this build and
// that the tests then only read: ctest runs each test in its own process, so
// a per-process cache would remake it for every test. Kept in the temp folder
// under a lock (the other processes of a parallel ctest wait), keyed by `id`
// and by this build's sapmvs binary; a folder whose `make` did not finish is
// made again. `root`, where given, replaces the temp folder and the build's
// key: the folder is then shared by every build that names that root.
std::filesystem::path SharedFolder(const std::string& id,
                                   const std::function<void(const std::filesystem::path&)>& make,
                                   const std::filesystem::path& root = {});

// The options Simulated() runs the simulator with (quiet, truth/lidar.xyz
// too, truth/ortho.tif for tiny seed 1 at full scale only), without `out`:
// a test can rebuild the same world or render the same block again.
SimulateOptions SimulatedOptions(const std::string& preset, int seed, double scale = 1.0);
// The simulator's `preset` rendered with `seed` at `scale` (a SharedFolder).
// Read only: a test that needs a changed block copies it. The simulator is
// the slowest thing the sanitizer build runs, so tests share these folders
// rather than simulate their own. With SAPMVS_SIM_CACHE set, the blocks are
// kept there for every build of the same sources: the scenes are the same
// bytes from gcc and clang, so CI's two builds render each block once.
std::filesystem::path Simulated(const std::string& preset, int seed, double scale = 1.0);

// Kernel-versus-reference comparison: |actual - expected| <= abs_tol + rel_tol
// * |expected|, and NaN exactly where the reference has NaN (border policies
// must agree bit for bit).
::testing::AssertionResult NearAbsRel(double actual, double expected, double abs_tol,
                                      double rel_tol);

// Runs `fn` and expects an InputError naming a file called `file_name` (the
// last path component), `line`, and containing `text`.
void ExpectInputError(const std::function<void()>& fn, const std::string& file_name, int line,
                      const std::string& text);

// A table row for readers' malformed-input tests: file content, and the line
// and text the error must name.
struct MalformedText {
  std::string name;
  std::string text;
  int line;
  std::string expect;
};
// Keeps ctest's discovered test names stable (no byte dumps).
inline void PrintTo(const MalformedText& m, std::ostream* os) { *os << m.name; }

// A fixture with a fresh scratch folder `dir_`, removed after the test.
class ScratchTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = ScratchDir(); }
  void TearDown() override { std::filesystem::remove_all(dir_); }
  bool DirIsEmpty() const {
    return std::filesystem::directory_iterator(dir_) == std::filesystem::directory_iterator();
  }
  std::filesystem::path dir_;
};

// Reads `X Y Z` lines, keeping every `stride`-th point.
std::vector<Eigen::Vector3d> ReadXyz(const std::filesystem::path& path, int stride = 1);

// Photo-consistency of a pair: the mean NCC of (2 half + 1)^2 grey windows,
// bilinearly sampled around the projections of `points` into both images
// (image b's projections moved by `shift_b` pixels), over the points that
// land inside both images on textured windows.
struct PairNcc {
  int points = 0;
  double mean = 0;
};
PairNcc MeanPairNcc(const LoadedImage& a, const LoadedImage& b,
                    const std::vector<Eigen::Vector3d>& points, int half = 5,
                    const Eigen::Vector2d& shift_b = Eigen::Vector2d::Zero());

// MeanPairNcc over every pair of `images` that shares at least `min_points`
// points, also measured with image b shifted by 20 px as a control. Prints
// one line per pair.
struct BlockNcc {
  int pairs = 0;
  double mean = 0;          // mean over pairs
  double worst = 1;         // lowest pair
  double worst_margin = 1;  // lowest (pair NCC - shifted-control NCC)
};
BlockNcc MeasureBlockNcc(const std::vector<LoadedImage>& images,
                         const std::vector<std::string>& names,
                         const std::vector<Eigen::Vector3d>& points, int min_points = 200);

// SIFT matches (Lowe ratio 0.75, mutual) between two image files, cached per
// pair for the test binary's lifetime: several readers are checked against
// the same real images.
struct Match {
  Eigen::Vector2d a, b;
};
const std::vector<Match>& SiftMatches(const std::filesystem::path& a,
                                      const std::filesystem::path& b);

// Median distance (px, in image b) of the matches to the epipolar lines of
// the two cameras.
double MedianEpipolarDistance(const Camera& a, const Camera& b, const std::vector<Match>& matches);

}  // namespace sapmvs::test

namespace sapmvs::test {
// Whether SAPMVS_REQUIRE_OPENCL=1 (scripts/test.sh sets it): then a test that
// needs an OpenCL device fails without one instead of skipping, so that a
// machine without a driver cannot pass the suite.
bool OpenClRequired();
}  // namespace sapmvs::test

// Skips the current test for want of an OpenCL device, saying `why`; fails
// it instead when OpenClRequired().
#define SAPMVS_SKIP_WITHOUT_OPENCL(why)                                                    \
  do {                                                                                     \
    if (::sapmvs::test::OpenClRequired()) FAIL() << (why) << " (SAPMVS_REQUIRE_OPENCL=1)"; \
    GTEST_SKIP() << (why);                                                                 \
  } while (0)

namespace sapmvs::test {
// What a headless Chromium (Debian's `chromium`) made of a page: the DOM
// after the load event, and every console message (errors, uncaught
// exceptions, logs) it printed. `browser` is empty when none is installed.
struct BrowserPage {
  std::string browser;
  std::string dom;
  std::vector<std::string> console;
};
BrowserPage LoadInHeadlessBrowser(const std::filesystem::path& html);
// Whether SAPMVS_REQUIRE_BROWSER=1 (scripts/test.sh sets it, having
// installed Chromium): then a test without a browser fails, not skips.
bool BrowserRequired();
}  // namespace sapmvs::test

// Skips the current test when `page` found no browser; fails it instead when
// BrowserRequired().
#define SAPMVS_REQUIRE_BROWSER(page)                                                   \
  do {                                                                                 \
    if ((page).browser.empty()) {                                                      \
      if (::sapmvs::test::BrowserRequired())                                           \
        FAIL() << "no headless browser (chromium) on PATH (SAPMVS_REQUIRE_BROWSER=1)"; \
      GTEST_SKIP() << "no headless browser (chromium) on PATH";                        \
    }                                                                                  \
  } while (0)

// Skips the current test, naming the missing path, when `path` does not exist.
#define SAPMVS_REQUIRE_PATH(path)                                 \
  do {                                                            \
    if (!std::filesystem::exists(path)) {                         \
      GTEST_SKIP() << "test data not found: " << (path).string(); \
    }                                                             \
  } while (0)
