// NRRD (NRRD0001-0005): attached (.nrrd) and detached (.nhdr + data file)
// headers; raw, gzip and ascii encodings; 3-D scalar data only.
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <unordered_set>
#include <vector>

#include "isowave/core/error.h"
#include "volume_io_internal.h"

namespace isowave::detail {
namespace {

constexpr std::size_t kMaxHeaderBytes = std::size_t{16} << 20;

enum class Encoding { Raw, Gzip, Ascii };

struct NrrdHeader {
  std::optional<ScalarType> type;
  std::optional<int> dimension;
  std::vector<std::size_t> sizes;
  std::optional<Encoding> encoding;
  std::optional<bool> big_endian;
  std::optional<std::vector<double>> spacings;
  std::optional<std::vector<std::optional<std::vector<double>>>> space_directions;
  std::optional<std::vector<double>> space_origin;
  std::optional<int> space_dimension;
  std::vector<std::string> kinds;
  std::string data_file;
  std::int64_t line_skip = 0;
  std::int64_t byte_skip = 0;
  bool attached_data = false;  // a blank line ended the header
};

std::optional<ScalarType> nrrd_type(std::string_view name, bool& known_but_unsupported) {
  known_but_unsupported = false;
  const std::string n = to_lower(trim(name));
  if (n == "signed char" || n == "int8" || n == "int8_t") return ScalarType::Int8;
  if (n == "uchar" || n == "unsigned char" || n == "uint8" || n == "uint8_t") return ScalarType::UInt8;
  if (n == "short" || n == "short int" || n == "signed short" || n == "signed short int" || n == "int16" ||
      n == "int16_t")
    return ScalarType::Int16;
  if (n == "ushort" || n == "unsigned short" || n == "unsigned short int" || n == "uint16" || n == "uint16_t")
    return ScalarType::UInt16;
  if (n == "int" || n == "signed int" || n == "int32" || n == "int32_t") return ScalarType::Int32;
  if (n == "uint" || n == "unsigned int" || n == "uint32" || n == "uint32_t") return ScalarType::UInt32;
  if (n == "float") return ScalarType::Float32;
  if (n == "double") return ScalarType::Float64;
  if (n == "longlong" || n == "long long" || n == "long long int" || n == "signed long long" ||
      n == "signed long long int" || n == "int64" || n == "int64_t" || n == "ulonglong" || n == "unsigned long long" ||
      n == "unsigned long long int" || n == "uint64" || n == "uint64_t" || n == "block")
    known_but_unsupported = true;
  return std::nullopt;
}

std::vector<double> parse_numbers(const std::string& path, const std::string& field, std::string_view text,
                                  bool allow_nan) {
  std::vector<double> values;
  for (const auto token : split_whitespace(text)) {
    double v = 0;
    if (!parse_double(token, v) || (!allow_nan && !std::isfinite(v)))
      format_error(path, "bad header: invalid number '" + std::string(token) + "' in field '" + field + "'");
    values.push_back(v);
  }
  return values;
}

// "(x,y,z)" -> numbers; whitespace inside the parentheses is tolerated.
std::vector<double> parse_vector(const std::string& path, const std::string& field, std::string_view text) {
  text = trim(text);
  if (text.size() < 2 || text.front() != '(' || text.back() != ')')
    format_error(path, "bad header: expected a vector like (x,y,z) in field '" + field + "', got '" + std::string(text) + "'");
  text = text.substr(1, text.size() - 2);
  std::vector<double> values;
  while (true) {
    const auto comma = text.find(',');
    const std::string_view part = text.substr(0, comma);
    double v = 0;
    if (!parse_double(part, v) || !std::isfinite(v))
      format_error(path, "bad header: invalid vector component '" + std::string(trim(part)) + "' in field '" + field + "'");
    values.push_back(v);
    if (comma == std::string_view::npos) break;
    text = text.substr(comma + 1);
  }
  return values;
}

// Splits "(a,b,c) none (d,e,f)" into its vectors and 'none' entries.
std::vector<std::string_view> split_vectors(const std::string& path, const std::string& field, std::string_view text) {
  std::vector<std::string_view> parts;
  std::size_t i = 0;
  while (i < text.size()) {
    while (i < text.size() && std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    if (i == text.size()) break;
    const std::size_t start = i;
    if (text[i] == '(') {
      const auto close = text.find(')', i);
      if (close == std::string_view::npos) format_error(path, "bad header: unbalanced parentheses in field '" + field + "'");
      i = close + 1;
    } else {
      while (i < text.size() && !std::isspace(static_cast<unsigned char>(text[i]))) ++i;
    }
    parts.push_back(text.substr(start, i - start));
  }
  return parts;
}

std::int64_t parse_integer_field(const std::string& path, const std::string& field, std::string_view text) {
  std::int64_t v = 0;
  if (!parse_int64(text, v)) format_error(path, "bad header: invalid integer '" + std::string(trim(text)) + "' in field '" + field + "'");
  return v;
}

// Reads one header line (without its newline); false at the end of the file.
bool read_line(InputFile& file, std::string& line, std::size_t& header_bytes) {
  line.clear();
  int c;
  bool any = false;
  while ((c = file.get()) >= 0) {
    any = true;
    if (++header_bytes > kMaxHeaderBytes) format_error(file.path(), "bad header: no end of header in the first 16 MB");
    if (c == '\n') break;
    line.push_back(static_cast<char>(c));
  }
  if (!line.empty() && line.back() == '\r') line.pop_back();
  return any;
}

NrrdHeader parse_header(InputFile& file) {
  const std::string& path = file.path();
  NrrdHeader header;
  std::string line;
  std::size_t header_bytes = 0;
  if (!read_line(file, line, header_bytes) || line.size() < 8 || line.compare(0, 7, "NRRD000") != 0 ||
      trim(std::string_view(line).substr(8)).size() != 0)
    format_error(path, "not a NRRD file (the first line must be NRRD0001 to NRRD0005)");
  if (line[7] < '1' || line[7] > '5') format_error(path, "unsupported NRRD version '" + line.substr(0, 8) + "'");

  std::unordered_set<std::string> seen;  // a hash set: a header of many unique fields stays linear
  while (read_line(file, line, header_bytes)) {
    if (line.empty()) {
      header.attached_data = true;
      break;
    }
    if (line[0] == '#') continue;
    const auto colon = line.find(':');
    if (colon == std::string::npos) format_error(path, "bad header line '" + line.substr(0, 80) + "' (expected 'field: value')");
    if (colon + 1 < line.size() && line[colon + 1] == '=') continue;  // key:=value pair
    const std::string field = to_lower(trim(std::string_view(line).substr(0, colon)));
    const std::string_view value = trim(std::string_view(line).substr(colon + 1));
    if (!seen.insert(field).second) format_error(path, "bad header: field '" + field + "' appears twice");

    if (field == "type") {
      bool unsupported = false;
      header.type = nrrd_type(value, unsupported);
      if (!header.type) {
        format_error(path, std::string(unsupported ? "unsupported" : "unknown") + " sample type '" + std::string(value) +
                               "' (supported: int8, uint8, int16, uint16, int32, uint32, float, double)");
      }
    } else if (field == "dimension") {
      const auto d = parse_integer_field(path, field, value);
      if (d != 3) format_error(path, "unsupported dimension " + std::to_string(d) + ": only 3-D scalar volumes are supported");
      header.dimension = 3;
    } else if (field == "sizes") {
      for (const auto token : split_whitespace(value)) {
        const auto s = parse_integer_field(path, field, token);
        if (s <= 0) format_error(path, "bad header: sizes must be positive, got " + std::string(token));
        header.sizes.push_back(static_cast<std::size_t>(s));
      }
    } else if (field == "encoding") {
      const std::string e = to_lower(value);
      if (e == "raw") header.encoding = Encoding::Raw;
      else if (e == "gzip" || e == "gz") header.encoding = Encoding::Gzip;
      else if (e == "ascii" || e == "text" || e == "txt") header.encoding = Encoding::Ascii;
      else format_error(path, "unsupported encoding '" + std::string(value) + "' (supported: raw, gzip, ascii)");
    } else if (field == "endian") {
      const std::string e = to_lower(value);
      if (e == "little") header.big_endian = false;
      else if (e == "big") header.big_endian = true;
      else format_error(path, "bad header: endian must be 'little' or 'big', got '" + std::string(value) + "'");
    } else if (field == "spacings") {
      header.spacings = parse_numbers(path, field, value, true);
    } else if (field == "space directions") {
      std::vector<std::optional<std::vector<double>>> directions;
      for (const auto part : split_vectors(path, field, value)) {
        if (iequals(part, "none")) directions.emplace_back();
        else directions.emplace_back(parse_vector(path, field, part));
      }
      header.space_directions = std::move(directions);
    } else if (field == "space origin") {
      header.space_origin = parse_vector(path, field, value);
    } else if (field == "space dimension") {
      header.space_dimension = static_cast<int>(std::clamp<std::int64_t>(parse_integer_field(path, field, value), -1, 1000));
    } else if (field == "kinds") {
      for (const auto token : split_whitespace(value)) header.kinds.emplace_back(token);
    } else if (field == "data file" || field == "datafile") {
      header.data_file = std::string(value);
    } else if (field == "line skip" || field == "lineskip") {
      header.line_skip = parse_integer_field(path, field, value);
      if (header.line_skip < 0) format_error(path, "bad header: negative line skip");
    } else if (field == "byte skip" || field == "byteskip") {
      header.byte_skip = parse_integer_field(path, field, value);
      if (header.byte_skip < -1) format_error(path, "bad header: byte skip must be -1 or non-negative");
    }
    // Other fields (content, space, units, centers, min, max, ...) do not affect the samples.
  }

  if (!header.type) format_error(path, "bad header: missing required field 'type'");
  if (!header.dimension) format_error(path, "bad header: missing required field 'dimension'");
  if (header.sizes.empty()) format_error(path, "bad header: missing required field 'sizes'");
  if (!header.encoding) format_error(path, "bad header: missing required field 'encoding'");
  if (header.sizes.size() != 3)
    format_error(path, "bad header: 'sizes' has " + std::to_string(header.sizes.size()) + " entries for dimension 3");
  for (std::size_t a = 0; a < header.kinds.size(); ++a) {
    const std::string k = to_lower(header.kinds[a]);
    if (k != "domain" && k != "space" && k != "time" && k != "???" && k != "none")
      format_error(path, "axis " + std::to_string(a) + " has kind '" + header.kinds[a] + "': not a 3-D scalar volume");
  }
  if (header.kinds.size() > 0 && header.kinds.size() != 3)
    format_error(path, "bad header: 'kinds' has " + std::to_string(header.kinds.size()) + " entries for dimension 3");
  if (*header.encoding != Encoding::Ascii && scalar_type_size(*header.type) > 1 && !header.big_endian)
    format_error(path, "bad header: missing field 'endian' (required for multi-byte samples)");
  return header;
}

void apply_geometry(const NrrdHeader& header, Volume& volume, const std::string& path) {
  if (header.space_dimension && *header.space_dimension != 3)
    format_error(path, "unsupported space dimension " + std::to_string(*header.space_dimension) + " (only 3 is supported)");
  double spacing[3] = {1, 1, 1};
  if (header.space_directions) {
    const auto& dirs = *header.space_directions;
    if (dirs.size() != 3)
      format_error(path, "bad header: 'space directions' has " + std::to_string(dirs.size()) + " entries for dimension 3");
    for (int a = 0; a < 3; ++a) {
      if (!dirs[a]) format_error(path, "bad header: space direction of axis " + std::to_string(a) + " is 'none'");
      const auto& d = *dirs[a];
      if (d.size() != 3) format_error(path, "bad header: space directions must have 3 components");
      const double length = std::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
      for (int b = 0; b < 3; ++b) {
        if (b != a && std::abs(d[b]) > 1e-9 * length)
          format_error(path, "space directions are not axis-aligned (rotated or permuted grids are not supported)");
      }
      if (d[a] == 0) format_error(path, "bad header: zero space direction for axis " + std::to_string(a));
      spacing[a] = d[a];
    }
  } else if (header.spacings) {
    const auto& s = *header.spacings;
    if (s.size() != 3) format_error(path, "bad header: 'spacings' has " + std::to_string(s.size()) + " entries for dimension 3");
    for (int a = 0; a < 3; ++a) {
      if (std::isnan(s[a])) continue;  // NRRD's "no spacing"
      if (!std::isfinite(s[a]) || s[a] == 0) format_error(path, "bad header: invalid spacing for axis " + std::to_string(a));
      spacing[a] = s[a];
    }
  }
  volume.spacing = {spacing[0], spacing[1], spacing[2]};
  if (header.space_origin) {
    const auto& o = *header.space_origin;
    if (o.size() != 3) format_error(path, "bad header: 'space origin' must have 3 components");
    volume.origin = {o[0], o[1], o[2]};
  }
}

std::string directory_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  return slash == std::string::npos ? std::string() : path.substr(0, slash + 1);
}

void skip_lines(InputFile& file, std::int64_t lines) {
  for (std::int64_t i = 0; i < lines; ++i) {
    int c;
    while ((c = file.get()) >= 0 && c != '\n') {
    }
    if (c < 0) format_error(file.path(), "truncated: the file ends within the " + std::to_string(lines) + " skipped lines");
  }
}

std::string size_text(const std::array<std::size_t, 3>& dims, ScalarType type) {
  return std::to_string(dims[0]) + " x " + std::to_string(dims[1]) + " x " + std::to_string(dims[2]) + " " + to_string(type);
}

void inflate_data(InputFile& file, std::uint64_t skip, SampleDecoder& decoder) {
  const std::string& path = file.path();
  z_stream zs{};
  if (inflateInit2(&zs, 15 + 32) != Z_OK) throw Error(ErrorKind::Io, path + ": cannot initialise zlib");
  struct Guard {
    z_stream* zs;
    ~Guard() { inflateEnd(zs); }
  } guard{&zs};

  std::vector<std::uint8_t> input(std::size_t{1} << 18), output(std::size_t{1} << 18);
  const std::uint64_t expected = decoder.bytes_remaining();
  bool end_of_file = false;
  bool stream_end = false;
  while (true) {
    if (zs.avail_in == 0 && !end_of_file) {
      const std::size_t got = file.read_some(input.data(), input.size());
      if (got == 0) end_of_file = true;
      zs.next_in = input.data();
      zs.avail_in = static_cast<uInt>(got);
    }
    if (stream_end) {
      // Another gzip member may follow; anything else after the data is ignored.
      if (zs.avail_in == 0) break;
      if (zs.next_in[0] != 0x1f) break;
      if (inflateReset(&zs) != Z_OK) format_error(path, "corrupt gzip data");
      stream_end = false;
    }
    zs.next_out = output.data();
    zs.avail_out = static_cast<uInt>(output.size());
    const int status = inflate(&zs, Z_NO_FLUSH);
    const std::size_t produced = output.size() - zs.avail_out;
    std::size_t offset = 0;
    if (skip > 0) {
      offset = static_cast<std::size_t>(std::min<std::uint64_t>(skip, produced));
      skip -= offset;
    }
    if (produced - offset > decoder.bytes_remaining())
      format_error(path, "size mismatch: the gzip data holds more than the " + std::to_string(expected) +
                             " bytes the header declares");
    decoder.push(output.data() + offset, produced - offset);
    if (status == Z_STREAM_END) {
      stream_end = true;
    } else if (status == Z_BUF_ERROR) {
      if (zs.avail_in == 0 && end_of_file) break;
    } else if (status != Z_OK) {
      format_error(path, std::string("corrupt gzip data (") + (zs.msg ? zs.msg : "zlib error " + std::to_string(status)) + ")");
    }
  }
  if (!stream_end) format_error(path, "truncated gzip data (the compressed stream ends early)");
  if (skip > 0 || !decoder.full())
    format_error(path, "truncated data: the gzip data holds only " +
                           std::to_string(expected - decoder.bytes_remaining()) + " of the " + std::to_string(expected) +
                           " bytes the header declares");
}

}  // namespace

Volume read_nrrd(const std::string& path, const VolumeReadOptions& options) {
  InputFile header_file(path);
  const NrrdHeader header = parse_header(header_file);

  Volume volume;
  volume.dims = {header.sizes[0], header.sizes[1], header.sizes[2]};
  volume.source_type = *header.type;
  apply_geometry(header, volume, path);
  const std::size_t sample_size = scalar_type_size(volume.source_type);
  const std::size_t count = checked_sample_count(volume.dims, sample_size, path);
  const std::uint64_t expected = static_cast<std::uint64_t>(count) * sample_size;
  const bool big_endian = header.big_endian.value_or(false);

  std::optional<InputFile> detached;
  InputFile* data = &header_file;
  std::string data_name = path;
  if (!header.data_file.empty()) {
    const std::string& name = header.data_file;
    if (name.rfind("LIST", 0) == 0 || name.find('%') != std::string::npos)
      format_error(path, "unsupported multi-file 'data file' form '" + name + "' (one data file is supported)");
    data_name = name[0] == '/' ? name : directory_of(path) + name;
    try {
      detached.emplace(data_name);
    } catch (const Error& e) {
      throw Error(e.kind(), std::string(e.what()) + " (data file of " + path + ")");
    }
    data = &*detached;
  } else if (!header.attached_data) {
    format_error(path, "no data: the header has neither a 'data file' field nor a blank line before attached data");
  }
  // Errors about the samples name the file that holds them.
  const std::string where = data_name == path ? path : data_name + " (data file of " + path + ")";

  skip_lines(*data, header.line_skip);
  const std::uint64_t start = data->tell();
  const std::uint64_t available = data->size() - std::min(data->size(), start);

  switch (*header.encoding) {
    case Encoding::Raw: {
      std::uint64_t skip = 0;
      if (header.byte_skip == -1) {
        if (available < expected)
          format_error(where, "truncated data: " + std::to_string(available) + " bytes for " +
                                  size_text(volume.dims, volume.source_type) + " samples (" + std::to_string(expected) +
                                  " bytes)");
        skip = available - expected;
      } else {
        skip = static_cast<std::uint64_t>(header.byte_skip);
      }
      if (skip > available) format_error(where, "truncated: the byte skip passes the end of the file");
      const std::uint64_t data_bytes = available - skip;
      if (data_bytes < expected)
        format_error(where, "truncated data: " + std::to_string(data_bytes) + " bytes for " +
                                size_text(volume.dims, volume.source_type) + " samples (" + std::to_string(expected) +
                                " bytes)");
      if (data_bytes > expected)
        format_error(where, "size mismatch: " + std::to_string(data_bytes) + " data bytes but the header declares " +
                                size_text(volume.dims, volume.source_type) + " samples (" + std::to_string(expected) +
                                " bytes)");
      data->seek(start + skip);
      volume.values.resize(count);
      read_binary_samples(*data, volume.values.data(), count, volume.source_type, big_endian, "raw data");
      break;
    }
    case Encoding::Gzip: {
      if (header.byte_skip < 0) format_error(path, "bad header: byte skip -1 is not allowed with gzip encoding");
      const std::uint64_t skip = static_cast<std::uint64_t>(header.byte_skip);
      if (expected + skip > max_inflated_size(available))
        format_error(where, "truncated data: " + std::to_string(available) + " bytes of gzip data cannot hold " +
                                size_text(volume.dims, volume.source_type) + " samples (" + std::to_string(expected) +
                                " bytes)");
      reserve_samples(volume.values, count, where);
      SampleDecoder decoder(volume.values, count, volume.source_type, big_endian);
      inflate_data(*data, skip, decoder);
      break;
    }
    case Encoding::Ascii: {
      if (header.byte_skip < 0) format_error(path, "bad header: byte skip -1 is not allowed with ascii encoding");
      const std::uint64_t skip = static_cast<std::uint64_t>(header.byte_skip);
      if (skip > available) format_error(where, "truncated: the byte skip passes the end of the file");
      const std::uint64_t text_bytes = available - skip;
      if (count > text_bytes / 2 + 1)
        format_error(where, "truncated data: " + std::to_string(text_bytes) + " bytes of text cannot hold " +
                                std::to_string(count) + " values");
      std::vector<char> text(static_cast<std::size_t>(text_bytes));
      data->seek(start + skip);
      data->read_exact(text.data(), text.size(), "ascii data");
      volume.values.resize(count);
      parse_text_samples(text.data(), text.data() + text.size(), count, volume.source_type, true, true,
                         volume.values.data(), where, "ascii data");
      break;
    }
  }
  make_spacing_positive(volume);
  check_geometry(volume, path);
  (void)options;
  return volume;
}

}  // namespace isowave::detail
