// PLY files checked before assimp reads them, and their per-face colours.
// assimp 5.2's PLY reader trusts the file: it reads past the end of a header
// that stops early or hides `end_header` inside another line (SEGV), asserts
// (abort) on unknown property types, and allocates by the header's element
// counts and the lengths of lists before reading them (a file of a few
// hundred bytes can make it allocate gigabytes). So the header is parsed here, every count is
// checked against the limits and the bytes present, and the body is walked item by item; assimp
// only sees files whose every count is backed by data. Debian's assimp also drops colour properties
// of the face element, which the density fit uses to find an object's parts: the walk collects
// them.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "mesh_internal.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::io::internal {
namespace {

enum class Encoding { kAscii, kLittle, kBig };

struct Property {
  std::string name;
  int size = 0;  // bytes of a scalar value (or of a list's items)
  bool is_float = false;
  bool is_signed = false;
  int count_size = 0;  // > 0: a list, with a count of this many bytes
  bool count_signed = false;
};

struct Element {
  std::string name;
  uint64_t count = 0;
  int line = 0;  // the header line declaring it
  std::vector<Property> properties;
};

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  size_t body_start = 0;  // offset of the first byte after the end_header line
  int lines = 0;          // header lines, end_header included
};

// Size and kind of a PLY scalar type name; size 0 when unknown.
Property ScalarType(absl::string_view type) {
  Property p;
  if (type == "char" || type == "int8")
    p.size = 1, p.is_signed = true;
  else if (type == "uchar" || type == "uint8")
    p.size = 1;
  else if (type == "short" || type == "int16")
    p.size = 2, p.is_signed = true;
  else if (type == "ushort" || type == "uint16")
    p.size = 2;
  else if (type == "int" || type == "int32")
    p.size = 4, p.is_signed = true;
  else if (type == "uint" || type == "uint32")
    p.size = 4;
  else if (type == "float" || type == "float32")
    p.size = 4, p.is_float = true;
  else if (type == "double" || type == "float64")
    p.size = 8, p.is_float = true;
  return p;
}

// "property TYPE NAME" or "property list COUNT_TYPE TYPE NAME", split into
// words; the problem when it is not understood.
absl::StatusOr<Property> ParseProperty(const std::vector<absl::string_view>& w,
                                       absl::string_view line) {
  const absl::Status unexpected =
      absl::InvalidArgumentError(absl::StrCat("unexpected '", line.substr(0, 40), "'"));
  Property p;
  if (w.size() == 5 && w[1] == "list") {
    const Property count = ScalarType(w[2]);
    p = ScalarType(w[3]);
    if (count.size == 0 || p.size == 0) return unexpected;
    if (count.is_float)
      return absl::InvalidArgumentError(
          absl::StrCat("list length type '", w[2], "' is not an integer type"));
    p.count_size = count.size;
    p.count_signed = count.is_signed;
  } else if (w.size() == 3) {
    p = ScalarType(w[1]);
    if (p.size == 0) return unexpected;
  } else {
    return unexpected;
  }
  p.name = std::string(w.back());
  return p;
}

// The header, line by line. Accepted lines: "ply", one "format
// ascii|binary_little_endian|binary_big_endian 1.0", "comment ...",
// "obj_info ...", "element NAME COUNT", "property TYPE NAME",
// "property list TYPE TYPE NAME", then "end_header".
absl::StatusOr<Header> ParseHeader(absl::string_view bytes, const std::string& name) {
  Header h;
  bool format = false;
  int line_number = 0;
  size_t pos = 0;
  while (pos < bytes.size()) {
    const size_t eol = bytes.find('\n', pos);
    absl::string_view line =
        bytes.substr(pos, eol == absl::string_view::npos ? absl::string_view::npos : eol - pos);
    pos = eol == absl::string_view::npos ? bytes.size() : eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    auto bad = [&](absl::string_view what) {
      return absl::InvalidArgumentError(
          absl::StrCat(name, ": PLY header line ", line_number, ": ", what));
    };
    for (char c : line) {
      if (c != '\t' && (c < ' ' || c > '~')) return bad("binary bytes inside the header");
    }
    const std::vector<absl::string_view> w = absl::StrSplit(line, ' ', absl::SkipEmpty());
    if (line_number == 1) {
      if (line != "ply") return bad("not a PLY file (the first line must be 'ply')");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header" && w.size() == 1) {
      if (!format) return bad("'end_header' before a 'format' line");
      h.body_start = pos;
      h.lines = line_number;
      return h;
    }
    uint64_t count = 0;
    if (w[0] == "format" && !format && w.size() == 3 && w[2] == "1.0" &&
        (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian")) {
      format = true;
      h.encoding = w[1] == "ascii"               ? Encoding::kAscii
                   : w[1] == "binary_big_endian" ? Encoding::kBig
                                                 : Encoding::kLittle;
    } else if (w[0] == "element" && w.size() == 3 && absl::SimpleAtoi(w[2], &count)) {
      h.elements.push_back({std::string(w[1]), count, line_number, {}});
    } else if (w[0] == "property" && !h.elements.empty()) {
      absl::StatusOr<Property> p = ParseProperty(w, line);
      if (!p.ok()) return bad(p.status().message());
      h.elements.back().properties.push_back(*std::move(p));
    } else {
      return bad(absl::StrCat("unexpected '", line.substr(0, 40), "'"));
    }
  }
  return absl::InvalidArgumentError(absl::StrCat(name, ": not a PLY file: no 'end_header' line"));
}

// Smallest size of one item of `e`: bytes in a binary file (lists empty),
// values in an ASCII file (a list at least its length).
uint64_t MinItemSize(const Element& e, bool binary) {
  uint64_t n = 0;
  for (const Property& p : e.properties)
    n += !binary ? 1 : p.count_size > 0 ? p.count_size : p.size;
  return n;
}

// Non-blank lines and whitespace-separated values of an ASCII body.
void CountLinesAndValues(absl::string_view body, uint64_t* lines, uint64_t* values) {
  bool line_has_value = false, in_value = false;
  for (char c : body) {
    const bool space = absl::ascii_isspace(static_cast<unsigned char>(c));
    if (!space && !in_value) ++*values, line_has_value = true;
    in_value = !space;
    if (c == '\n') *lines += line_has_value, line_has_value = false;
  }
  *lines += line_has_value;
}

// Every element's declared count against its limit and against what the
// body can hold at the smallest item size, before anything is allocated.
absl::Status CheckCounts(const Header& h, absl::string_view body, const std::string& name) {
  const bool binary = h.encoding != Encoding::kAscii;
  uint64_t lines = 0, values = 0;
  if (!binary) CountLinesAndValues(body, &lines, &values);
  uint64_t bytes_left = body.size(), lines_left = lines, values_left = values;
  for (const Element& e : h.elements) {
    auto bad = [&](absl::string_view what) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": PLY header line ", e.line,
                                                     ": element '", e.name, "' declares ", e.count,
                                                     " items", what));
    };
    if (e.count == 0) continue;
    const uint64_t min_size = MinItemSize(e, binary);
    if (min_size == 0) return bad(" but has no properties");
    const uint64_t at_most =
        binary ? bytes_left / min_size : std::min(lines_left, values_left / min_size);
    if (e.count > at_most) {
      return bad(absl::StrCat(" but the file holds at most ", at_most, " (",
                              binary ? absl::StrCat(body.size(), " bytes")
                                     : absl::StrCat(lines, " lines, ", values, " values"),
                              " after the header)"));
    }
    const bool vertex = e.name == "vertex";
    const uint64_t limit = vertex ? kMaxMeshVertices : kMaxMeshTriangles;
    if (e.count > limit)
      return bad(absl::StrCat(", more than the limit of ", limit,
                              vertex ? " vertices" : " items per element"));
    if (binary) {
      bytes_left -= e.count * min_size;
    } else {
      lines_left -= e.count;
      values_left -= e.count * min_size;
    }
  }
  return absl::OkStatus();
}

// Reads an element's items from the body: ASCII one line per item, binary
// packed values in the file's byte order.
class BodyReader {
 public:
  BodyReader(absl::string_view body, const Header& h)
      : body_(body), encoding_(h.encoding), line_number_(h.lines), body_start_(h.body_start) {}

  // Moves to the next item: in ASCII its line. The problem, or "".
  std::string NextItem() {
    if (encoding_ != Encoding::kAscii) return "";
    if (next_line_ >= body_.size()) return "the file ends before it";
    pos_ = next_line_;
    line_end_ = std::min(body_.find('\n', pos_), body_.size());
    next_line_ = line_end_ + 1;
    ++line_number_;
    if (absl::StripAsciiWhitespace(body_.substr(pos_, line_end_ - pos_)).empty())
      return "blank line instead of an item";
    return "";
  }

  std::optional<double> Read(int size, bool is_float, bool is_signed) {
    if (encoding_ == Encoding::kAscii) return ReadToken();
    if (pos_ + size > body_.size()) return std::nullopt;
    unsigned char raw[8];
    std::memcpy(raw, body_.data() + pos_, size);
    pos_ += size;
    const bool swap = (encoding_ == Encoding::kBig) == (std::endian::native == std::endian::little);
    if (swap) std::reverse(raw, raw + size);
    if (is_float) {
      if (size == 4) return static_cast<double>(std::bit_cast<float>(Load<uint32_t>(raw)));
      return std::bit_cast<double>(Load<uint64_t>(raw));
    }
    uint64_t u = 0;
    std::memcpy(&u, raw,
                size);  // native order after the swap; little-endian hosts only matter here
    if (is_signed && size < 8 && (u >> (8 * size - 1)) & 1) u |= ~uint64_t{0} << (8 * size);
    return is_signed ? static_cast<double>(static_cast<int64_t>(u)) : static_cast<double>(u);
  }

  // How many values of `size` bytes are left: on the item's line (ASCII) or
  // in the file (binary).
  uint64_t ValuesLeft(int size) const {
    if (encoding_ != Encoding::kAscii) return (body_.size() - pos_) / size;
    uint64_t n = 0;
    bool in_value = false;
    for (size_t i = pos_; i < line_end_; ++i) {
      const bool space = absl::ascii_isspace(static_cast<unsigned char>(body_[i]));
      n += !space && !in_value;
      in_value = !space;
    }
    return n;
  }

  // "line 12" (ASCII) or "byte 345" (binary), counted from the file's start.
  std::string Where() const {
    if (encoding_ == Encoding::kAscii) return absl::StrCat("line ", line_number_);
    return absl::StrCat("byte ", body_start_ + pos_);
  }

  bool ascii() const { return encoding_ == Encoding::kAscii; }

 private:
  template <typename T>
  static T Load(const unsigned char* raw) {
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
  }

  std::optional<double> ReadToken() {
    while (pos_ < line_end_ && absl::ascii_isspace(static_cast<unsigned char>(body_[pos_]))) ++pos_;
    const size_t start = pos_;
    while (pos_ < line_end_ && !absl::ascii_isspace(static_cast<unsigned char>(body_[pos_])))
      ++pos_;
    double v = 0;
    if (start == pos_ || !absl::SimpleAtod(body_.substr(start, pos_ - start), &v))
      return std::nullopt;
    return v;
  }

  absl::string_view body_;
  Encoding encoding_;
  int line_number_;    // ASCII: file line of the current item
  size_t body_start_;  // binary: file offset of the body, for messages
  size_t pos_ = 0;
  size_t line_end_ = 0;   // ASCII: end of the current item's line
  size_t next_line_ = 0;  // ASCII: start of the line after it
};

// 0..255 from a colour property (integers as they are, floats in 0..1).
uint32_t Channel(double v, bool is_float) {
  const double scaled = is_float ? 255.0 * v : v;
  return static_cast<uint32_t>(std::clamp(std::lround(scaled), 0L, 255L));
}

// Index of the property `name` of `e`; -1 when absent.
int PropertyIndex(const Element& e, absl::string_view name) {
  for (size_t i = 0; i < e.properties.size(); ++i)
    if (e.properties[i].name == name) return static_cast<int>(i);
  return -1;
}

// Where the colour and the corners are in the face element.
struct FaceLayout {
  int rgb[3] = {-1, -1, -1};  // property indices of red, green, blue
  int indices = -1;           // the vertex index list
  bool is_float = false;      // colours in 0..1 (else 0..255)

  bool colored() const { return *std::min_element(rgb, rgb + 3) >= 0 && indices >= 0; }
};

FaceLayout FaceLayoutOf(const Element& face) {
  FaceLayout layout;
  layout.rgb[0] = PropertyIndex(face, "red");
  layout.rgb[1] = PropertyIndex(face, "green");
  layout.rgb[2] = PropertyIndex(face, "blue");
  layout.indices = PropertyIndex(face, "vertex_indices");
  if (layout.indices < 0) layout.indices = PropertyIndex(face, "vertex_index");
  if (layout.indices >= 0 && face.properties[layout.indices].count_size == 0) layout.indices = -1;
  if (layout.rgb[0] >= 0) layout.is_float = face.properties[layout.rgb[0]].is_float;
  return layout;
}

// One item of `e`: every value present, each list's length a whole number
// within what is left; the colour channels and the corner count at `layout`
// (for the face element; other elements are only checked). The problem, or "".
std::string ReadItem(BodyReader& reader, const Element& e, const FaceLayout& layout, double rgb[3],
                     uint64_t* corners) {
  for (size_t k = 0; k < e.properties.size(); ++k) {
    const Property& p = e.properties[k];
    if (p.count_size > 0) {
      const std::optional<double> n = reader.Read(p.count_size, false, p.count_signed);
      if (!n) return absl::StrCat("the length of list '", p.name, "' is missing or not a number");
      if (*n < 0 || *n != std::floor(*n))
        return absl::StrCat("list '", p.name, "' has length ", *n);
      const uint64_t left = reader.ValuesLeft(p.size);
      if (*n > static_cast<double>(left)) {
        return absl::StrCat(
            "list '", p.name, "' has length ", static_cast<uint64_t>(*n), " but only ", left,
            reader.ascii() ? " values follow on the line" : " values fit in the rest of the file");
      }
      for (uint64_t j = 0; j < static_cast<uint64_t>(*n); ++j)
        if (!reader.Read(p.size, p.is_float, p.is_signed))
          return absl::StrCat("list '", p.name, "': not a number");
      if (static_cast<int>(k) == layout.indices) *corners = static_cast<uint64_t>(*n);
      continue;
    }
    const std::optional<double> v = reader.Read(p.size, p.is_float, p.is_signed);
    if (!v) return absl::StrCat("property '", p.name, "' is missing or not a number");
    for (int c = 0; c < 3; ++c)
      if (static_cast<int>(k) == layout.rgb[c]) rgb[c] = *v;
  }
  return "";
}

// Walks every item of every element; the face colours (one per triangle,
// polygons fanned as ReadMeshBytes does) when the face element has them.
absl::StatusOr<std::vector<uint32_t>> WalkBody(const Header& h, absl::string_view bytes,
                                               const std::string& name) {
  const auto face = std::find_if(h.elements.begin(), h.elements.end(),
                                 [](const Element& e) { return e.name == "face"; });
  const FaceLayout face_layout = face == h.elements.end() ? FaceLayout{} : FaceLayoutOf(*face);
  BodyReader reader(bytes.substr(h.body_start), h);
  std::vector<uint32_t> colors;
  for (auto e = h.elements.begin(); e != h.elements.end(); ++e) {
    const bool colored = e == face && face_layout.colored();
    const FaceLayout layout = e == face ? face_layout : FaceLayout{};
    for (uint64_t item = 0; item < e->count; ++item) {
      double rgb[3] = {0, 0, 0};
      uint64_t corners = 0;
      std::string problem = reader.NextItem();
      if (problem.empty()) problem = ReadItem(reader, *e, layout, rgb, &corners);
      if (!problem.empty()) {
        return absl::InvalidArgumentError(absl::StrCat(name, ": PLY ", reader.Where(),
                                                       ": element '", e->name, "' item ", item,
                                                       ": ", problem));
      }
      if (!colored) continue;
      const bool f = face_layout.is_float;
      const uint32_t c = Channel(rgb[0], f) << 16 | Channel(rgb[1], f) << 8 | Channel(rgb[2], f);
      for (uint64_t t = 2; t < corners; ++t) colors.push_back(c);
    }
  }
  return colors;
}

}  // namespace

// A mesh needs a non-empty `vertex` element and faces (`face`, or the
// `tristrips` some exporters write). assimp, given neither, treats other
// elements' data as its vertices and can allocate gigabytes for a file of a
// few hundred bytes.
absl::Status RequireMeshElements(const Header& h, const std::string& name) {
  bool vertices = false, faces = false;
  for (const Element& e : h.elements) {
    vertices = vertices || (e.name == "vertex" && e.count > 0);
    faces = faces || ((e.name == "face" || e.name == "tristrips") && e.count > 0);
  }
  if (!vertices)
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": PLY header declares no vertices (element 'vertex' missing or empty)"));
  if (!faces)
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": PLY header declares no faces (element 'face' or 'tristrips' missing or empty)"));
  return absl::OkStatus();
}

absl::StatusOr<CheckedPly> CheckPly(std::string_view bytes_std, const std::string& name) {
  const absl::string_view bytes(bytes_std.data(), bytes_std.size());
  TF_ASSIGN_OR_RETURN(Header header, ParseHeader(bytes, name));
  TF_RETURN_IF_ERROR(CheckCounts(header, bytes.substr(header.body_start), name));
  TF_RETURN_IF_ERROR(RequireMeshElements(header, name));
  TF_ASSIGN_OR_RETURN(std::vector<uint32_t> colors, WalkBody(header, bytes, name));
  CheckedPly checked;
  checked.face_colors = std::move(colors);
  const size_t body = header.body_start;
  if (header.encoding != Encoding::kAscii && body < bytes.size() && bytes[body] == '\n' &&
      bytes[body - 2] != '\r')
    checked.assimp_bytes = absl::StrCat(bytes.substr(0, body), "\n", bytes.substr(body));
  return checked;
}

}  // namespace tactforce::io::internal
