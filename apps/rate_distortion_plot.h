#pragma once
// The plots of `isowave stats --plot`, as standalone SVG files: one writer
// for a curve of points, and the two curves stats draws with it (the paper's
// RMSE against percent kept; D against bits per vertex for an embedded stream).
#include <string>
#include <vector>

#include "isowave/codec/statistics.h"

namespace isowave::cli {

struct PlotPoint {
  double x = 0, y = 0;  // data units, >= 0; a point with a coordinate that is not finite is not drawn
  std::string label;    // drawn beside the point when not empty
};

struct Plot {
  std::string title, x_label, y_label;  // plain text (escaped for XML when written)
  std::vector<PlotPoint> points;        // joined in this order, each drawn as a circle
};

// The plot as SVG: both axes start at 0 and carry round ticks (nice_ticks)
// up to the largest coordinate (1 when there is none above 0).
std::string plot_svg(const Plot& plot);

// The paper's truncation curve: RMSE (rows' rms / cell x 100, `y_unit` in the
// axis label) against the percent of coefficients kept. `rows` as
// error_table() returns them, `cell` > 0 in world units; one point per
// distinct reconstruction in increasing percent, the base mesh one point
// labelled "base mesh" (rows at or below its share give the same reconstruction).
Plot truncation_plot(const std::vector<RateDistortionRow>& rows, double cell, const std::string& y_unit,
                     const std::string& title);

// 0, s, 2s, ... up to the first multiple of s at or above `max` (> 0), with
// s from the 1-2-5 series (..., 0.5, 1, 2, 5, 10, ...) the smallest that
// needs at most `max_intervals` (>= 1) intervals.
std::vector<double> nice_ticks(double max, int max_intervals);

}  // namespace isowave::cli
