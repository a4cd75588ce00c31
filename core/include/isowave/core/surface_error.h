#pragma once
// The surface error D between two meshes (issue #33): the distance from each
// surface to the other, sampled uniformly over the area of both, the
// symmetric measure MPEG uses for meshes (point-to-surface "D1" both ways).
// What a user gets back is a decoded surface, so this is the error that
// counts; distances of vertices alone miss faces that fold or bridge a gap,
// whose corners lie on the surface while their interiors do not.
//
// All distances are exact (BinnedSurfaceDistance) and in the meshes' world
// units; callers divide by Volume::cell_size() for cells. Polygons are fanned
// into triangles from their first vertex, as everywhere in isowave.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "isowave/core/binned_surface_distance.h"
#include "isowave/core/mesh.h"
#include "isowave/core/point_set_distance.h"
#include "isowave/core/vec3.h"

namespace isowave {

// `count` points distributed uniformly over the area of `mesh` (faces fanned
// from their first vertex; a triangle of zero or non-finite area gets none).
// Sample i depends only on (seed, i): the result is the same for any thread
// count. Parallel (TBB); O(triangles + count log count) time, about 40
// bytes per sample and nothing per triangle. Throws Error(InvalidArgument) for a mesh
// without a triangle of positive finite area.
std::vector<Vec3> area_samples(const PolygonMesh& mesh, std::size_t count, std::uint64_t seed);

// RMS and maximum distance, world units, both ways between two surfaces.
struct SurfaceError {
  double forward_rms = 0, forward_max = 0;    // samples on the mesh to the reference's surface
  double backward_rms = 0, backward_max = 0;  // samples on the reference to the mesh's surface
  // D: the larger of the two RMS values.
  double d() const { return forward_rms > backward_rms ? forward_rms : backward_rms; }
};

// D between `mesh` and `reference` from `samples` (>= 1) area-uniform samples
// on each (fixed seeds: deterministic, and the same for any thread count).
// The samples on `mesh` go to a BinnedSurfaceDistance of the reference,
// the reference's samples to `mesh` through a PointSetDistance (nothing
// stored per triangle of `mesh`): time about linear in the triangles plus
// the samples, memory about 40 bytes per triangle of the reference and per
// sample. Throws Error(InvalidArgument) for samples == 0, a mesh without
// area (see area_samples()) or with a non-finite position.
SurfaceError surface_error(const PolygonMesh& mesh, const PolygonMesh& reference, std::size_t samples = 200000);

// The same against one reference for many meshes (convert's levels and
// summary rows): the reference's samples and distance bins are made once.
// measure(mesh) equals surface_error(mesh, reference, samples). The
// reference is not kept. Errors as surface_error().
class SurfaceErrorReference {
 public:
  explicit SurfaceErrorReference(const PolygonMesh& reference, std::size_t samples = 200000);
  SurfaceError measure(const PolygonMesh& mesh) const;

  std::size_t samples() const { return samples_; }
  // The two directions apart, for callers that sample a mesh themselves:
  // the distance (world units) from each of `points` (finite) to the
  // reference's surface, in order (measure()'s forward distances for its
  // own samples), and the RMS and maximum distance of the reference's
  // samples to `mesh` (measure()'s backward direction). Errors as measure().
  std::vector<double> distances_to_reference(const std::vector<Vec3>& points) const;
  void backward(const PolygonMesh& mesh, double& rms, double& max) const;
  // The same reference with fewer samples each way (1..samples()): its
  // measure(mesh) equals surface_error(mesh, reference, fewer), whose samples
  // are the first `fewer` of this one's on both surfaces (sample i depends
  // only on the seed and i), so the two measures share their samples. The
  // reference's distance bins are shared, not built again. Cost:
  // O(fewer). Throws Error(InvalidArgument) for a count outside 1..samples().
  SurfaceErrorReference with_first_samples(std::size_t fewer) const;

 private:
  SurfaceErrorReference(PointSetDistance reference_samples, double area,
                        std::shared_ptr<const BinnedSurfaceDistance> distance);
  static SurfaceErrorReference built(const PolygonMesh& reference, std::size_t samples);

  std::size_t samples_;
  PointSetDistance reference_samples_;                    // the backward direction, against each mesh
  double area_ = 0;                                       // the reference's, which spaces its samples
  std::shared_ptr<const BinnedSurfaceDistance> distance_;  // the forward direction, from each mesh's samples
};

}  // namespace isowave
