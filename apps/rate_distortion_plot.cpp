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

// The rows to draw: one per distinct reconstruction, in increasing percent.
std::vector<RateDistortionRow> distinct_rows(const std::vector<RateDistortionRow>& rows) {
  std::size_t base_kept = 0;
  for (const RateDistortionRow& r : rows)
    if (r.is_base) base_kept = r.kept;
  std::vector<RateDistortionRow> distinct;
  for (const RateDistortionRow& r : rows)
    if (r.is_base || r.kept != base_kept) distinct.push_back(r);
  std::sort(distinct.begin(), distinct.end(), [](const auto& a, const auto& b) { return a.percent < b.percent; });
  distinct.erase(std::unique(distinct.begin(), distinct.end(), [](const auto& a, const auto& b) { return a.kept == b.kept; }),
                 distinct.end());
  return distinct;
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

std::string plot_svg(const Plot& plot) {
  std::vector<PlotPoint> points;
  for (const PlotPoint& p : plot.points)
    if (std::isfinite(p.x) && std::isfinite(p.y)) points.push_back(p);
  const double width = 640, height = 420, left = 70, right = 20, top = 40, bottom = 60;
  double max_x = 0, max_y = 0;
  for (const PlotPoint& p : points) {
    max_x = std::max(max_x, p.x);
    max_y = std::max(max_y, p.y);
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
  svg += buffer + xml_escaped(plot.title) + "</text>\n";
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
  std::snprintf(buffer, sizeof buffer, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">", (left + width - right) / 2,
                height - 18);
  svg += buffer + xml_escaped(plot.x_label) + "</text>\n";
  std::snprintf(buffer, sizeof buffer, "<text x=\"18\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 18 %.1f)\">",
                (top + height - bottom) / 2, (top + height - bottom) / 2);
  svg += buffer + xml_escaped(plot.y_label) + "</text>\n";
  svg += "<polyline fill=\"none\" stroke=\"#1f5fbf\" stroke-width=\"2\" points=\"";
  for (const PlotPoint& p : points) {
    std::snprintf(buffer, sizeof buffer, "%.1f,%.1f ", x(p.x), y(p.y));
    svg += buffer;
  }
  svg += "\"/>\n";
  for (const PlotPoint& p : points) {
    std::snprintf(buffer, sizeof buffer, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"3.5\" fill=\"#1f5fbf\"/>\n", x(p.x), y(p.y));
    svg += buffer;
    if (p.label.empty()) continue;
    // Right of the point, or above and left of it in the right half (inside the plot).
    const bool right_half = x(p.x) > (left + width - right) / 2;
    std::snprintf(buffer, sizeof buffer, "<text x=\"%.1f\" y=\"%.1f\"%s>", x(p.x) + (right_half ? -8 : 8),
                  y(p.y) + (right_half ? -8 : 4), right_half ? " text-anchor=\"end\"" : "");
    svg += buffer + xml_escaped(p.label) + "</text>\n";
  }
  svg += "</svg>\n";
  return svg;
}

Plot truncation_plot(const std::vector<RateDistortionRow>& rows, double cell, const std::string& y_unit,
                     const std::string& title) {
  Plot plot{title, "coefficients kept [% of full resolution]", "RMSE [" + y_unit + "]", {}};
  for (const RateDistortionRow& r : distinct_rows(rows))
    plot.points.push_back({r.percent, 100 * r.rms / cell, r.is_base ? "base mesh" : ""});
  return plot;
}

}  // namespace isowave::cli
