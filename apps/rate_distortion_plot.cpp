#include "rate_distortion_plot.h"

#include <algorithm>
#include <cassert>
#include <cmath>
#include <cstdio>

namespace isowave::cli {
namespace {

std::string xml_escaped(const std::string& text) {
  std::string out;
  for (const char c : text) {
    if (c == '&') out += "&amp;";
    else if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '"') out += "&quot;";
    else out += c;
  }
  return out;
}

// The points to draw: one per distinct reconstruction, in increasing percent.
std::vector<RateDistortionRow> distinct_points(const std::vector<RateDistortionRow>& rows) {
  std::size_t base_kept = 0;
  for (const RateDistortionRow& r : rows)
    if (r.is_base) base_kept = r.kept;
  std::vector<RateDistortionRow> points;
  for (const RateDistortionRow& r : rows)
    if (r.is_base || r.kept != base_kept) points.push_back(r);
  std::sort(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.percent < b.percent; });
  points.erase(std::unique(points.begin(), points.end(), [](const auto& a, const auto& b) { return a.kept == b.kept; }),
               points.end());
  return points;
}

}  // namespace

std::vector<double> nice_ticks(double max, int max_intervals) {
  assert(max > 0 && max_intervals >= 1);
  const double raw = max / max_intervals;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * magnitude;
  for (const double m : {1.0, 2.0, 5.0})
    if (m * magnitude >= raw * (1 - 1e-12)) {
      step = m * magnitude;
      break;
    }
  const int intervals = static_cast<int>(std::ceil(max / step * (1 - 1e-12)));
  std::vector<double> ticks;
  for (int k = 0; k <= intervals; ++k) ticks.push_back(k * step);
  return ticks;
}

std::string rate_distortion_svg(const std::vector<RateDistortionRow>& rows, double cell, const std::string& title) {
  const std::vector<RateDistortionRow> points = distinct_points(rows);
  const double width = 640, height = 420, left = 70, right = 20, top = 40, bottom = 60;
  const auto error = [&](const RateDistortionRow& r) { return 100 * r.rms / cell; };
  double max_x = 0, max_y = 0;
  for (const RateDistortionRow& r : points) {
    if (std::isfinite(r.percent)) max_x = std::max(max_x, r.percent);
    if (std::isfinite(error(r))) max_y = std::max(max_y, error(r));
  }
  const std::vector<double> x_ticks = nice_ticks(max_x > 0 ? max_x : 1, 5);
  const std::vector<double> y_ticks = nice_ticks(max_y > 0 ? max_y : 1, 5);
  const auto x = [&](double v) { return left + (width - left - right) * v / x_ticks.back(); };
  const auto y = [&](double v) { return height - bottom - (height - top - bottom) * v / y_ticks.back(); };
  char buffer[512];
  std::string svg = "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n";
  std::snprintf(buffer, sizeof buffer,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" font-family=\"sans-serif\" "
                "font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
                width, height);
  svg += buffer;
  std::snprintf(buffer, sizeof buffer, "<text x=\"%.0f\" y=\"22\" text-anchor=\"middle\" font-size=\"14\">", width / 2);
  svg += buffer + xml_escaped(title) + "</text>\n";
  std::snprintf(buffer, sizeof buffer,
                "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>\n"
                "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>\n",
                left, y(0), width - right, y(0), left, y(0), left, top);
  svg += buffer;
  for (const double v : x_ticks) {
    std::snprintf(buffer, sizeof buffer,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"black\"/>"
                  "<text class=\"x-tick\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%g</text>\n",
                  x(v), y(0), x(v), y(0) + 5, x(v), y(0) + 20, v);
    svg += buffer;
  }
  for (const double v : y_ticks) {
    std::snprintf(buffer, sizeof buffer,
                  "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#ddd\"/>"
                  "<text class=\"y-tick\" x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n",
                  left, y(v), width - right, y(v), left - 6, y(v) + 4, v);
    svg += buffer;
  }
  std::snprintf(buffer, sizeof buffer,
                "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">coefficients kept [%% of full resolution]</text>\n"
                "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 18 %.1f)\">RMSE [%% of cell "
                "edge]</text>\n",
                (left + width - right) / 2, height - 18, (top + height - bottom) / 2, (top + height - bottom) / 2);
  svg += buffer;
  svg += "<polyline fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\" points=\"";
  for (const RateDistortionRow& r : points) {
    std::snprintf(buffer, sizeof buffer, "%.1f,%.1f ", x(r.percent), y(error(r)));
    svg += buffer;
  }
  svg += "\"/>\n";
  for (const RateDistortionRow& r : points) {
    std::snprintf(buffer, sizeof buffer, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3.5\" fill=\"#1f5fbf\"/>\n", x(r.percent),
                  y(error(r)));
    svg += buffer;
    if (!r.is_base) continue;
    std::snprintf(buffer, sizeof buffer, "<text x=\"%.1f\" y=\"%.1f\">base mesh</text>\n", x(r.percent) + 8,
                  y(error(r)) + 4);
    svg += buffer;
  }
  svg += "</svg>\n";
  return svg;
}

}  // namespace isowave::cli
