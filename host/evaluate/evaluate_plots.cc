// The evaluation's PNG plots: a histogram of dz, a map of dz over XY with a
// colour bar, and a map of where the pseudo-errors are, every axis with its
// unit. Drawn with OpenCV so that no plotting stack is needed.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "sapmvs/evaluate/evaluate.h"
#include "sapmvs/io/raster_io.h"
#include "sapmvs/util/atomic_file.h"
#include "sapmvs/util/error.h"
#include "sapmvs/util/number_text.h"
#include "util/image_codec.h"

namespace sapmvs {
namespace {

// Layout, in pixels: the plot area's longest side and the margins around it
// (room for the title, axis labels and the colour bar).
constexpr int kPlotSide = 800;
constexpr int kMarginLeft = 90, kMarginRight = 130, kMarginTop = 60, kMarginBottom = 50;
constexpr int kHistogramBins = 80;
// The maps merge pixels into blocks of up to this many pixels a side (a
// power of two) until a typical block with points holds this many.
constexpr int kMaxBlock = 64;
constexpr double kPointsPerBlock = 2;
// The colour and histogram range is this quantile of |dz|, so that
// pseudo-errors of tens of metres (often several percent of the points on
// building edges) do not flatten everything else.
constexpr double kRangeQuantile = 0.95;

const cv::Scalar kBlack(0, 0, 0), kWhite(255, 255, 255), kGrey(200, 200, 200), kRed(0, 0, 220),
    kBlue(200, 120, 40), kGreen(60, 160, 60);

void Text(cv::Mat* img, const std::string& text, int x, int y, double scale = 0.45,
          const cv::Scalar& color = kBlack) {
  cv::putText(*img, text, {x, y}, cv::FONT_HERSHEY_SIMPLEX, scale, color, 1, cv::LINE_AA);
}

// The smallest of 1, 2, 2.5, 5 x 10^k at or above v.
double NiceCeil(double v) {
  if (!(v > 0)) return 1;
  const double p = std::pow(10.0, std::floor(std::log10(v)));
  for (double m : {1.0, 2.0, 2.5, 5.0, 10.0}) {
    if (m * p >= v * (1 - 1e-12)) return m * p;
  }
  return 10 * p;
}

// " (m)" for axis labels.
std::string Unit(const EvaluationReport& r, bool vertical) {
  return " (" + (vertical ? HeightLabel(r.unit) : LengthLabel(r.unit)) + ")";
}

// Block sums of `m` (CV_64F), f x f pixels each: INTER_AREA over whole blocks
// is their exact mean, times f^2.
cv::Mat BlockSums(const cv::Mat& m, int f) {
  cv::Mat padded, out;
  cv::copyMakeBorder(m, padded, 0, (f - m.rows % f) % f, 0, (f - m.cols % f) % f,
                     cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::resize(padded, out, {padded.cols / f, padded.rows / f}, 0, 0, cv::INTER_AREA);
  return out * (f * f);
}

// Per-pixel sums and counts over the plot merged into blocks large enough
// that a typical block with points holds kPointsPerBlock of them, then shown
// block by block. Pixels finer than the point spacing would otherwise show
// the points' lattice beating against the pixels' as a moire of dots and
// gaps; area averaging over whole blocks keeps every point and no pattern.
struct Blocks {
  int f = 1;
  cv::Mat sum, count;  // per block
  // The block of plot pixel (x, y).
  double Sum(int x, int y) const { return sum.at<double>(y / f, x / f); }
  double Count(int x, int y) const { return count.at<double>(y / f, x / f); }
};
Blocks MergeIntoBlocks(const cv::Mat& sum, const cv::Mat& count) {
  Blocks b;
  for (b.f = 1;; b.f *= 2) {
    b.count = BlockSums(count, b.f);
    std::vector<double> occupied;
    for (auto it = b.count.begin<double>(); it != b.count.end<double>(); ++it) {
      if (*it > 0.5) occupied.push_back(*it);
    }
    if (occupied.empty() || b.f >= kMaxBlock) break;
    std::nth_element(occupied.begin(), occupied.begin() + occupied.size() / 2, occupied.end());
    if (occupied[occupied.size() / 2] >= kPointsPerBlock) break;
  }
  b.sum = BlockSums(sum, b.f);
  return b;
}

// The symmetric range [-R, R] of the colour scale and histogram.
double ErrorRange(const EvaluationReport& r) {
  std::vector<double> a;
  for (double d : r.dz) {
    if (std::isfinite(d)) a.push_back(std::abs(d));
  }
  double range = r.tolerance;
  if (!a.empty()) {
    const auto q = a.begin() + static_cast<std::ptrdiff_t>(kRangeQuantile * (a.size() - 1));
    std::nth_element(a.begin(), q, a.end());
    range = std::max(range, *q);
  }
  return NiceCeil(range);
}

// Diverging blue - light grey - red (BGR), t in [-1, 1]: the sign of dz
// reads at a glance and zero stays visible on white.
cv::Vec3b Diverging(double t) {
  t = std::clamp(t, -1.0, 1.0);
  const double mid[3] = {221, 221, 221};
  const double end[3] = {t < 0 ? 192.0 : 38.0, t < 0 ? 76.0 : 4.0, t < 0 ? 59.0 : 180.0};
  const double a = std::abs(t);
  cv::Vec3b c;
  for (int k = 0; k < 3; ++k) c[k] = cv::saturate_cast<uchar>(mid[k] + a * (end[k] - mid[k]));
  return c;
}

void WritePng(const std::filesystem::path& path, const cv::Mat& img) {
  const std::vector<uchar> bytes = EncodeImage(img, ImageEncoding::kPng, path.string());
  WriteStreamAtomically(path, [&](std::ostream& out) {
    out.write(reinterpret_cast<const char*>(bytes.data()),
              static_cast<std::streamsize>(bytes.size()));
  });
}

// Maps world XY to pixels, north up, keeping the aspect ratio.
struct MapFrame {
  explicit MapFrame(const std::vector<Eigen::Vector3d>& points) {
    Eigen::Vector2d lo = points[0].head<2>(), hi = lo;
    for (const Eigen::Vector3d& p : points) {
      lo = lo.cwiseMin(p.head<2>());
      hi = hi.cwiseMax(p.head<2>());
    }
    min = lo;
    max = hi;
    const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-9});
    scale = (kPlotSide - 1) / span;
    width = std::max(1, static_cast<int>(std::lround((hi.x() - lo.x()) * scale)) + 1);
    height = std::max(1, static_cast<int>(std::lround((hi.y() - lo.y()) * scale)) + 1);
  }
  cv::Point Pixel(const Eigen::Vector3d& p) const {
    return {kMarginLeft + static_cast<int>(std::lround((p.x() - min.x()) * scale)),
            kMarginTop + static_cast<int>(std::lround((max.y() - p.y()) * scale))};
  }
  // The plot area with X (east) and Y (north) axes, ticks and their unit.
  cv::Mat Canvas(const std::string& unit) const {
    cv::Mat img(kMarginTop + height + kMarginBottom + 20, kMarginLeft + width + kMarginRight,
                CV_8UC3, kWhite);
    cv::rectangle(img, {kMarginLeft - 1, kMarginTop - 1},
                  {kMarginLeft + width, kMarginTop + height}, kBlack);
    const double step = NiceCeil(std::max(max.x() - min.x(), max.y() - min.y()) / 5);
    for (double x = std::ceil(min.x() / step) * step; x <= max.x(); x += step) {
      const int px = kMarginLeft + static_cast<int>(std::lround((x - min.x()) * scale));
      cv::line(img, {px, kMarginTop + height}, {px, kMarginTop + height + 5}, kBlack);
      Text(&img, FormatPrintf("%.10g", x), px - 25, kMarginTop + height + 20, 0.4);
    }
    for (double y = std::ceil(min.y() / step) * step; y <= max.y(); y += step) {
      const int py = kMarginTop + static_cast<int>(std::lround((max.y() - y) * scale));
      cv::line(img, {kMarginLeft - 6, py}, {kMarginLeft - 1, py}, kBlack);
      Text(&img, FormatPrintf("%.10g", y), 4, py + 4, 0.4);
    }
    Text(&img, "X, east" + unit + "; north up", kMarginLeft, kMarginTop + height + 42);
    Text(&img, "Y" + unit, 4, kMarginTop - 8);
    return img;
  }
  Eigen::Vector2d min, max;
  double scale = 1;
  int width = 1, height = 1;
};

cv::Mat Histogram(const EvaluationReport& r, double range) {
  std::vector<long> bins(kHistogramBins, 0);
  long n = 0;
  for (double d : r.dz) {
    if (!std::isfinite(d)) continue;
    const int b = static_cast<int>(std::floor((d + range) / (2 * range) * kHistogramBins));
    ++bins[std::clamp(b, 0, kHistogramBins - 1)];
    ++n;
  }
  const long peak = std::max<long>(1, *std::max_element(bins.begin(), bins.end()));
  const int w = kPlotSide, h = kPlotSide / 2;
  cv::Mat img(kMarginTop + h + kMarginBottom + 10, kMarginLeft + w + 40, CV_8UC3, kWhite);
  const int bar = w / kHistogramBins;
  for (int b = 0; b < kHistogramBins; ++b) {
    const int top = kMarginTop + h - static_cast<int>(std::lround(double(bins[b]) / peak * h));
    cv::rectangle(img, {kMarginLeft + b * bar, top},
                  {kMarginLeft + (b + 1) * bar - 2, kMarginTop + h},
                  cv::Scalar(Diverging((b + 0.5) / kHistogramBins * 2 - 1)), cv::FILLED);
  }
  cv::rectangle(img, {kMarginLeft - 1, kMarginTop - 1},
                {kMarginLeft + bar * kHistogramBins, kMarginTop + h}, kBlack);
  auto x_of = [&](double v) {
    return kMarginLeft +
           static_cast<int>(std::lround((v + range) / (2 * range) * bar * kHistogramBins));
  };
  for (double t : {-r.tolerance, r.tolerance}) {
    if (std::abs(t) < range)
      cv::line(img, {x_of(t), kMarginTop}, {x_of(t), kMarginTop + h}, kGreen);
  }
  for (int k = -2; k <= 2; ++k) {
    const double v = range * k / 2;
    cv::line(img, {x_of(v), kMarginTop + h}, {x_of(v), kMarginTop + h + 5}, kBlack);
    Text(&img, FormatPrintf("%g", v), x_of(v) - 15, kMarginTop + h + 22);
  }
  Text(&img, std::to_string(peak), 5, kMarginTop + 10);
  Text(&img, "0", 5, kMarginTop + h);
  Text(&img, "points", 5, kMarginTop + h / 2);
  Text(&img, "per bin", 5, kMarginTop + h / 2 + 16);
  Text(&img, "dz = Z - Z_ref" + Unit(r, true), kMarginLeft + w / 2 - 70, kMarginTop + h + 42);
  Text(&img, "dz of " + std::to_string(n) + " checkpoints (no threshold)", kMarginLeft, 22, 0.55);
  Text(&img,
       "values beyond +-" + FormatPrintf("%g", range) +
           " are counted in the end bins; green: +-tolerance " + FormatPrintf("%g", r.tolerance),
       kMarginLeft, 44);
  return img;
}

cv::Mat ErrorMap(const EvaluationReport& r, double range) {
  const MapFrame frame(r.points);
  cv::Mat img = frame.Canvas(Unit(r, false));
  cv::Mat sum(frame.height, frame.width, CV_64F, cv::Scalar(0));
  cv::Mat count = sum.clone(), no_reference = sum.clone();
  for (size_t i = 0; i < r.points.size(); ++i) {
    const cv::Point p = frame.Pixel(r.points[i]) - cv::Point(kMarginLeft, kMarginTop);
    if (std::isfinite(r.dz[i])) {
      sum.at<double>(p) += r.dz[i];
      count.at<double>(p) += 1;
    } else {
      no_reference.at<double>(p) += 1;
    }
  }
  const Blocks dz = MergeIntoBlocks(sum, count);
  const cv::Mat missing = BlockSums(no_reference, dz.f);
  for (int y = 0; y < frame.height; ++y) {
    for (int x = 0; x < frame.width; ++x) {
      cv::Vec3b& px = img.at<cv::Vec3b>(kMarginTop + y, kMarginLeft + x);
      if (const double c = dz.Count(x, y); c > 0.5) {
        px = Diverging(dz.Sum(x, y) / c / range);
      } else if (missing.at<double>(y / dz.f, x / dz.f) > 0.5) {
        px = cv::Vec3b(120, 120, 120);
      }
    }
  }
  // The colour bar, +range at the top.
  const int x0 = kMarginLeft + frame.width + 30, bar_h = std::max(100, frame.height);
  if (img.rows < kMarginTop + bar_h + kMarginBottom) {
    cv::copyMakeBorder(img, img, 0, kMarginTop + bar_h + kMarginBottom - img.rows, 0, 0,
                       cv::BORDER_CONSTANT, kWhite);
  }
  for (int y = 0; y < bar_h; ++y) {
    const double t = 1 - 2.0 * y / (bar_h - 1);
    cv::line(img, {x0, kMarginTop + y}, {x0 + 20, kMarginTop + y}, cv::Scalar(Diverging(t)));
  }
  cv::rectangle(img, {x0 - 1, kMarginTop - 1}, {x0 + 21, kMarginTop + bar_h}, kBlack);
  for (int k = -2; k <= 2; ++k) {
    const int y = kMarginTop + static_cast<int>(std::lround((bar_h - 1) * (2 - k) / 4.0));
    cv::line(img, {x0 + 21, y}, {x0 + 26, y}, kBlack);
    Text(&img, FormatPrintf("%+g", range * k / 2), x0 + 30, y + 5);
  }
  Text(&img, "dz" + Unit(r, true), x0 - 10, kMarginTop - 10);
  Text(&img,
       "mean dz per " + FormatPrintf("%.3g", dz.f / frame.scale) + " " + LengthLabel(r.unit) +
           " cell, clipped to +-" + FormatPrintf("%g", range),
       kMarginLeft, 22, 0.55);
  Text(&img, "dark grey: no reference height", kMarginLeft, 44);
  return img;
}

cv::Mat PseudoErrorMap(const EvaluationReport& r) {
  double t = r.tolerance;
  std::string what = "|dz| > tolerance " + FormatPrintf("%g", t) + " (no --drop-above given)";
  if (r.rows.size() > 1) {
    t = 0;
    for (size_t i = 1; i < r.rows.size(); ++i) t = std::max(t, r.rows[i].threshold);
    what =
        "|dz| > " + FormatPrintf("%g", t) + ", dropped as pseudo-errors by the largest threshold";
  }
  const MapFrame frame(r.points);
  cv::Mat img = frame.Canvas(Unit(r, false));
  // Kept and unreferenced points as areas, in blocks as in the dz map.
  cv::Mat kept(frame.height, frame.width, CV_64F, cv::Scalar(0));
  cv::Mat no_reference = kept.clone();
  for (size_t i = 0; i < r.points.size(); ++i) {
    const cv::Point p = frame.Pixel(r.points[i]) - cv::Point(kMarginLeft, kMarginTop);
    if (!std::isfinite(r.dz[i])) {
      no_reference.at<double>(p) += 1;
    } else if (std::abs(r.dz[i]) <= t) {
      kept.at<double>(p) += 1;
    }
  }
  const Blocks blocks = MergeIntoBlocks(kept, kept);
  const cv::Mat missing = BlockSums(no_reference, blocks.f);
  for (int y = 0; y < frame.height; ++y) {
    for (int x = 0; x < frame.width; ++x) {
      cv::Vec3b& px = img.at<cv::Vec3b>(kMarginTop + y, kMarginLeft + x);
      if (blocks.Count(x, y) > 0.5) {
        px = cv::Vec3b(190, 190, 190);
      } else if (missing.at<double>(y / blocks.f, x / blocks.f) > 0.5) {
        px = cv::Vec3b(230, 200, 150);
      }
    }
  }
  long marked = 0;
  // Marked points on top, as dots that stay visible when they are few.
  for (size_t i = 0; i < r.points.size(); ++i) {
    if (std::abs(r.dz[i]) > t) {
      cv::circle(img, frame.Pixel(r.points[i]), 2, kRed, cv::FILLED);
      ++marked;
    }
  }
  Text(&img, "red: " + std::to_string(marked) + " points with " + what, kMarginLeft, 22, 0.5);
  Text(&img, "grey: kept checkpoints; light blue: no reference height", kMarginLeft, 44, 0.45,
       kBlue);
  return img;
}

}  // namespace

std::vector<std::filesystem::path> WriteEvaluationPlots(const EvaluationReport& r,
                                                        const std::filesystem::path& dir) {
  if (r.points.empty() || r.points.size() != r.dz.size()) {
    throw Error(dir.string() + ": nothing to plot (the report holds no per-point errors)");
  }
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (!std::filesystem::is_directory(dir)) {
    throw Error(dir.string() + ": cannot create the plots folder" +
                (ec ? " (" + ec.message() + ")" : std::string()));
  }
  const double range = ErrorRange(r);
  const std::vector<std::filesystem::path> paths = {dir / "dz_histogram.png", dir / "dz_map.png",
                                                    dir / "pseudo_errors.png"};
  WritePng(paths[0], Histogram(r, range));
  WritePng(paths[1], ErrorMap(r, range));
  WritePng(paths[2], PseudoErrorMap(r));
  return paths;
}

}  // namespace sapmvs
