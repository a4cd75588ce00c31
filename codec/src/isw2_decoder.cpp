// The .isw 2.0 plane stream decoder (docs/FORMAT.md, PLNS): the packets
// through the plane decoder, the local frames of the frame-precision base
// (built meanwhile on another thread), and the world coefficients.
#include <algorithm>
#include <cassert>
#include <chrono>
#include <cmath>

#include <tbb/task_group.h>

#include "isowave/codec/region.h"
#include "isowave/transform/patch_hierarchy.h"
#include "isowave/core/error.h"
#include "isowave/core/huge_page_vector.h"
#include "bitplane_coder.h"
#include "coefficient_tree.h"
#include "isw2_layout.h"
#include "isw_models.h"
#include "patch_selection.h"

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

// The tree's groups: runs of roots in index order (2.0, 2.1) or GIDX's runs
// of base faces in Morton order (2.2); `face_group` receives each base
// face's group in the latter case.
TreeGroups stream_groups(const SubdivisionHierarchy& hierarchy, const CoefficientTree& tree, const PlaneStream& planes,
                         const StreamAccess& access, std::vector<std::uint32_t>& face_group) {
  if (!access.index) return split_tree(tree, planes.layout.groups);
  const FaceOrder order = morton_face_order(hierarchy.base(), *access.base_q);
  const std::vector<std::uint32_t> owners = root_faces(hierarchy, tree);
  face_group = face_groups(order.faces, access.index->runs);
  return split_tree(tree, root_groups(owners, face_group), access.index->count());
}

// The groups a view frustum needs: those holding an entry that some fine
// control point of a base face that may lie in it (its corners' box grown by
// its group's reach) depends on.
std::vector<std::uint8_t> groups_for_view(const SubdivisionHierarchy& hierarchy, const std::vector<Vec3>& frame_base,
                                            const TreeGroups& split, const GroupIndex& index,
                                            const std::vector<std::uint32_t>& face_group, const StreamAccess& access) {
  std::vector<std::uint8_t> points(hierarchy.fine_vertex_count(), 0);
  for (std::size_t f = 0; f < face_group.size(); ++f) {
    Vec3 lo, hi;
    face_box(hierarchy.base(), frame_base, f, index.reach[face_group[f]], lo, hi);
    if (!access.frustum->box_outside(lo, hi)) for_each_fine_point(hierarchy, f, [&](std::size_t v) { return points[v] = 1; });
  }
  const std::vector<std::uint8_t> needed = entries_for_points(hierarchy, points);
  std::vector<std::uint8_t> selected(index.count(), 0);
  for (std::size_t g = 0; g < index.count(); ++g)
    for (std::uint32_t k = split.offsets[g]; k < split.offsets[g + 1] && !selected[g]; ++k)
      selected[g] = needed[split.members[k]];
  return selected;
}

// The packets of a file read in part: those of the selected groups, fetched
// in runs of neighbouring groups into `store`; the others empty.
std::vector<std::string_view> fetch_packets(const Section& section, const PlaneStream& planes,
                                            std::uint64_t max_stream_bytes, const StreamAccess& access,
                                            const std::vector<std::uint8_t>& selected, std::string& store,
                                            bool& last_cut) {
  const std::uint64_t first = section.info.offset + kSectionHeader + planes.data_offset;
  const std::uint64_t in_file = access.file_size > first ? access.file_size - first : 0;
  const std::uint64_t declared = section.payload_size - planes.data_offset;
  const std::vector<PacketSpan> spans =
      present_packets(planes.sizes, std::min({in_file, declared, max_stream_bytes}), planes.encoder_cut, last_cut);
  const std::size_t groups = selected.size();
  std::uint64_t total = 0;
  for (std::size_t j = 0; j < spans.size(); ++j) total += selected[j % groups] ? spans[j].size : 0;
  store.clear();
  store.reserve(static_cast<std::size_t>(total));  // views into it stay valid
  std::vector<std::string_view> packets(spans.size());
  for (std::size_t j = 0; j < spans.size();) {
    if (!selected[j % groups]) {
      ++j;
      continue;
    }
    std::size_t end = j + 1;  // a run of selected groups in one plane's level: contiguous bytes
    while (end < spans.size() && end % groups != 0 && selected[end % groups]) ++end;
    const std::uint64_t offset = spans[j].offset, size = spans[end - 1].offset + spans[end - 1].size - offset;
    const std::size_t at = store.size();
    store += access.fetch(first + offset, size);
    if (store.size() - at != size) throw Error(ErrorKind::Io, section.where + ": the file changed while it was read");
    for (std::size_t k = j; k < end; ++k)
      packets[k] = std::string_view(store).substr(at + static_cast<std::size_t>(spans[k].offset - offset),
                                                  static_cast<std::size_t>(spans[k].size));
    j = end;
  }
  return packets;
}

// 2.2: the packet table's CRC, and each selected group's when all of its
// packets are present (a cut stream's last group is not checked, as a cut
// section is not).
void check_group_crcs(PayloadReader& reader, const Section& section, const PlaneStream& planes,
                      const GroupIndex& index, const std::vector<std::string_view>& packets, bool last_cut,
                      const std::vector<std::uint8_t>* selected) {
  if (bytes_crc(section.payload.substr(0, static_cast<std::size_t>(planes.data_offset))) != index.table_crc)
    reader.fail("is corrupt (its packet table does not match GIDX's CRC)");
  if (packets.size() != planes.sizes.size() || last_cut) return;
  const std::vector<std::uint32_t> crcs = group_crcs(packets, index.count());
  for (std::size_t g = 0; g < index.count(); ++g)
    if ((!selected || (*selected)[g]) && crcs[g] != index.group_crc[g])
      reader.fail("is corrupt (group " + std::to_string(g) + "'s packets do not match GIDX's CRC)");
}

// The stream bytes `prefix` allows: with a coefficient limit and PCNT, the
// planes limit_planes() names. Error(Format) where PCNT does not fit the
// packet table (checked with or without a limit).
std::uint64_t prefix_bytes(PayloadReader& reader, const PlaneStream& planes, const StreamPrefix& prefix,
                           const CoefficientClasses& layout) {
  if (!prefix.nonzero || !planes.table) return prefix.bytes;
  const std::vector<std::uint64_t>& nonzero = *prefix.nonzero;
  if (nonzero.size() != static_cast<std::size_t>(planes.layout.top_plane + 1) ||
      (!nonzero.empty() && nonzero.back() > layout.fine() - layout.base()))
    reader.fail("does not match PCNT's plane counts");
  if (prefix.keep == UINT64_MAX) return prefix.bytes;
  const std::size_t packets =
      limit_planes(nonzero, planes.layout.top_plane, prefix.keep, layout.base()) * planes.layout.packets_per_plane();
  if (packets >= planes.sizes.size()) return prefix.bytes;
  std::uint64_t end = 0;
  for (std::size_t p = 0; p < packets; ++p) end += std::min(planes.sizes[p], UINT64_MAX - end);
  return std::min(prefix.bytes, end);
}

}  // namespace

namespace {

// What both decoders do first: PLNS's table read within the prefix (PCNT's
// planes for a coefficient limit) and checked against the file's levels,
// version and index, and reported in result.stream.
PlaneStream open_plane_stream(PayloadReader& reader, const Section& section, int levels,
                              const CoefficientClasses& layout, const StreamPrefix& prefix, const StreamAccess& access,
                              IswDecoded& result, std::uint64_t& max_stream_bytes) {
  const bool by_space = result.minor_version >= 2;
  if (by_space && !access.index) reader.fail("comes without its group index (GIDX)");
  const std::uint64_t max_groups = by_space ? access.index->count() : kMaxGroups;
  PlaneStream planes = read_planes(reader, section.payload, section.cut, prefix.bytes, max_groups);
  max_stream_bytes = prefix_bytes(reader, planes, prefix, layout);
  if (max_stream_bytes < prefix.bytes) {
    PayloadReader again = section.reader();
    planes = read_planes(again, section.payload, section.cut, max_stream_bytes, max_groups);
  }
  if (planes.packets_total > 0 && planes.layout.segments != static_cast<std::size_t>(levels) + 1)
    reader.fail("has a segment count other than the levels + 1");
  // The coding, which the header's minor version (outside every CRC) must agree with.
  if (section.payload.size() >= 2 && planes.layout.coding_minor() != std::min<int>(result.minor_version, 1))
    reader.fail("codes its planes for another minor version than the file header's");
  if (by_space && planes.table && planes.layout.groups != access.index->count())
    reader.fail("has another group count than its index (GIDX)");
  IswStreamInfo& stream = result.stream;
  stream.offset = section.info.offset + kSectionHeader + planes.data_offset;
  // Packet bytes in the file: those in memory, or up to the file's end.
  const std::uint64_t payload_start = section.info.offset + kSectionHeader;
  const std::uint64_t in_file =
      access.fetch ? std::min(section.payload_size, access.file_size > payload_start ? access.file_size - payload_start : 0)
                   : section.payload.size();
  stream.bytes = in_file > planes.data_offset ? in_file - planes.data_offset : 0;
  stream.top_plane = planes.layout.top_plane;
  stream.planes = static_cast<int>(planes.planes_total);
  stream.plane_ends = planes.plane_ends;
  result.chunks_total = planes.planes_total;
  return planes;
}

// The packets of the groups `only` flags (all without it), fetched when the
// file is read in part and checked against GIDX's CRCs (2.2), through
// `decoder` (none: no group flagged), and what was read reported.
void decode_packets(PayloadReader& reader, const Section& section, const PlaneStream& planes,
                    std::uint64_t max_stream_bytes, const StreamAccess& access, std::size_t groups,
                    const std::vector<std::uint8_t>* only, PlaneDecoder* decoder, IswDecoded& result) {
  const bool by_space = result.minor_version >= 2;
  std::string fetched;
  bool last_cut = planes.last_cut;
  const std::vector<std::string_view> packets =
      access.fetch && planes.table
          ? fetch_packets(section, planes, max_stream_bytes, access, only ? *only : std::vector<std::uint8_t>(groups, 1),
                          fetched, last_cut)
          : planes.packets;
  if (by_space && planes.table && (access.fetch || only))
    check_group_crcs(reader, section, planes, *access.index, packets, last_cut, only);
  if (decoder) decoder->decode(packets, last_cut, only);
  IswStreamInfo& stream = result.stream;
  for (std::size_t j = 0; j < packets.size(); ++j)
    if (!only || (*only)[j % groups]) stream.decoded += packets[j].size();
  stream.groups = groups;
  stream.groups_decoded = only ? static_cast<std::size_t>(std::count(only->begin(), only->end(), 1)) : groups;
  result.file_bytes_read += fetched.size();
  stream.planes_decoded = decoder ? decoder->planes_done() : 0;
  result.chunks_decoded = static_cast<std::size_t>(stream.planes_decoded);
}

}  // namespace

void decode_plane_stream(const Section& section, const SubdivisionHierarchy& hierarchy,
                         const CoefficientClasses& layout, const V2Scales& scales, const StreamPrefix& prefix,
                         const StreamAccess& access, IswDecoded& result) {
  const auto start = Clock::now();
  PayloadReader reader = section.reader();
  const bool by_space = result.minor_version >= 2;
  std::uint64_t max_stream_bytes = 0;
  const PlaneStream planes =
      open_plane_stream(reader, section, hierarchy.levels(), layout, prefix, access, result, max_stream_bytes);

  // The frames need only the base the decoder has: built during the planes.
  const std::vector<Vec3> frame_base = result.base.positions;
  std::vector<Vec3> normals;
  tbb::task_group frames;
  frames.run([&] { normals = frame_normals(hierarchy, frame_base); });
  const CoefficientTree tree = build_coefficient_tree(hierarchy);
  std::vector<std::uint32_t> face_group;
  const TreeGroups split = stream_groups(hierarchy, tree, planes, by_space ? access : StreamAccess{}, face_group);
  std::vector<std::uint8_t> selected;
  if (by_space && access.frustum)
    selected = groups_for_view(hierarchy, frame_base, split, *access.index, face_group, access);
  const std::vector<std::uint8_t> classes = node_classes(layout);
  PlaneDecoder decoder(tree, classes, layout.count(), planes.layout.coding_minor(), planes.layout.top_plane, split);
  decode_packets(reader, section, planes, max_stream_bytes, access, split.count(), selected.empty() ? nullptr : &selected,
                 &decoder, result);
  result.seconds.chunks = seconds_since(start);
  frames.wait();
  const auto world_start = Clock::now();
  to_world(decoder, layout, classes, scales, frame_base, normals, result);
  result.seconds.dequantize = seconds_since(world_start);
}

void decode_patch_stream(const Section& section, int levels, const CoefficientClasses& layout, const V2Scales& scales,
                         const StreamPrefix& prefix, const StreamAccess& access, const BaseIncidence& incidence,
                         IswDecoded& result) {
  assert((access.region || access.frustum) && access.index && result.minor_version >= 2);
  const auto start = Clock::now();
  PayloadReader reader = section.reader();
  std::uint64_t max_stream_bytes = 0;
  const PlaneStream planes = open_plane_stream(reader, section, levels, layout, prefix, access, result, max_stream_bytes);
  // The patch: the base as BPTS gives it, its groups and the faces the region needs.
  const PolygonMesh& base = result.base;
  const std::vector<std::uint32_t> face_group =
      face_groups(morton_face_order(base, *access.base_q).faces, access.index->runs);
  PatchSelection selection;
  try {  // the base's topology, as the whole hierarchy would check it
    selection = select_patch(base, incidence, face_group, access.index->reach, PatchTarget{access.region, access.frustum},
                             levels);
  } catch (const Error& error) {
    if (error.kind() != ErrorKind::Topology && error.kind() != ErrorKind::InvalidArgument) throw;
    reader.fail(std::string("needs a base mesh the subdivision hierarchy cannot take: ") + error.what());
  }
  result.seconds.hierarchy = seconds_since(start);
  auto patch = std::make_shared<RegionPatch>();
  if (!selection.patch) {  // no seed: no group to read, the base mesh alone
    decode_packets(reader, section, planes, max_stream_bytes, access, access.index->count(), &selection.selected,
                   nullptr, result);
    result.patch = std::move(patch);
    return;
  }
  const SelectedTree selected = selected_tree(selection, layout);
  patch->patch.emplace(std::move(*selection.patch));
  const SubdivisionHierarchy& h = patch->patch->hierarchy();
  const std::vector<std::uint32_t>& entries = patch->patch->entries();
  std::vector<Vec3> frame_base(h.vertex_count(0));
  for (std::size_t v = 0; v < frame_base.size(); ++v) frame_base[v] = base.positions[patch->patch->base_vertices()[v]];
  std::vector<Vec3> normals;
  tbb::task_group frames;
  frames.run([&] { normals = frame_normals(h, frame_base); });
  // The selected groups' nodes, decoded as in the whole tree.
  PlaneDecoder decoder(selected.tree, selected.node_class, layout.count(), planes.layout.coding_minor(),
                       planes.layout.top_plane, selected.groups);
  decode_packets(reader, section, planes, max_stream_bytes, access, selected.groups.count(), &selection.selected,
                 &decoder, result);
  std::vector<Vec3> values(selected.tree.nodes);
  decoder.values(values);
  result.seconds.chunks = seconds_since(start);
  // World values per patch entry: base control points at the frame precision
  // where their group was not decoded, coefficients zero there.
  const auto world_start = Clock::now();
  std::vector<Vec3>& world = patch->coefficients;
  world.assign(entries.size(), Vec3{});
  for (std::size_t i = 0; i < values.size(); ++i) world[selected.node_entry[i]] = values[i];
  std::vector<std::uint8_t> classes(entries.size());
  for (std::size_t k = 0; k < entries.size(); ++k) classes[k] = static_cast<std::uint8_t>(layout.of(entries[k]));
  frames.wait();
  steps_to_world(classes, scales, frame_base, normals, world);
  for (std::size_t v = 0; v < frame_base.size(); ++v) result.base.positions[patch->patch->base_vertices()[v]] = world[v];
  patch->exact.assign(h.base().face_count(), 0);
  const std::vector<std::uint32_t>& faces = patch->patch->faces();
  for (const std::uint32_t f : selection.seeds)
    patch->exact[static_cast<std::size_t>(std::lower_bound(faces.begin(), faces.end(), f) - faces.begin())] = 1;
  result.patch = std::move(patch);
  result.seconds.dequantize = seconds_since(world_start);
}

void rank_and_keep(IswDecoded& result, const CoefficientClasses& layout, std::uint64_t keep, IswOrder order,
                   Oracle oracle) {
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
    const double weight = oracle == Oracle::Magnitude ? 1.0 : result.class_weights[static_cast<std::size_t>(layout.of(i))];
    keyed.push_back({weight * norm(c), static_cast<std::uint32_t>(i), 0});
  }
  if (oracle == Oracle::Greedy && keep < keyed.size()) {
    result.ranked = keep_greedy(*result.hierarchy, result.coefficients, static_cast<std::size_t>(keep));
    return;
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

namespace isowave {

std::uint64_t stream_bytes_for_keep(const IswDecoded& decoded, std::uint64_t keep) {
  const IswStreamInfo& stream = decoded.stream;
  if (stream.plane_counts.empty() || keep >= decoded.coefficients_total || !decoded.hierarchy) return stream.bytes;
  const std::size_t planes =
      detail::limit_planes(stream.plane_counts, stream.top_plane, keep, decoded.hierarchy->vertex_count(0));
  return planes < stream.plane_ends.size() ? stream.plane_ends[planes - 1] : stream.bytes;
}

}  // namespace isowave
