#include "isw2_layout.h"

#include <algorithm>
#include <cmath>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "isowave/core/error.h"
#include "bitplane_coder.h"
#include "isw_models.h"

namespace isowave::detail {

std::vector<std::uint8_t> node_classes(const CoefficientClasses& classes) {
  std::vector<std::uint8_t> result(classes.fine());
  for (int c = 0; c < classes.count(); ++c) {
    const auto [first, last] = classes.range(c);
    std::fill(result.begin() + static_cast<std::ptrdiff_t>(first), result.begin() + static_cast<std::ptrdiff_t>(last),
              static_cast<std::uint8_t>(c));
  }
  return result;
}

void steps_to_world(const std::vector<std::uint8_t>& classes, const V2Scales& scales, const std::vector<Vec3>& frame_base,
                    const std::vector<Vec3>& normals, std::vector<Vec3>& values) {
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, values.size(), kParallelGrain), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const Vec3 u = values[i];
      const int cls = classes[i];
      values[i] = cls > 0 && u == Vec3{} ? Vec3{} : scales.from_steps(i, cls, u, frame_base, normals);
    }
  });
}

std::string plane_table(PlaneLayout layout, const std::vector<std::string_view>& packets, PlaneEnding last) {
  std::string payload;
  payload.push_back(static_cast<char>(static_cast<std::int8_t>(layout.top_plane)));
  payload.push_back(static_cast<char>((last == PlaneEnding::Cut ? 1 : 0) | (layout.non_normal_flags ? 2 : 0)));
  put_varint(payload, layout.groups);
  put_varint(payload, layout.segments);
  put_varint(payload, packets.size());
  for (std::string_view p : packets) put_varint(payload, p.size());
  return payload;
}

void put_planes(std::string& out, PlaneLayout layout, const std::vector<std::string_view>& packets, PlaneEnding last) {
  std::string payload = plane_table(layout, packets, last);
  for (std::string_view p : packets) payload += p;
  put_section(out, "PLNS", payload);
}

PlaneStream read_planes(PayloadReader& reader, std::string_view payload, bool payload_cut,
                        std::uint64_t max_stream_bytes, std::uint64_t max_groups) {
  PlaneStream stream;
  if (reader.remaining() < 2) {
    if (payload_cut) return stream;
    reader.fail("is truncated");
  }
  const int top_plane = reader.read<std::int8_t>();
  const auto flags = reader.read<std::uint8_t>();
  if (top_plane < -1 || top_plane > 31 || flags > 3) reader.fail("has an invalid plane header");
  std::uint64_t groups = 0, segments = 0, count = 0;
  if (!read_varint(reader, groups) || !read_varint(reader, segments) || !read_varint(reader, count)) {
    if (payload_cut) return stream;
    reader.fail("is truncated");
  }
  if (groups < 1 || groups > max_groups || segments < 1 || segments > kMaxSegments)
    reader.fail("has an invalid group or segment count");
  stream.layout = {top_plane, static_cast<std::size_t>(groups), static_cast<std::size_t>(segments), (flags & 2) != 0};
  if (count > static_cast<std::uint64_t>(top_plane + 1) * stream.layout.packets_per_plane())
    reader.fail("holds more packets than planes");
  if (count > reader.remaining()) {  // every size takes a byte at least
    if (payload_cut) return stream;
    reader.fail("has an impossible packet count");
  }
  std::vector<std::uint64_t> sizes(static_cast<std::size_t>(count));
  for (std::uint64_t& size : sizes)
    if (!read_varint(reader, size)) {
      if (payload_cut) return stream;
      reader.fail("is truncated");
    }
  stream.table = true;
  stream.packets_total = sizes.size();
  const std::size_t per_plane = stream.layout.packets_per_plane();
  stream.planes_total = (sizes.size() + per_plane - 1) / per_plane;
  std::uint64_t end = 0;
  for (std::size_t p = 0; p < sizes.size(); ++p) {
    end += std::min<std::uint64_t>(sizes[p], payload.size());
    if ((p + 1) % per_plane == 0 || p + 1 == sizes.size()) stream.plane_ends.push_back(end);
  }
  stream.data_offset = payload.size() - reader.remaining();
  std::string_view data = payload.substr(static_cast<std::size_t>(stream.data_offset));
  std::uint64_t total = 0;
  for (std::uint64_t size : sizes) total += std::min<std::uint64_t>(size, payload.size());
  if (!payload_cut && total != data.size()) reader.fail("has an inconsistent packet table");
  stream.encoder_cut = (flags & 1) != 0;
  const std::uint64_t available = std::min<std::uint64_t>(data.size(), max_stream_bytes);
  for (const PacketSpan& span : present_packets(sizes, available, stream.encoder_cut, stream.last_cut))
    stream.packets.push_back(data.substr(static_cast<std::size_t>(span.offset), static_cast<std::size_t>(span.size)));
  stream.sizes = std::move(sizes);
  return stream;
}

std::vector<PacketSpan> present_packets(const std::vector<std::uint64_t>& sizes, std::uint64_t available,
                                        bool encoder_cut, bool& last_cut) {
  std::vector<PacketSpan> spans;
  last_cut = false;
  std::uint64_t offset = 0;
  for (std::size_t p = 0; p < sizes.size(); ++p) {
    // An empty packet is complete wherever the bytes end (it needs none).
    if (offset > available || (offset == available && sizes[p] > 0)) break;
    const std::uint64_t size = std::min(sizes[p], available - offset);
    spans.push_back({offset, size});
    offset += size;
    if (size < sizes[p] || (p + 1 == sizes.size() && encoder_cut)) {
      last_cut = true;
      break;
    }
  }
  return spans;
}

void put_rate_table(std::string& out, const std::vector<IswRatePoint>& rows) {
  std::string payload;
  put_u32(payload, static_cast<std::uint32_t>(rows.size()));
  for (const IswRatePoint& row : rows) {
    put_u64(payload, row.stream_bytes);
    put_f64(payload, row.error);
  }
  put_section(out, "RDTB", payload);
}

std::vector<IswRatePoint> read_rate_table(PayloadReader& reader) {
  const auto rows = reader.read<std::uint32_t>();
  if (rows > reader.remaining() / 16) reader.fail("has an impossible row count");
  std::vector<IswRatePoint> table(rows);
  for (IswRatePoint& row : table) {
    row.stream_bytes = reader.read<std::uint64_t>();
    row.error = reader.read<double>();
    if (!(row.error >= 0) || !std::isfinite(row.error)) reader.fail("holds an invalid error");
  }
  return table;
}

void put_plane_counts(std::string& out, const std::vector<std::uint64_t>& nonzero) {
  std::string payload;
  put_u32(payload, static_cast<std::uint32_t>(nonzero.size()));
  for (const std::uint64_t n : nonzero) put_u64(payload, n);
  put_section(out, "PCNT", payload);
}

std::vector<std::uint64_t> read_plane_counts(PayloadReader& reader) {
  const auto rows = reader.read<std::uint32_t>();
  if (rows > 32 || rows > reader.remaining() / 8) reader.fail("has an impossible row count");
  std::vector<std::uint64_t> nonzero(rows);
  for (std::size_t k = 0; k < nonzero.size(); ++k) {
    nonzero[k] = reader.read<std::uint64_t>();
    if (k > 0 && nonzero[k] < nonzero[k - 1]) reader.fail("holds counts that decrease");
  }
  return nonzero;
}

std::size_t limit_planes(const std::vector<std::uint64_t>& nonzero, int top_plane, std::uint64_t keep,
                         std::uint64_t base) {
  const std::size_t rows = nonzero.size();
  const auto first = static_cast<std::size_t>(std::lower_bound(nonzero.begin(), nonzero.end(), keep) - nonzero.begin());
  if (first >= rows) return rows;
  const auto squared_step = [&](std::size_t k) { return std::ldexp(1.0, 2 * (top_plane - static_cast<int>(k))); };
  // What is dropped: the rest of plane `first`, and every later plane's.
  double dropped = 2.25 * static_cast<double>(nonzero[first] - keep) * squared_step(first);
  for (std::size_t k = first + 1; k < rows; ++k)
    dropped += 2.25 * static_cast<double>(nonzero[k] - nonzero[k - 1]) * squared_step(k);
  const double kept = static_cast<double>(keep) + static_cast<double>(base);
  for (std::size_t k = first + 1; k < rows; ++k)
    if (kept * squared_step(k) <= dropped / 10) return k + 1;
  return rows;
}

}  // namespace isowave::detail
