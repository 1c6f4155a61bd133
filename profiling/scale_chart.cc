// scale_chart: the chart of profiling/results/scale.md, from the CSV that
// profiling/scale_runs.sh writes: wall and CPU time per image, and peak RSS,
// against the block's images, each panel with its own axis from 0. CPU time
// is drawn beside wall time because the machine is shared: a run that gets
// half the cores shows it in wall time only.
//
//   ./build/profiling/scale_chart profiling/results/scale.csv profiling/results/scale.png

#include <algorithm>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <sstream>
#include <string>
#include <vector>

namespace {

struct Row {
  double images = 0, seconds_per_image = 0, cpu_seconds_per_image = 0, peak_rss_mib = 0;
};

// Columns by header name: images, seconds_per_image, cpu_seconds_per_image,
// peak_rss_mib.
std::vector<Row> ReadCsv(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path + ": cannot read");
  std::string line;
  std::getline(in, line);
  std::vector<std::string> names;
  for (std::stringstream s(line); std::getline(s, line, ',');) names.push_back(line);
  auto column = [&](const std::string& name) {
    const auto it = std::find(names.begin(), names.end(), name);
    if (it == names.end()) throw std::runtime_error(path + ": expected a column " + name);
    return static_cast<size_t>(it - names.begin());
  };
  const size_t ci = column("images"), ct = column("seconds_per_image"),
               cc = column("cpu_seconds_per_image"), cr = column("peak_rss_mib");
  std::vector<Row> rows;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    std::vector<std::string> f;
    for (std::stringstream s(line); std::getline(s, line, ',');) f.push_back(line);
    if (f.size() != names.size()) {
      throw std::runtime_error(path + ":" + std::to_string(number) + ": expected " +
                               std::to_string(names.size()) + " fields");
    }
    rows.push_back({std::stod(f[ci]), std::stod(f[ct]), std::stod(f[cc]), std::stod(f[cr])});
  }
  if (rows.empty()) throw std::runtime_error(path + ": no rows");
  return rows;
}

std::string Label(double v, int decimals) {
  char b[32];
  std::snprintf(b, sizeof(b), "%.*f", decimals, v);
  return b;
}

struct Series {
  double Row::*value;
  cv::Scalar colour;
  std::string name;  // in the legend; empty for none
};

void Panel(cv::Mat* img, int x0, int y0, int w, int h, const std::vector<Row>& rows,
           const std::vector<Series>& series, const std::string& title, int decimals) {
  const cv::Scalar black(0, 0, 0), grey(200, 200, 200);
  cv::rectangle(*img, {x0, y0}, {x0 + w, y0 + h}, grey);
  cv::putText(*img, title, {x0, y0 - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.55, black, 1, cv::LINE_AA);
  double xmax = 0, ymax = 0;
  for (const Row& r : rows) {
    xmax = std::max(xmax, r.images);
    for (const Series& s : series) ymax = std::max(ymax, r.*(s.value));
  }
  xmax *= 1.1;
  ymax *= 1.3;
  auto px = [&](double v) { return x0 + static_cast<int>(v / xmax * w); };
  auto py = [&](double v) { return y0 + h - static_cast<int>(v / ymax * h); };
  for (int t = 0; t <= 4; ++t) {
    const double v = ymax * t / 4;
    cv::line(*img, {x0, py(v)}, {x0 + w, py(v)}, cv::Scalar(235, 235, 235));
    cv::putText(*img, Label(v, decimals), {x0 - 52, py(v) + 4}, cv::FONT_HERSHEY_SIMPLEX, 0.4,
                black, 1, cv::LINE_AA);
  }
  for (const Row& r : rows) {
    cv::putText(*img, Label(r.images, 0), {px(r.images) - 14, y0 + h + 18},
                cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
  }
  for (size_t k = 0; k < series.size(); ++k) {
    const Series& s = series[k];
    for (size_t i = 0; i < rows.size(); ++i) {
      const cv::Point p(px(rows[i].images), py(rows[i].*(s.value)));
      if (i > 0) {
        cv::line(*img, {px(rows[i - 1].images), py(rows[i - 1].*(s.value))}, p, s.colour, 2);
      }
      cv::circle(*img, p, 5, s.colour, cv::FILLED, cv::LINE_AA);
      // The first series labelled above its points, the others below.
      cv::putText(*img, Label(rows[i].*(s.value), decimals), {p.x - 18, p.y + (k == 0 ? -10 : 22)},
                  cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1, cv::LINE_AA);
    }
    if (!s.name.empty()) {
      const int ly = y0 + 18 + 18 * static_cast<int>(k);
      cv::rectangle(*img, {x0 + 10, ly - 10}, {x0 + 22, ly}, s.colour, cv::FILLED);
      cv::putText(*img, s.name, {x0 + 28, ly}, cv::FONT_HERSHEY_SIMPLEX, 0.45, black, 1,
                  cv::LINE_AA);
    }
  }
  cv::putText(*img, "images in the block", {x0 + w / 2 - 70, y0 + h + 40}, cv::FONT_HERSHEY_SIMPLEX,
              0.5, black, 1, cv::LINE_AA);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::cerr << "usage: scale_chart SCALE.csv CHART.png\n";
    return 1;
  }
  try {
    const std::vector<Row> rows = ReadCsv(argv[1]);
    const int w = 380, h = 260, margin = 70;
    cv::Mat img(h + 2 * margin, 2 * w + 3 * margin, CV_8UC3, cv::Scalar(255, 255, 255));
    Panel(&img, margin, margin, w, h, rows,
          {{&Row::seconds_per_image, cv::Scalar(180, 119, 31), "wall"},
           {&Row::cpu_seconds_per_image, cv::Scalar(44, 160, 44), "CPU (user + system)"}},
          "time per image, s", 3);
    Panel(&img, 2 * margin + w, margin, w, h, rows,
          {{&Row::peak_rss_mib, cv::Scalar(14, 127, 255), ""}}, "peak RSS, MiB", 0);
    if (!cv::imwrite(argv[2], img))
      throw std::runtime_error(std::string(argv[2]) + ": cannot write");
  } catch (const std::exception& e) {
    std::cerr << "scale_chart: " << e.what() << "\n";
    return 1;
  }
  return 0;
}
