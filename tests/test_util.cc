#include "test_util.h"

#include "sapmvs/simulate/simulate.h"
#include "sapmvs/util/error.h"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>
#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <iterator>
#include <map>
#include <opencv2/features2d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <stdexcept>

namespace sapmvs::test {

std::filesystem::path TestDir() { return SAPMVS_TEST_DIR; }

namespace {

namespace fs = std::filesystem;

// This build's identity: the sapmvs binary's path, size and modification
// time. Both test binaries and the CLI link the same sapmvs_core, which is
// relinked into sapmvs whenever it changes; a cache made by another build may
// hold another simulator's images or another matcher's cloud.
std::string BuildKey() {
  std::error_code ec;
  const fs::path exe = SAPMVS_CLI_PATH;
  const auto size = fs::file_size(exe, ec);
  const auto time = fs::last_write_time(exe, ec).time_since_epoch().count();
  return std::to_string(std::hash<std::string>{}(exe.string())) + "_" + std::to_string(size) + "_" +
         std::to_string(time);
}

// Drops the caches of other builds left an hour or more ago.
void RemoveStaleCaches(const fs::path& keep) {
  std::error_code ec;
  const auto now = fs::file_time_type::clock::now();
  for (const auto& e : fs::directory_iterator(fs::temp_directory_path(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.rfind("sapmvs_sim_cache_", 0) != 0 || e.path() == keep) continue;
    std::error_code ec2;
    if (now - fs::last_write_time(e.path(), ec2) > std::chrono::hours(1))
      fs::remove_all(e.path(), ec2);
  }
}

}  // namespace

fs::path SharedFolder(const std::string& id, const std::function<void(const fs::path&)>& make,
                      const fs::path& root) {
  static std::map<std::string, fs::path> made;
  if (auto it = made.find(id); it != made.end()) return it->second;
  const fs::path cache =
      root.empty() ? fs::temp_directory_path() / ("sapmvs_sim_cache_" + BuildKey()) : root;
  fs::create_directories(cache);
  const fs::path dir = cache / id;
  // Made in place (a run's files name their folder) and marked done beside it.
  const fs::path done = cache / (id + ".done");
  const int lock = ::open((cache / (id + ".lock")).c_str(), O_CREAT | O_RDWR, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) throw Error("cannot lock " + cache.string());
  try {
    if (!fs::exists(done)) {
      fs::remove_all(dir);
      make(dir);
      std::ofstream(done).put('\n');
      if (root.empty()) RemoveStaleCaches(cache);
    }
  } catch (...) {
    ::close(lock);
    throw;
  }
  ::close(lock);
  made[id] = dir;
  return dir;
}

SimulateOptions SimulatedOptions(const std::string& preset, int seed, double scale) {
  SimulateOptions o;
  o.preset = preset;
  o.seed = seed;
  o.scale = scale;
  o.quiet = true;
  o.xyz = true;
  // The true orthophoto only where a test reads it (SimOrtho, the run's
  // ortho against it): rendered under the sanitizers for every block, it
  // took half a minute of CI.
  o.ortho = preset == "tiny" && seed == 1 && scale == 1.0;
  return o;
}

fs::path Simulated(const std::string& preset, int seed, double scale) {
  std::ostringstream id;
  id << preset << "_seed" << seed << "_scale" << scale;
  const char* shared = std::getenv("SAPMVS_SIM_CACHE");
  return SharedFolder(
      id.str(),
      [&](const fs::path& dir) {
        SimulateOptions o = SimulatedOptions(preset, seed, scale);
        o.out = dir;
        Simulate(o);
      },
      shared && *shared ? fs::path(shared) : fs::path());
}

bool OpenClRequired() {
  const char* env = std::getenv("SAPMVS_REQUIRE_OPENCL");
  return env && std::string(env) == "1";
}

bool BrowserRequired() {
  const char* env = std::getenv("SAPMVS_REQUIRE_BROWSER");
  return env && std::string(env) == "1";
}

BrowserPage LoadInHeadlessBrowser(const std::filesystem::path& html) {
  BrowserPage page;
  for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
    const std::string which = std::string("command -v ") + name + " >/dev/null 2>&1";
    if (std::system(which.c_str()) == 0) {
      page.browser = name;
      break;
    }
  }
  if (page.browser.empty()) return page;
  static int calls = 0;
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() /
      ("sapmvs_browser_" + std::to_string(getpid()) + "_" + std::to_string(calls++));
  std::filesystem::create_directories(dir);
  // --no-sandbox: the tests may run as root, where Chromium's sandbox will
  // not start. Console messages go to stderr as INFO:CONSOLE lines.
  const std::string cmd = "timeout 120 " + page.browser +
                          " --headless --no-sandbox --disable-gpu --no-first-run "
                          "--user-data-dir=" +
                          (dir / "profile").string() +
                          " --enable-logging=stderr --v=0 --dump-dom 'file://" +
                          std::filesystem::absolute(html).string() + "' > " +
                          (dir / "dom.html").string() + " 2> " + (dir / "stderr.txt").string();
  if (std::system(cmd.c_str()) != 0) {
    throw std::runtime_error("failed: " + cmd + "\n" + Slurp(dir / "stderr.txt"));
  }
  page.dom = Slurp(dir / "dom.html");
  std::istringstream err(Slurp(dir / "stderr.txt"));
  for (std::string line; std::getline(err, line);) {
    if (line.find(":CONSOLE") != std::string::npos) page.console.push_back(line);
  }
  std::filesystem::remove_all(dir);
  return page;
}

std::filesystem::path HerzJesu() { return SharedDir() / "datasets/strecha_herzjesu/Herz-Jesus-P8"; }

std::string Slurp(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void WriteFileBytes(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << bytes;
}

std::vector<std::filesystem::path> FolderEntries(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> entries;
  if (!std::filesystem::exists(dir)) return entries;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    entries.push_back(entry.path());
  }
  std::sort(entries.begin(), entries.end());
  return entries;
}

std::filesystem::path SharedDir() {
  if (const char* env = std::getenv("SAPMVS_SHARED_DIR"); env && *env) return env;
  return std::filesystem::weakly_canonical(SAPMVS_SHARED_DIR);
}

namespace {

std::filesystem::path ScratchPath(const ::testing::TestInfo* info) {
  // The pid keeps two runs of the suite (e.g. two build trees) apart.
  std::string name = "sapmvs_test_" + std::to_string(::getpid());
  if (info) name += std::string("_") + info->test_suite_name() + "_" + info->name();
  for (char& c : name) {
    if (c == '/') c = '_';
  }
  return std::filesystem::temp_directory_path() / name;
}

// Removes a test's scratch folder when the test passed; a failed test's
// stays for a look.
class ScratchCleaner : public ::testing::EmptyTestEventListener {
  void OnTestEnd(const ::testing::TestInfo& info) override {
    if (!info.result()->Passed()) return;
    std::error_code ec;
    std::filesystem::remove_all(ScratchPath(&info), ec);
  }
};

const bool kCleanerInstalled = [] {
  ::testing::UnitTest::GetInstance()->listeners().Append(new ScratchCleaner);
  return true;
}();

}  // namespace

std::filesystem::path ScratchDir() {
  const auto dir = ScratchPath(::testing::UnitTest::GetInstance()->current_test_info());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

::testing::AssertionResult NearAbsRel(double actual, double expected, double abs_tol,
                                      double rel_tol) {
  if (std::isnan(expected) || std::isnan(actual)) {
    if (std::isnan(expected) && std::isnan(actual)) return ::testing::AssertionSuccess();
    return ::testing::AssertionFailure()
           << "NaN policy differs: got " << actual << ", reference " << expected;
  }
  const double error = std::abs(actual - expected);
  const double tolerance = abs_tol + rel_tol * std::abs(expected);
  if (error <= tolerance) return ::testing::AssertionSuccess();
  return ::testing::AssertionFailure() << "got " << actual << ", reference " << expected
                                       << ", error " << error << " > tolerance " << tolerance;
}

void ExpectInputError(const std::function<void()>& fn, const std::string& file_name, int line,
                      const std::string& text) {
  try {
    fn();
    ADD_FAILURE() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_EQ(std::filesystem::path(e.file()).filename().string(), file_name) << e.what();
    EXPECT_EQ(e.line(), line) << e.what();
    EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
  }
}

std::vector<Eigen::Vector3d> ReadXyz(const std::filesystem::path& path, int stride) {
  std::ifstream in(path);
  std::vector<Eigen::Vector3d> out;
  double x, y, z;
  for (long i = 0; in >> x >> y >> z; ++i) {
    if (i % stride == 0) out.emplace_back(x, y, z);
  }
  return out;
}

namespace {

cv::Mat Grey(const cv::Mat& bgr) {
  cv::Mat g, f;
  cv::cvtColor(bgr, g, cv::COLOR_BGR2GRAY);
  g.convertTo(f, CV_32F);
  return f;
}

double Bilinear(const cv::Mat& g, double x, double y) {
  // Checked before the cast: a NaN or huge coordinate cast to int is
  // undefined (UBSan).
  if (!(x >= 0 && y >= 0 && x < g.cols && y < g.rows)) return std::nan("");
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  if (x0 < 0 || y0 < 0 || x0 + 1 >= g.cols || y0 + 1 >= g.rows) return std::nan("");
  const double fx = x - x0, fy = y - y0;
  return (1 - fy) * ((1 - fx) * g.at<float>(y0, x0) + fx * g.at<float>(y0, x0 + 1)) +
         fy * ((1 - fx) * g.at<float>(y0 + 1, x0) + fx * g.at<float>(y0 + 1, x0 + 1));
}

}  // namespace

PairNcc MeanPairNcc(const LoadedImage& a, const LoadedImage& b,
                    const std::vector<Eigen::Vector3d>& points, int half,
                    const Eigen::Vector2d& shift_b) {
  const cv::Mat ga = Grey(a.pixels), gb = Grey(b.pixels);
  const int n = (2 * half + 1) * (2 * half + 1);
  std::vector<double> wa(n), wb(n);
  PairNcc r;
  double sum = 0;
  for (const Eigen::Vector3d& x : points) {
    // The window is image a's pixel grid around the point, laid on the plane
    // through the point facing camera a, and projected into b: images of
    // opposite strips (kappa 0 and 180) are compared on the ground, not as
    // rotated pixel windows.
    const Eigen::Vector2d ua = a.camera.Project(x);
    const double depth = a.camera.Depth(x);
    if (!(depth > 0) || !b.camera.Project(x).allFinite()) continue;
    bool ok = true;
    for (int k = 0, i = -half; i <= half && ok; ++i) {
      for (int j = -half; j <= half && ok; ++j, ++k) {
        const Eigen::Vector2d pa = ua + Eigen::Vector2d(j, i);
        const Eigen::Vector2d pb = b.camera.Project(a.camera.BackProject(pa, depth)) + shift_b;
        wa[k] = Bilinear(ga, pa.x(), pa.y());
        wb[k] = Bilinear(gb, pb.x(), pb.y());
        ok = std::isfinite(wa[k]) && std::isfinite(wb[k]);
      }
    }
    if (!ok) continue;
    double ma = 0, mb = 0;
    for (int k = 0; k < n; ++k) {
      ma += wa[k];
      mb += wb[k];
    }
    ma /= n;
    mb /= n;
    double saa = 0, sbb = 0, sab = 0;
    for (int k = 0; k < n; ++k) {
      saa += (wa[k] - ma) * (wa[k] - ma);
      sbb += (wb[k] - mb) * (wb[k] - mb);
      sab += (wa[k] - ma) * (wb[k] - mb);
    }
    // Flat windows (water, saturated roofs, undistortion's black border) have
    // no defined correlation: a standard deviation under 2 grey levels.
    if (saa < 4.0 * n || sbb < 4.0 * n) continue;
    sum += sab / std::sqrt(saa * sbb);
    ++r.points;
  }
  r.mean = r.points ? sum / r.points : 0;
  return r;
}

BlockNcc MeasureBlockNcc(const std::vector<LoadedImage>& images,
                         const std::vector<std::string>& names,
                         const std::vector<Eigen::Vector3d>& points, int min_points) {
  BlockNcc r;
  double sum = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    for (size_t j = i + 1; j < images.size(); ++j) {
      const PairNcc at = MeanPairNcc(images[i], images[j], points);
      if (at.points < min_points) continue;
      const PairNcc off = MeanPairNcc(images[i], images[j], points, 5, {20, 0});
      std::cout << "[ ncc ] " << names[i] << " / " << names[j] << ": " << at.mean << " over "
                << at.points << " points; shifted 20 px: " << off.mean << "\n";
      ++r.pairs;
      sum += at.mean;
      r.worst = std::min(r.worst, at.mean);
      r.worst_margin = std::min(r.worst_margin, at.mean - off.mean);
    }
  }
  r.mean = r.pairs ? sum / r.pairs : 0;
  std::cout << "[ ncc ] mean over " << r.pairs << " pairs: " << r.mean << "\n";
  return r;
}

namespace {

struct Features {
  std::vector<cv::KeyPoint> keypoints;
  cv::Mat descriptors;
};

const Features& SiftFeatures(const std::filesystem::path& path) {
  static std::map<std::string, Features> cache;
  auto it = cache.find(path.string());
  if (it != cache.end()) return it->second;
  // SIFT at half size: OpenCV first doubles the image, so at full size it
  // builds its pyramid from 4x the pixels, and on a 3072x2048 image that
  // is seconds of page faults per image. Keypoints map back to full-size
  // pixels (centres at integers), so callers keep full-size units.
  const cv::Mat full = cv::imread(path.string(), cv::IMREAD_GRAYSCALE);
  cv::Mat grey;
  cv::resize(full, grey, cv::Size(), 0.5, 0.5, cv::INTER_AREA);
  Features f;
  cv::SIFT::create(4000)->detectAndCompute(grey, cv::noArray(), f.keypoints, f.descriptors);
  for (cv::KeyPoint& k : f.keypoints)
    k.pt = (k.pt + cv::Point2f(0.5f, 0.5f)) * 2.0f - cv::Point2f(0.5f, 0.5f);
  return cache.emplace(path.string(), std::move(f)).first->second;
}

}  // namespace

const std::vector<Match>& SiftMatches(const std::filesystem::path& a,
                                      const std::filesystem::path& b) {
  static std::map<std::pair<std::string, std::string>, std::vector<Match>> cache;
  const auto key = std::make_pair(a.string(), b.string());
  auto it = cache.find(key);
  if (it != cache.end()) return it->second;
  const Features& fa = SiftFeatures(a);
  const Features& fb = SiftFeatures(b);
  cv::BFMatcher matcher(cv::NORM_L2);
  std::vector<std::vector<cv::DMatch>> ab, ba;
  matcher.knnMatch(fa.descriptors, fb.descriptors, ab, 2);
  matcher.knnMatch(fb.descriptors, fa.descriptors, ba, 2);
  std::vector<Match> out;
  for (const auto& m : ab) {
    if (m.size() < 2 || m[0].distance > 0.75f * m[1].distance) continue;
    const auto& back = ba[m[0].trainIdx];
    if (back.empty() || back[0].trainIdx != m[0].queryIdx) continue;
    const cv::Point2f pa = fa.keypoints[m[0].queryIdx].pt, pb = fb.keypoints[m[0].trainIdx].pt;
    out.push_back({{pa.x, pa.y}, {pb.x, pb.y}});
  }
  return cache.emplace(key, std::move(out)).first->second;
}

double MedianEpipolarDistance(const Camera& a, const Camera& b, const std::vector<Match>& matches) {
  // F = K_b^-T [t]x R K_a^-1 with the pose of b relative to a.
  const Eigen::Matrix3d r = b.rotation() * a.rotation().transpose();
  const Eigen::Vector3d t = b.rotation() * (a.center() - b.center());
  Eigen::Matrix3d tx;
  tx << 0, -t.z(), t.y(), t.z(), 0, -t.x(), -t.y(), t.x(), 0;
  const Eigen::Matrix3d f =
      b.intrinsics().K().inverse().transpose() * tx * r * a.intrinsics().K().inverse();
  std::vector<double> d;
  for (const Match& m : matches) {
    const Eigen::Vector3d line = f * m.a.homogeneous();
    d.push_back(std::abs(line.dot(m.b.homogeneous())) / line.head<2>().norm());
  }
  if (d.empty()) return std::nan("");
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace sapmvs::test
