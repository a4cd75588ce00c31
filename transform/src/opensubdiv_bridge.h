#pragma once
// Private: builds OpenSubdiv topology from an isowave mesh. Kept out of the
// public headers so that OpenSubdiv stays an implementation detail.
#include <memory>

#include <opensubdiv/far/topologyRefiner.h>

#include "isowave/core/mesh.h"

namespace isowave::detail {

// Catmull-Clark (CATMARK) topology with VTX_BOUNDARY_EDGE_ONLY boundaries;
// sharp vertices become infinitely sharp corners. `base` must have passed
// require_manifold().
std::unique_ptr<OpenSubdiv::Far::TopologyRefiner> make_refiner(const PolygonMesh& base);

}  // namespace isowave::detail
