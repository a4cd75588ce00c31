#pragma once
// View-dependent refinement (issue #48, item 2; Linsen et al.'s
// distance-scaled criterion): each base face is refined to the coarsest level
// whose omitted detail projects to at most a given number of pixels from the
// camera, faces outside the view frustum stay base faces, and the faces meet
// crack-free (transform/adaptive_mesh.h). The camera is ParaView's and
// three.js's: position, target, up, vertical field of view, viewport.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "isowave/codec/camera.h"
#include "isowave/codec/isw_format.h"
#include "isowave/core/mesh.h"
#include "isowave/core/vec3.h"

namespace isowave {

struct ViewLevels {
  std::vector<int> levels;       // per base face, 0..L
  std::size_t culled = 0;        // base faces outside the frustum (level 0)
  std::size_t back_facing = 0;   // base faces facing away, with BackFaces::Cull (level 0)
};

// What a view does with base faces that face away from the camera.
enum class BackFaces {
  Refine,  // as any other face (the default: an isosurface may be seen from either side)
  // Level 0 where every point of the face's patch faces away (its normal cone,
  // widened by the angle its box subtends from the camera, lies behind): for
  // a closed surface seen from outside, as a renderer culling back faces
  // shows it (Linsen et al.; the normals are the mesh's orientation).
  Cull,
};

// Per base face of `decoded` (a decode: hierarchy and coefficients, all of
// them or, read with options.frustum, those the frustum needs; `fine` its
// level-L control points): the coarsest level l such that the
// detail above it, sum over levels m > l of the largest class weight times
// coefficient magnitude among the level-m coefficients of the face (a level-m
// edge's coefficient counts for both faces along it), projects to at most
// `pixel_error` (> 0) pixels at the distance from the camera to the box of
// the face's fine points (a box holding the camera: the finest level); level
// 0 outside the frustum, and for faces facing away with BackFaces::Cull. A
// nearer camera never gives a coarser level to a face inside the frustum
// (and not culled). Error(InvalidArgument) for a decode without a hierarchy
// or a pixel error that is not positive. Cost: O(fine vertices).
ViewLevels view_face_levels(const IswDecoded& decoded, const std::vector<Vec3>& fine, const Camera& camera,
                            double pixel_error, BackFaces back_faces = BackFaces::Refine);

// For interactive use (issue #48, item 6): a decode synthesized once, then
// refined or coarsened as the camera moves. Each set_view() costs O(base
// faces) of arithmetic on what the constructor kept (each face's box and the
// detail each level leaves out) and returns the base faces whose polygons
// changed, so a viewer holding points() as one vertex buffer re-emits only
// those patches. Not thread-safe; the decode may be dropped afterwards.
class ViewRefiner {
 public:
  // `decoded`: a decode (all of it, or read with options.frustum for a first
  // camera near those it will move to). Error(InvalidArgument) without a
  // hierarchy. Cost: one synthesis and O(fine vertices); keeps the fine
  // control points and 11 + L doubles per base face. Every face starts at 0.
  explicit ViewRefiner(const IswDecoded& decoded);
  ~ViewRefiner();
  ViewRefiner(ViewRefiner&&) noexcept;
  ViewRefiner& operator=(ViewRefiner&&) noexcept;

  // The levels of view_face_levels() for this camera; returns, ascending,
  // the base faces whose patch changed: those whose level changed and their
  // neighbours across base edges (their transition polygons). Errors as
  // view_face_levels().
  std::vector<std::uint32_t> set_view(const Camera& camera, double pixel_error,
                                      BackFaces back_faces = BackFaces::Refine);
  const ViewLevels& levels() const;
  // The fine control points: patch() indices refer to them.
  const std::vector<Vec3>& points() const;
  // Base face f's polygons at its level (adaptive_patch()): corners appended
  // to `corners`, each polygon's end to `offsets`.
  void patch(std::size_t base_face, std::vector<std::uint32_t>& offsets, std::vector<std::uint32_t>& corners) const;
  // The whole crack-free mesh (adaptive_control_mesh(): the vertices used only).
  PolygonMesh mesh() const;

 private:
  struct Data;
  std::unique_ptr<Data> data_;
};

// What a view decode writes (decode --view, Python's decode(view=...)): the
// crack-free mesh of view_face_levels() (adaptive_control_mesh, the vertices
// it uses only); `report` (optional) receives the levels. Cost: one synthesis.
PolygonMesh view_mesh(const IswDecoded& decoded, const Camera& camera, double pixel_error,
                      ViewLevels* report = nullptr, BackFaces back_faces = BackFaces::Refine);

}  // namespace isowave
