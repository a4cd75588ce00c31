// The .isw 2.0 plane stream decoder (docs/FORMAT.md, PLNS): the packets
// through the plane decoder, the local frames of the frame-precision base
// (built meanwhile on another thread), and the world coefficients.
#include <algorithm>
#include <chrono>
#include <cmath>

#include <tbb/task_group.h>

#include "isowave/core/huge_page_vector.h"
#include "bitplane_coder.h"
#include "coefficient_tree.h"
#include "isw2_layout.h"
#include "isw_models.h"

namespace isowave::detail {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) { return std::chrono::duration<double>(Clock::now() - start).count(); }

// The world coefficients from the decoder's step-unit values.
void to_world(const PlaneDecoder& decoder, const CoefficientClasses& layout, const std::vector<std::uint8_t>& classes,
              const V2Scales& scales, const std::vector<Vec3>& frame_base, const std::vector<Vec3>& normals,
              IswDecoded& result) {
  reserve_fresh_on_huge_pages(result.coefficients, layout.fine());
  result.coefficients.resize(layout.fine());
  decoder.values(result.coefficients);  // step units, converted in place
  steps_to_world(classes, scales, frame_base, normals, result.coefficients);
  std::copy(result.coefficients.begin(), result.coefficients.begin() + static_cast<std::ptrdiff_t>(layout.base()),
            result.base.positions.begin());
}

}  // namespace

void decode_plane_stream(const Section& section, const SubdivisionHierarchy& hierarchy,
                         const CoefficientClasses& layout, const V2Scales& scales, std::uint64_t max_stream_bytes,
                         IswDecoded& result) {
  const auto start = Clock::now();
  PayloadReader reader = section.reader();
  const PlaneStream planes = read_planes(reader, section.payload, section.cut, max_stream_bytes);
  if (planes.packets_total > 0 && planes.layout.segments != static_cast<std::size_t>(hierarchy.levels()) + 1)
    reader.fail("has a segment count other than the levels + 1");
  // The coding, which the header's minor version (outside every CRC) must agree with.
  if (section.payload.size() >= 2 && planes.layout.coding_minor() != std::min<int>(result.minor_version, 1))
    reader.fail("codes its planes for another minor version than the file header's");
  IswStreamInfo& stream = result.stream;
  stream.offset = section.info.offset + kSectionHeader + planes.data_offset;
  stream.bytes = section.payload.size() > planes.data_offset ? section.payload.size() - planes.data_offset : 0;
  stream.top_plane = planes.layout.top_plane;
  stream.planes = static_cast<int>(planes.planes_total);
  stream.plane_ends = planes.plane_ends;
  result.chunks_total = planes.planes_total;

  // The frames need only the base the decoder has: built during the planes.
  const std::vector<Vec3> frame_base = result.base.positions;
  std::vector<Vec3> normals;
  tbb::task_group frames;
  frames.run([&] { normals = frame_normals(hierarchy, frame_base); });
  const CoefficientTree tree = build_coefficient_tree(hierarchy);
  const std::vector<std::uint8_t> classes = node_classes(layout);
  PlaneDecoder decoder(tree, classes, layout.count(), planes.layout.coding_minor(), planes.layout.top_plane,
                       planes.layout.groups);
  decoder.decode(planes.packets, planes.last_cut);
  for (std::string_view packet : planes.packets) stream.decoded += packet.size();
  stream.planes_decoded = decoder.planes_done();
  result.chunks_decoded = static_cast<std::size_t>(decoder.planes_done());
  result.seconds.chunks = seconds_since(start);
  frames.wait();
  const auto world_start = Clock::now();
  to_world(decoder, layout, classes, scales, frame_base, normals, result);
  result.seconds.dequantize = seconds_since(world_start);
}

void rank_and_keep(IswDecoded& result, const CoefficientClasses& layout, std::uint64_t keep, IswOrder order) {
  if (order == IswOrder::Index) {
    result.ranked.clear();
    for (std::size_t i = layout.base(); i < result.coefficients.size(); ++i)
      if (!(result.coefficients[i] == Vec3{})) result.ranked.push_back(static_cast<std::uint32_t>(i));
    return;
  }
  std::vector<RankedEntry> keyed;
  keyed.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(result.coefficients_total, result.coefficients.size())));
  for (std::size_t i = layout.base(); i < result.coefficients.size(); ++i) {
    const Vec3& c = result.coefficients[i];
    if (c == Vec3{}) continue;
    keyed.push_back({result.class_weights[static_cast<std::size_t>(layout.of(i))] * norm(c),
                     static_cast<std::uint32_t>(i), 0});
  }
  sort_by_importance(keyed);
  result.ranked.resize(keyed.size());
  for (std::size_t k = 0; k < keyed.size(); ++k) result.ranked[k] = keyed[k].index;
  if (keep >= result.ranked.size()) return;
  for (std::size_t k = static_cast<std::size_t>(keep); k < result.ranked.size(); ++k)
    result.coefficients[result.ranked[k]] = Vec3{};
  result.ranked.resize(static_cast<std::size_t>(keep));
}

}  // namespace isowave::detail
