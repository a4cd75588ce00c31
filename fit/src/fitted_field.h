#pragma once
// The trilinear field as the shrink-wrap's searches see it, for the stand-
// alone steps and the fit's report: the volume's samples, with non-finite
// ones filled (fill_non_finite_samples) in a copy made only when there are
// any (a scan of the samples otherwise).
#include <algorithm>
#include <cmath>
#include <vector>

#include "isowave/core/volume.h"
#include "isowave/fit/signed_distance.h"
#include "isowave/fit/trilinear.h"

namespace isowave::detail {

class FittedField {
 public:
  // Keeps a pointer to `field`'s samples when they are all finite: the
  // volume must outlive this.
  FittedField(const Volume& field, double iso)
      : filled_(filled_values(field, iso)), grid_(field, filled_.empty() ? field.values.data() : filled_.data()) {}
  FittedField(const FittedField&) = delete;
  FittedField& operator=(const FittedField&) = delete;

  const TrilinearGrid& grid() const { return grid_; }

 private:
  static std::vector<float> filled_values(const Volume& field, double iso) {
    if (std::all_of(field.values.begin(), field.values.end(), [](float f) { return std::isfinite(f); })) return {};
    std::vector<float> values = field.values;
    fill_non_finite_samples(field, iso, values.data());
    return values;
  }

  std::vector<float> filled_;
  TrilinearGrid grid_;
};

}  // namespace isowave::detail
