#include "isowave/pipeline/prepare.h"

#include "isowave/core/error.h"
#include "isowave/extract/volume_summary.h"

namespace isowave {

Volume load_volume(const std::string& path, const VolumeReadOptions& options, ProgressSink& progress) {
  progress.begin_stage("load");
  Volume volume = read_volume(path, options);
  progress.end_stage();
  return volume;
}

PreparedSurface extract_surface(Volume volume, const PrepareOptions& options, const std::string& source,
                                ProgressSink& progress) {
  if (volume.dims[0] < 2 || volume.dims[1] < 2 || volume.dims[2] < 2)
    throw Error(ErrorKind::InvalidArgument, source + ": extraction needs at least 2 samples along each axis");
  PreparedSurface prepared;
  // The pre-filtered field replaces the input: the fit searches the field the surface came from.
  const double sigma = options.extract.smooth_sigma;
  if (sigma > 0) {
    progress.begin_stage("smooth");
    prepared.field = gaussian_smoothed(volume, sigma);
    progress.end_stage();
    volume = Volume{};
  } else {
    prepared.field = std::move(volume);
  }
  IsosurfaceOptions extract_options = options.extract;
  extract_options.smooth_sigma = 0;  // applied above
  prepared.isosurface = extract_isosurface_in_place(prepared.field, extract_options, progress);
  prepared.isosurface.report.smooth_sigma = sigma;
  if (prepared.isosurface.mesh.face_count() == 0)
    throw empty_isosurface_error(source, options.extract.iso, prepared.field,
                                 prepared.isosurface.report.topology.changed() ? options.extract.topology_tolerance : 0);
  return prepared;
}

SignedDistanceField surface_distance_field(const PreparedSurface& prepared, const PrepareOptions& options,
                                           ProgressSink& progress) {
  SignedDistanceOptions distance_options;
  distance_options.iso = options.extract.iso;
  distance_options.flip = options.extract.flip;
  distance_options.band_cells = options.distance_band_cells;
  distance_options.surface = &prepared.isosurface.mesh;
  return compute_signed_distance(prepared.field, distance_options, progress);
}

PreparedSurface prepare_surface(Volume volume, const PrepareOptions& options, const std::string& source,
                                ProgressSink& progress) {
  PreparedSurface prepared = extract_surface(std::move(volume), options, source, progress);
  prepared.distance = surface_distance_field(prepared, options, progress);
  return prepared;
}

}  // namespace isowave
