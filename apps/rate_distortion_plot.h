#pragma once
// The plot of `isowave stats --plot`: RMSE in percent of the cell edge
// against the percent of coefficients kept, as a standalone SVG file.
#include <string>
#include <vector>

#include "isowave/codec/statistics.h"

namespace isowave::cli {

// `rows` as rate_distortion() returns them, `cell` the cell edge (world
// units, > 0). The curve runs through the rows in increasing percent; the
// base mesh is one point labelled "base mesh" (rows at or below its share
// give the same reconstruction and are not drawn again). Both axes start at
// 0 and carry round ticks (nice_ticks). The title is escaped for XML.
std::string rate_distortion_svg(const std::vector<RateDistortionRow>& rows, double cell, const std::string& title);

// 0, s, 2s, ... up to the first multiple of s at or above `max` (> 0), with
// s from the 1-2-5 series (..., 0.5, 1, 2, 5, 10, ...) the smallest that
// needs at most `max_intervals` (>= 1) intervals.
std::vector<double> nice_ticks(double max, int max_intervals);

}  // namespace isowave::cli
