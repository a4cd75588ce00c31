#pragma once
// The preparation every fit starts from (Bertram et al. 2000, Sec. 4 and
// 4.2): load the volume, pre-filter it if asked, extract the isosurface, and
// compute the signed-distance field of the field the surface came from.
// convert_volume(), the fit command, bench_fit and the fit tests all start
// here, so the field the shrink-wrap searches is always the one the surface
// was extracted from.
#include <cstddef>
#include <string>

#include "isowave/core/progress.h"
#include "isowave/core/volume.h"
#include "isowave/extract/isosurface.h"
#include "isowave/extract/volume_io.h"
#include "isowave/fit/signed_distance.h"

namespace isowave {

struct PrepareOptions {
  // Isovalue, orientation, component clean-up and the Gaussian pre-filter
  // (smooth_sigma in voxels, 0: none), as extract_isosurface() takes them.
  IsosurfaceOptions extract;
  // Half-width of the signed-distance narrow band in cells (finite, >= 0; 0: the whole grid).
  double distance_band_cells = 3.0;
};

struct PreparedSurface {
  // The field the surface was extracted from: the input, pre-filtered when
  // extract.smooth_sigma > 0 and with the topology tolerance's few samples
  // changed when extract.topology_tolerance > 0 (the input is not kept).
  Volume field;
  // The extracted triangle mesh (world coordinates) and its report;
  // report.smooth_sigma records the pre-filter.
  Isosurface isosurface;
  // Signed distance to the isosurface, world units; empty until
  // prepare_surface() or surface_distance_field() fills it.
  SignedDistanceField distance;
};

// Reads a volume (a file or builtin:NAME[:N]) as the stage "load" of
// `progress`. Throws what read_volume() throws.
Volume load_volume(const std::string& path, const VolumeReadOptions& options, ProgressSink& progress = no_progress());

// Steps 1-2: the pre-filter (stage "smooth", O(samples * sigma)) and the
// extraction (O(samples + output)); distance left empty. `source` names the
// input in errors. Throws Error(InvalidArgument) for fewer than 2 samples
// along an axis, Error(EmptyResult) for an empty isosurface (the message
// gives the field's value range), and what extract_isosurface() throws.
PreparedSurface extract_surface(Volume volume, const PrepareOptions& options, const std::string& source,
                                ProgressSink& progress = no_progress());

// Step 3: the signed-distance field of prepared.field, seeded from its
// extracted mesh (compute_signed_distance(); O(band nodes) plus a queue).
SignedDistanceField surface_distance_field(const PreparedSurface& prepared, const PrepareOptions& options,
                                           ProgressSink& progress = no_progress());

// Steps 1-3: extract_surface() and surface_distance_field().
PreparedSurface prepare_surface(Volume volume, const PrepareOptions& options, const std::string& source,
                                ProgressSink& progress = no_progress());

}  // namespace isowave
