#pragma once
// Topology checks and counts for polygon meshes: the contract every stage
// after extraction relies on (2-manifold, consistently oriented).
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/mesh.h"

namespace isowave {

struct TopologySummary {
  std::size_t vertices = 0;
  std::size_t edges = 0;
  std::size_t faces = 0;
  std::size_t boundary_edges = 0;
  std::size_t boundary_loops = 0;
  std::size_t components = 0;
  long long euler_characteristic = 0;  // V - E + F
  // Sum over components of g_c, where chi_c = 2 - 2 g_c - b_c.
  long long genus = 0;

  // Every count is additive over disjoint components (summarize_components).
  TopologySummary& operator+=(const TopologySummary& other) {
    vertices += other.vertices;
    edges += other.edges;
    faces += other.faces;
    boundary_edges += other.boundary_edges;
    boundary_loops += other.boundary_loops;
    components += other.components;
    euler_characteristic += other.euler_characteristic;
    genus += other.genus;
    return *this;
  }
};

// Throws Error(Topology), naming `source` and the first offending vertex, edge
// or face, unless the mesh is a consistently oriented 2-manifold, possibly with
// boundary: no face with fewer than 3 or with repeated vertices, every edge in
// one or two faces with opposite directions, the faces around every vertex one
// fan, no unreferenced vertex, at least one face. O(n log n).
void require_manifold(const PolygonMesh& mesh, const std::string& source);

// Counts for a mesh that passed require_manifold(). O(n log n).
TopologySummary summarize_topology(const PolygonMesh& mesh);

// The counts of every connected component (components joined through shared
// vertices, in order of first face; each entry has components = 1), and each
// face's component in `face_component` if given. For a mesh that passed
// require_manifold(); the entries add up to summarize_topology()'s counts
// (genus included), so a caller can total any subset of the components
// without recounting. O(n log n).
std::vector<TopologySummary> summarize_components(const PolygonMesh& mesh,
                                                  std::vector<std::uint32_t>* face_component = nullptr);

// Component index per face (0-based, in order of first face), for a mesh that
// passed require_manifold(); components are joined through shared vertices.
std::vector<std::uint32_t> face_components(const PolygonMesh& mesh, std::size_t* component_count);

}  // namespace isowave
