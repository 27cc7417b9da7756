// Per-face colours of a PLY file. Debian 12's assimp (5.2) reads PLY
// geometry but drops colour properties of the face element; the density
// fit uses colours to find an object's parts, so they are read here. Only the
// header and the element layout are interpreted (geometry stays assimp's);
// anything unexpected yields "no colours", never an error.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_split.h"
#include "absl/strings/string_view.h"
#include "mesh_internal.h"

namespace tactforce::io::internal {
namespace {

enum class Encoding { kAscii, kLittle, kBig };

struct Property {
  std::string name;
  int size = 0;             // bytes of a scalar value (or of a list's items)
  bool is_float = false;
  bool is_signed = false;
  int count_size = 0;       // > 0: a list, with a count of this many bytes
};

struct Element {
  std::string name;
  size_t count = 0;
  std::vector<Property> properties;
};

// Size and kind of a PLY scalar type name; size 0 when unknown.
Property ScalarType(absl::string_view type) {
  Property p;
  if (type == "char" || type == "int8") p.size = 1, p.is_signed = true;
  else if (type == "uchar" || type == "uint8") p.size = 1;
  else if (type == "short" || type == "int16") p.size = 2, p.is_signed = true;
  else if (type == "ushort" || type == "uint16") p.size = 2;
  else if (type == "int" || type == "int32") p.size = 4, p.is_signed = true;
  else if (type == "uint" || type == "uint32") p.size = 4;
  else if (type == "float" || type == "float32") p.size = 4, p.is_float = true;
  else if (type == "double" || type == "float64") p.size = 8, p.is_float = true;
  return p;
}

// Reads values one by one from the body in either encoding.
class BodyReader {
 public:
  BodyReader(absl::string_view body, Encoding encoding) : body_(body), encoding_(encoding) {}

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
    std::memcpy(&u, raw, size);  // native order after the swap; little-endian hosts only matter here
    if (is_signed && size < 8 && (u >> (8 * size - 1)) & 1) u |= ~uint64_t{0} << (8 * size);
    return is_signed ? static_cast<double>(static_cast<int64_t>(u)) : static_cast<double>(u);
  }

 private:
  template <typename T>
  static T Load(const unsigned char* raw) {
    T v;
    std::memcpy(&v, raw, sizeof(T));
    return v;
  }

  std::optional<double> ReadToken() {
    while (pos_ < body_.size() && absl::ascii_isspace(static_cast<unsigned char>(body_[pos_]))) ++pos_;
    const size_t start = pos_;
    while (pos_ < body_.size() && !absl::ascii_isspace(static_cast<unsigned char>(body_[pos_]))) ++pos_;
    double v = 0;
    if (start == pos_ || !absl::SimpleAtod(body_.substr(start, pos_ - start), &v)) return std::nullopt;
    return v;
  }

  absl::string_view body_;
  Encoding encoding_;
  size_t pos_ = 0;
};

// 0..255 from a colour property (integers as they are, floats in 0..1).
uint32_t Channel(double v, bool is_float) {
  const double scaled = is_float ? 255.0 * v : v;
  return static_cast<uint32_t>(std::clamp(std::lround(scaled), 0L, 255L));
}

struct Header {
  Encoding encoding = Encoding::kAscii;
  std::vector<Element> elements;
  size_t body_start = 0;  // offset of the first byte after "end_header\n"
};

// The header's format and elements; nullopt when it is not understood.
std::optional<Header> ReadHeader(absl::string_view bytes) {
  // Header: lines up to "end_header" (LF or CRLF).
  const size_t end = bytes.find("end_header");
  if (bytes.substr(0, 3) != "ply" || end == absl::string_view::npos) return std::nullopt;
  Header h;
  h.body_start = bytes.find('\n', end);
  if (h.body_start == absl::string_view::npos) return std::nullopt;
  ++h.body_start;
  for (absl::string_view line : absl::StrSplit(bytes.substr(0, end), '\n')) {
    const std::vector<absl::string_view> w = absl::StrSplit(absl::StripAsciiWhitespace(line), ' ', absl::SkipEmpty());
    if (w.empty()) continue;
    if (w[0] == "format" && w.size() >= 2) {
      if (w[1] == "binary_little_endian") h.encoding = Encoding::kLittle;
      else if (w[1] == "binary_big_endian") h.encoding = Encoding::kBig;
      else if (w[1] != "ascii") return std::nullopt;
    } else if (w[0] == "element" && w.size() == 3) {
      Element e;
      e.name = std::string(w[1]);
      if (!absl::SimpleAtoi(w[2], &e.count)) return std::nullopt;
      h.elements.push_back(std::move(e));
    } else if (w[0] == "property" && !h.elements.empty()) {
      Property p;
      if (w.size() == 5 && w[1] == "list") {
        p = ScalarType(w[3]);
        p.count_size = ScalarType(w[2]).size;
        if (p.count_size == 0) return std::nullopt;
      } else if (w.size() == 3) {
        p = ScalarType(w[1]);
      } else {
        return std::nullopt;
      }
      if (p.size == 0) return std::nullopt;
      p.name = std::string(w.back());
      h.elements.back().properties.push_back(std::move(p));
    }
  }
  return h;
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
};

// One item of an element: its colour channels and its list length at
// `layout` (for the face element; other elements are only skipped). False
// when the body ends early or a list length is negative.
bool ReadItem(BodyReader& reader, const Element& e, const FaceLayout& layout, double rgb[3], size_t* corners) {
  for (size_t k = 0; k < e.properties.size(); ++k) {
    const Property& p = e.properties[k];
    if (p.count_size > 0) {
      const std::optional<double> n = reader.Read(p.count_size, false, false);
      if (!n || *n < 0) return false;
      for (size_t j = 0; j < static_cast<size_t>(*n); ++j)
        if (!reader.Read(p.size, p.is_float, p.is_signed)) return false;
      if (static_cast<int>(k) == layout.indices) *corners = static_cast<size_t>(*n);
      continue;
    }
    const std::optional<double> v = reader.Read(p.size, p.is_float, p.is_signed);
    if (!v) return false;
    for (int c = 0; c < 3; ++c)
      if (static_cast<int>(k) == layout.rgb[c]) rgb[c] = *v;
  }
  return true;
}

}  // namespace

std::optional<std::vector<uint32_t>> PlyFaceColors(std::string_view bytes_std) {
  const absl::string_view bytes(bytes_std.data(), bytes_std.size());
  const std::optional<Header> header = ReadHeader(bytes);
  if (!header) return std::nullopt;
  const auto face = std::find_if(header->elements.begin(), header->elements.end(),
                                 [](const Element& e) { return e.name == "face"; });
  if (face == header->elements.end()) return std::nullopt;
  FaceLayout layout;
  layout.rgb[0] = PropertyIndex(*face, "red");
  layout.rgb[1] = PropertyIndex(*face, "green");
  layout.rgb[2] = PropertyIndex(*face, "blue");
  layout.indices = PropertyIndex(*face, "vertex_indices");
  if (layout.indices < 0) layout.indices = PropertyIndex(*face, "vertex_index");
  if (*std::min_element(layout.rgb, layout.rgb + 3) < 0 || layout.indices < 0 ||
      face->properties[layout.indices].count_size == 0)
    return std::nullopt;

  BodyReader reader(bytes.substr(header->body_start), header->encoding);
  const bool is_float = face->properties[layout.rgb[0]].is_float;
  std::vector<uint32_t> colors;  // one per triangle, polygons fanned as assimp does
  for (auto e = header->elements.begin(); e != header->elements.end(); ++e) {
    const bool is_face = e == face;
    if (is_face) colors.reserve(e->count);
    for (size_t item = 0; item < e->count; ++item) {
      double rgb[3] = {0, 0, 0};
      size_t corners = 0;
      if (!ReadItem(reader, *e, layout, rgb, &corners)) return std::nullopt;
      if (!is_face) continue;
      const uint32_t c = Channel(rgb[0], is_float) << 16 | Channel(rgb[1], is_float) << 8 | Channel(rgb[2], is_float);
      for (size_t t = 2; t < corners; ++t) colors.push_back(c);
    }
    if (is_face) return colors;
  }
  return std::nullopt;
}

}  // namespace tactforce::io::internal
