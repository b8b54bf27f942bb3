#include "core/io/point_cloud_header.hpp"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cstdlib>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <set>
#include <utility>
#include <vector>

#include "core/util/text.hpp"

namespace rotolidar {
namespace {

constexpr int kMaxHeaderLines = 4096;
constexpr uint64_t kMaxLzfExpansion = 100;  // LZF stores a run of up to 264 bytes in 3: ~88x at most

Status HeaderError(const std::string& path, int line, const std::string& what) {
  return Status::Error(path + ": header line " + std::to_string(line) + ": " + what);
}

/// The whole of `token` as a whole number >= 0 that fits 64 bits (digits only: no sign, no exponent).
bool ParseCount(const std::string& token, uint64_t* value) {
  const char* end = token.data() + token.size();
  const std::from_chars_result r = std::from_chars(token.data(), end, *value);
  return !token.empty() && r.ec == std::errc() && r.ptr == end;
}

/// Bytes of the file after the stream's read position (the data after a header).
uint64_t BytesAfter(std::ifstream& in, uint64_t file_size) {
  const std::streamoff pos = in.tellg();
  return pos < 0 ? 0 : file_size - std::min<uint64_t>(file_size, uint64_t(pos));
}

/// a * b, saturating at UINT64_MAX.
uint64_t SatMul(uint64_t a, uint64_t b) { return (b != 0 && a > UINT64_MAX / b) ? UINT64_MAX : a * b; }

/// Bytes of a PLY scalar type (PLY 1.0 names and the sized aliases); 0 if unknown.
uint64_t PlyScalarBytes(const std::string& type) {
  if (type == "char" || type == "uchar" || type == "int8" || type == "uint8") return 1;
  if (type == "short" || type == "ushort" || type == "int16" || type == "uint16") return 2;
  if (type == "int" || type == "uint" || type == "float" || type == "int32" || type == "uint32" || type == "float32")
    return 4;
  if (type == "double" || type == "float64") return 8;
  return 0;
}

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  int line = 0;
  uint64_t bytes = 0;       ///< binary: the smallest size of one element (a list counts its length field only)
  uint64_t properties = 0;  ///< ASCII: at least one byte per property value
};

/// True for a line of printable ASCII (tabs and a trailing CR allowed).
bool Printable(const std::string& line) {
  auto bad = [](char c) { return (c < 0x20 && c != '\t' && c != '\r') || c > 0x7e; };
  return std::none_of(line.begin(), line.end(), bad);
}

/// One PLY header line (not the first, not end_header) into `elements`; an error names what is wrong.
std::string ParsePlyLine(const std::vector<std::string>& t, bool* ascii, std::vector<PlyElement>* elements) {
  if (t[0] == "comment" || t[0] == "obj_info") return "";
  if (t[0] == "format") {
    if (t.size() != 3 || (t[1] != "ascii" && t[1] != "binary_little_endian" && t[1] != "binary_big_endian"))
      return "format: expected 'format ascii|binary_little_endian|binary_big_endian 1.0'";
    *ascii = t[1] == "ascii";
    return "";
  }
  if (t[0] == "element") {
    PlyElement e;
    e.name = t.size() >= 2 ? t[1] : "";
    if (t.size() != 3 || !ParseCount(t[2], &e.count))
      return "element " + e.name + ": the count '" + (t.size() >= 3 ? t[2] : "") + "' is not a whole number >= 0";
    elements->push_back(e);
    return "";
  }
  if (t[0] == "property") {
    const bool list = t.size() >= 2 && t[1] == "list";
    if (elements->empty()) return "property before any element";
    if (t.size() != (list ? 5u : 3u) || PlyScalarBytes(t[list ? 2 : 1]) == 0 || (list && PlyScalarBytes(t[3]) == 0))
      return "property: expected 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' with PLY types";
    elements->back().bytes += PlyScalarBytes(t[list ? 2 : 1]);  // a list: its length field at least
    elements->back().properties += 1;
    return "";
  }
  return "unknown PLY header keyword '" + t[0] + "'";
}

Status CheckPly(const std::string& path, std::ifstream& in, uint64_t file_size) {
  std::string line;
  std::getline(in, line);  // "ply", checked by the caller
  bool ascii = false;
  std::vector<PlyElement> elements;
  for (int number = 2; number <= kMaxHeaderLines && std::getline(in, line); ++number) {
    const std::vector<std::string> t = SplitWhitespace(line);
    // PCL skips lines it cannot parse and may then read the data as header, or the header as data: every line
    // must be one this check understands (an unparsed element count once made PCL loop for ~10^17 elements).
    if (t.empty()) return HeaderError(path, number, "an empty line (PLY headers have none)");
    if (std::isspace(static_cast<unsigned char>(line[0])))
      return HeaderError(path, number, "a header line must start with its keyword, not a blank");
    if (t[0] != "comment" && t[0] != "obj_info" && !Printable(line))
      return HeaderError(path, number, "a control or non-ASCII byte in the header");
    if (t[0] != "end_header") {
      const std::string error = ParsePlyLine(t, &ascii, &elements);
      if (!error.empty()) return HeaderError(path, number, error);
      if (t[0] == "element") elements.back().line = number;
      continue;
    }
    if (t.size() != 1) return HeaderError(path, number, "end_header: expected nothing after it");
    const uint64_t data = BytesAfter(in, file_size);
    for (const PlyElement& e : elements) {
      const uint64_t per_element = std::max<uint64_t>(1, ascii ? e.properties : e.bytes);
      const uint64_t need = SatMul(e.count, per_element);
      if (need > data)
        return HeaderError(path, e.line, "element " + e.name + " " + std::to_string(e.count) + " needs at least " +
                                             std::to_string(need) + " bytes of data, the file has " +
                                             std::to_string(data) + " after its header");
    }
    return Status::Ok();
  }
  return Status::Error(path + ": no end_header line in the first " + std::to_string(kMaxHeaderLines) +
                       " lines: not a PLY header");
}

bool Fail(std::string* error, std::string message) {
  *error = std::move(message);
  return false;
}

/// The PCD header's fields as far as the size check needs them (PCD v0.7, pointclouds.org "The PCD file format").
struct PcdHeader {
  std::vector<std::string> fields, types;
  std::vector<uint64_t> sizes, counts;
  uint64_t width = 0, height = 1, points = 0;
  bool have_width = false, have_points = false;
  std::set<std::string> seen;  ///< keywords so far: each at most once
};

/// Reads one header line into `h`; false with *error set on a malformed value or an unknown keyword.
bool ParsePcdLine(const std::vector<std::string>& t, PcdHeader* h, std::string* error) {
  const std::string& key = t[0];
  auto whole = [&](uint64_t* value) {
    if (t.size() == 2 && ParseCount(t[1], value)) return true;
    *error = key + ": '" + (t.size() >= 2 ? t[1] : "") + "' is not a whole number >= 0";
    return false;
  };
  if (!h->seen.insert(key).second) return Fail(error, key + " appears twice");
  if (key == "VERSION") return true;
  if (key == "VIEWPOINT") return t.size() == 8 || Fail(error, "VIEWPOINT: expected 7 numbers (tx ty tz qw qx qy qz)");
  if (key == "FIELDS" || key == "TYPE") {
    (key == "FIELDS" ? h->fields : h->types).assign(t.begin() + 1, t.end());
    return true;
  }
  if (key == "SIZE" || key == "COUNT") {
    std::vector<uint64_t>& list = key == "SIZE" ? h->sizes : h->counts;
    list.clear();
    for (size_t i = 1; i < t.size(); ++i) {
      uint64_t v = 0;
      if (!ParseCount(t[i], &v)) return Fail(error, key + ": '" + t[i] + "' is not a whole number");
      list.push_back(v);
    }
    return true;
  }
  if (key == "WIDTH") h->have_width = true;
  if (key == "POINTS") h->have_points = true;
  // WIDTH 0 crashed PCL's reader (found by fuzzing); a cloud without points is refused anyway.
  if (key == "WIDTH") return whole(&h->width) && (h->width > 0 || Fail(error, "WIDTH must be >= 1"));
  if (key == "HEIGHT") return whole(&h->height) && (h->height > 0 || Fail(error, "HEIGHT must be >= 1"));
  if (key == "POINTS") return whole(&h->points);
  *error = "unknown header keyword '" + key + "'";
  return false;
}

/// The per-field lists agree, each SIZE and TYPE is one PCL reads, and POINTS = WIDTH x HEIGHT.
bool ConsistentPcd(PcdHeader* h, std::string* error) {
  const size_t n = h->fields.size();
  if (n == 0) return Fail(error, "DATA before any FIELDS");
  if (h->counts.empty()) h->counts.assign(n, 1);
  if (h->sizes.size() != n || h->types.size() != n || h->counts.size() != n)
    return Fail(error, "FIELDS names " + std::to_string(n) + " fields, but SIZE has " +
                           std::to_string(h->sizes.size()) + ", TYPE " + std::to_string(h->types.size()) +
                           " and COUNT " + std::to_string(h->counts.size()));
  for (size_t i = 0; i < n; ++i) {
    const uint64_t size = h->sizes[i];
    if (size != 1 && size != 2 && size != 4 && size != 8)
      return Fail(error, "SIZE of field " + h->fields[i] + " must be 1, 2, 4 or 8");
    if (h->types[i] != "I" && h->types[i] != "U" && h->types[i] != "F")
      return Fail(error, "TYPE of field " + h->fields[i] + " must be I, U or F");
    if (h->counts[i] == 0 || h->counts[i] > (1u << 20))
      return Fail(error, "COUNT of field " + h->fields[i] + " must be 1 to 2^20");
  }
  // pcl::PointXYZ takes x, y, z as single 4-byte floats and copies each field's bytes as they are: another size,
  // type or count overran the point (a heap-buffer-overflow in pcl::fromPCLPointCloud2, found by fuzzing).
  for (const char* axis : {"x", "y", "z"}) {
    const auto it = std::find(h->fields.begin(), h->fields.end(), axis);
    const size_t i = size_t(it - h->fields.begin());
    if (it == h->fields.end()) return Fail(error, std::string("FIELDS has no ") + axis);
    if (h->sizes[i] != 4 || h->types[i] != "F" || h->counts[i] != 1)
      return Fail(error, std::string("field ") + axis + " must be one 4-byte float (SIZE 4, TYPE F, COUNT 1)");
  }
  if (!h->have_width) return Fail(error, "no WIDTH before DATA");
  if (!h->have_points) h->points = SatMul(h->width, h->height);
  if (h->points != SatMul(h->width, h->height))
    return Fail(error, "POINTS " + std::to_string(h->points) + " is not WIDTH x HEIGHT");
  return true;
}

/// DATA ascii: exactly `points` lines of `values` numbers each (blank lines skipped, as PCL does). PCL's own ASCII
/// reader left a cloud shorter than its header on a line of text, and pcl::fromPCLPointCloud2 then read past it
/// (found by fuzzing).
Status CheckPcdAscii(const std::string& path, std::ifstream& in, int data_line, uint64_t points, uint64_t values) {
  auto error = [&](int number, const std::string& what) {
    return Status::Error(path + ": line " + std::to_string(number) + ": " + what);
  };
  std::string line;
  uint64_t rows = 0;
  int number = data_line;
  while (std::getline(in, line)) {
    ++number;
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (rows == points) return error(number, "more data lines than POINTS " + std::to_string(points));
    if (!Printable(line)) return error(number, "a control or non-ASCII byte in the data");
    const std::vector<std::string> t = SplitWhitespace(line);
    if (t.size() != values)
      return error(number, "expected " + std::to_string(values) + " numbers, found " + std::to_string(t.size()));
    for (const std::string& token : t) {
      char* end = nullptr;
      std::strtod(token.c_str(), &end);
      if (end == token.c_str() || *end != '\0') return error(number, "'" + token + "' is not a number");
    }
    ++rows;
  }
  if (rows != points)
    return error(number,
                 "POINTS is " + std::to_string(points) + " but the data has " + std::to_string(rows) + " lines");
  return Status::Ok();
}

Status CheckPcd(const std::string& path, std::ifstream& in, uint64_t file_size) {
  PcdHeader h;
  std::string line, error;
  for (int number = 1; number <= kMaxHeaderLines && std::getline(in, line); ++number) {
    const std::vector<std::string> t = SplitWhitespace(line);
    if (line.empty()) continue;  // PCL skips empty lines
    // PCL splits on whitespace and takes the first piece as the keyword: a line that starts with a blank has an
    // empty keyword there, and PCL then read the data from the wrong place (a null-pointer crash found by fuzzing).
    if (std::isspace(static_cast<unsigned char>(line[0])))
      return HeaderError(path, number, "a header line must start with its keyword, not a blank");
    if (t[0][0] == '#') continue;
    // Printable ASCII only: PCL splits on whitespace alone, and a NUL inside a field name made it read past a
    // buffer it had freed (found by fuzzing).
    if (!Printable(line)) return HeaderError(path, number, "a control or non-ASCII byte in the header");
    if (t[0] != "DATA") {
      if (!ParsePcdLine(t, &h, &error)) return HeaderError(path, number, error);
      continue;
    }
    if (!ConsistentPcd(&h, &error)) return HeaderError(path, number, error);
    const std::string kind = t.size() == 2 ? t[1] : "";
    if (kind != "ascii" && kind != "binary" && kind != "binary_compressed")
      return HeaderError(path, number, "DATA must be ascii, binary or binary_compressed");
    uint64_t step = 0, values = 0;
    for (size_t i = 0; i < h.sizes.size(); ++i) step += h.sizes[i] * h.counts[i], values += h.counts[i];
    const uint64_t data = BytesAfter(in, file_size);
    uint64_t need = SatMul(h.points, kind == "ascii" ? values : step);
    if (kind == "binary_compressed") need /= kMaxLzfExpansion;
    if (need > data || (data == 0 && h.points > 0))
      return HeaderError(path, number, "POINTS " + std::to_string(h.points) + " (" + kind + ") needs at least " +
                                           std::to_string(need) + " bytes of data, the file has " +
                                           std::to_string(data) + " after its header");
    return kind == "ascii" ? CheckPcdAscii(path, in, number, h.points, values) : Status::Ok();
  }
  return Status::Error(path + ": no DATA line in the first " + std::to_string(kMaxHeaderLines) +
                       " lines: not a PCD header");
}

}  // namespace

Status CheckPointCloudHeader(const std::string& path) {
  std::error_code ec;
  const uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) return Status::Error(path + ": cannot read the file (" + ec.message() + ")");
  if (size == 0) return Status::Error(path + ": the file is empty");
  std::ifstream in(path, std::ios::binary);
  if (!in) return Status::Error(path + ": cannot open the file");
  std::string ext = std::filesystem::path(path).extension().string();
  for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
  if (ext == ".pcd") return CheckPcd(path, in, size);
  if (ext != ".ply") return Status::Error(path + ": unknown point cloud extension (use .ply or .pcd)");
  std::string magic;
  std::getline(in, magic);
  if (!magic.empty() && magic.back() == '\r') magic.pop_back();
  if (magic != "ply") return Status::Error(path + ": header line 1: not a PLY file (it must start with 'ply')");
  in.seekg(0);
  return CheckPly(path, in, size);
}

}  // namespace rotolidar
