#include "opensubdiv_bridge.h"

#include <opensubdiv/far/topologyDescriptor.h>
#include <opensubdiv/sdc/crease.h>

#include "isowave/core/error.h"

namespace isowave::detail {

using namespace OpenSubdiv;

std::unique_ptr<Far::TopologyRefiner> make_refiner(const PolygonMesh& base) {
  std::vector<int> sizes(base.face_count());
  for (std::size_t f = 0; f < base.face_count(); ++f) sizes[f] = static_cast<int>(base.face_size(f));
  std::vector<int> indices(base.face_vertices.begin(), base.face_vertices.end());
  std::vector<int> corners;
  for (std::size_t v = 0; v < base.vertex_count(); ++v)
    if (base.is_sharp(v)) corners.push_back(static_cast<int>(v));
  std::vector<float> corner_weights(corners.size(), Sdc::Crease::SHARPNESS_INFINITE);

  Far::TopologyDescriptor descriptor;
  descriptor.numVertices = static_cast<int>(base.vertex_count());
  descriptor.numFaces = static_cast<int>(base.face_count());
  descriptor.numVertsPerFace = sizes.data();
  descriptor.vertIndicesPerFace = indices.data();
  descriptor.numCorners = static_cast<int>(corners.size());
  descriptor.cornerVertexIndices = corners.data();
  descriptor.cornerWeights = corner_weights.data();

  Sdc::Options sdc_options;
  sdc_options.SetVtxBoundaryInterpolation(Sdc::Options::VTX_BOUNDARY_EDGE_ONLY);
  using Factory = Far::TopologyRefinerFactory<Far::TopologyDescriptor>;
  std::unique_ptr<Far::TopologyRefiner> refiner(
      Factory::Create(descriptor, Factory::Options(Sdc::SCHEME_CATMARK, sdc_options)));
  if (!refiner) throw Error(ErrorKind::Topology, "OpenSubdiv rejected the base mesh topology");
  return refiner;
}

}  // namespace isowave::detail
