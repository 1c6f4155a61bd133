#include "report/svg_chart.h"

#include <algorithm>
#include <cmath>

#include "report/html_text.h"

namespace sapmvs {

std::string BarChartSvg(const BarChart& chart) {
  constexpr int kWidth = 760, kBar = 14, kGap = 8, kLegend = 22, kValueRoom = 90;
  size_t longest = 0;
  for (const std::string& label : chart.labels) longest = std::max(longest, label.size());
  // Labels in a 12 px sans-serif font: about 7 px a character.
  const int label_room = static_cast<int>(std::min<size_t>(longest, 28) * 7 + 12);
  const int plot = kWidth - label_room - kValueRoom;
  double largest = 0;
  for (const auto& s : chart.series) {
    for (double v : s.values) {
      if (std::isfinite(v)) largest = std::max(largest, v);
    }
  }
  const int series = static_cast<int>(chart.series.size());
  const int row = series * kBar + kGap;
  const int top = series > 1 ? kLegend : 4;
  const int height = top + static_cast<int>(chart.labels.size()) * row + 4;
  std::string svg = "<svg class=\"chart\" xmlns=\"http://www.w3.org/2000/svg\" width=\"" +
                    std::to_string(kWidth) + "\" height=\"" + std::to_string(height) +
                    "\" viewBox=\"0 0 " + std::to_string(kWidth) + " " + std::to_string(height) +
                    "\" font-family=\"sans-serif\" font-size=\"12\">";
  if (series > 1) {
    int x = label_room;
    for (const auto& s : chart.series) {
      svg += "<rect x=\"" + std::to_string(x) + "\" y=\"4\" width=\"12\" height=\"12\" fill=\"" +
             HtmlEscape(s.colour) + "\"/><text x=\"" + std::to_string(x + 16) + "\" y=\"14\">" +
             HtmlEscape(s.name) + "</text>";
      x += 24 + static_cast<int>(s.name.size()) * 7;
    }
  }
  for (size_t i = 0; i < chart.labels.size(); ++i) {
    const int y0 = top + static_cast<int>(i) * row;
    std::string label = chart.labels[i];
    if (label.size() > 28) label = label.substr(0, 27) + "…";
    svg += "<text x=\"" + std::to_string(label_room - 6) + "\" y=\"" +
           std::to_string(y0 + series * kBar / 2 + 4) + "\" text-anchor=\"end\">" +
           HtmlEscape(label) + "</text>";
    for (int k = 0; k < series; ++k) {
      const auto& s = chart.series[k];
      const double v = i < s.values.size() ? s.values[i] : NAN;
      if (!(std::isfinite(v) && v >= 0)) continue;
      const double w = largest > 0 ? plot * v / largest : 0;
      const int y = y0 + k * kBar;
      svg += "<rect x=\"" + std::to_string(label_room) + "\" y=\"" + std::to_string(y + 1) +
             "\" width=\"" + Decimal(std::max(w, 0.5), 1) + "\" height=\"" +
             std::to_string(kBar - 2) + "\" fill=\"" + HtmlEscape(s.colour) + "\"><title>" +
             HtmlEscape(s.name + ": " + Decimal(v, chart.decimals) + chart.unit) +
             "</title></rect>";
      svg += "<text x=\"" + Decimal(label_room + w + 4, 1) + "\" y=\"" +
             std::to_string(y + kBar - 3) + "\" font-size=\"11\">" +
             HtmlEscape(Decimal(v, chart.decimals) + chart.unit) + "</text>";
    }
  }
  return svg + "</svg>";
}

}  // namespace sapmvs
