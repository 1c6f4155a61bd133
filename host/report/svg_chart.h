#pragma once
// Horizontal bar charts as inline SVG: a report that opens offline and
// without scripts draws its charts itself.
#include <string>
#include <vector>

namespace sapmvs {

struct BarChart {
  struct Series {
    std::string name;
    std::string colour;          // CSS colour
    std::vector<double> values;  // one per label; NaN or < 0: no bar
  };
  std::string unit;  // after each value, e.g. " s"
  std::vector<std::string> labels;
  std::vector<Series> series;
  int decimals = 1;
};

// The chart as an <svg> element: one row per label, one bar per series in
// it, a value at each bar's end, a legend when there are several series.
std::string BarChartSvg(const BarChart& chart);

}  // namespace sapmvs
