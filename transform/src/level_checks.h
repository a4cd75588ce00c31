#pragma once
// The transform's argument checks and the chunking of its lifting loops,
// shared by the synthesis, the analysis and the synthesis' transpose.
#include <cstdint>
#include <string>
#include <vector>

#include "isowave/core/error.h"
#include "isowave/core/vec3.h"
#include "isowave/transform/hierarchy.h"
#include "parallel_range.h"

namespace isowave::detail {

// Error(InvalidArgument) unless `data` holds the vertex_count(level) entries of `level`.
inline void require_size(const SubdivisionHierarchy& h, const std::vector<Vec3>& data, int level) {
  if (data.size() < h.vertex_count(level))
    throw Error(ErrorKind::InvalidArgument, "wavelet transform needs " + std::to_string(h.vertex_count(level)) +
                                                " points for level " + std::to_string(level) + ", got " +
                                                std::to_string(data.size()));
}

// Error(InvalidArgument) unless `level` is a refinement of the hierarchy, 1..levels().
inline void require_level(const SubdivisionHierarchy& h, int level) {
  if (level < 1 || level > h.levels())
    throw Error(ErrorKind::InvalidArgument, "level " + std::to_string(level) + " is not in 1.." +
                                                std::to_string(h.levels()));
}

// Chunks of the lifting loops.
template <class Body>
void for_lifting_range(std::uint32_t n, const Body& body) {
  parallel_range(n, 8192, body);
}

}  // namespace isowave::detail
