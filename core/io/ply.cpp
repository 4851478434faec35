// PLY (Stanford polygon file), ascii and binary little/big endian. The output keeps the
// input's header byte for byte (comments, obj_info, element and property order) and its
// encoding; every element and property is written back with its declared type. Only the
// vertex x, y, z change, and nx, ny, nz when present are recomputed from the new surface.
// Extra properties (colours, quality, texture coordinates, face colours) and extra elements
// pass through unchanged. Every face must be a triangle.
#include <bit>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/io/detail.h"
#include "core/io/plain.h"
#include "core/io/text_table.h"

namespace mdn::io::detail {
namespace {

enum class Encoding { Ascii, BinaryLittle, BinaryBig };
enum class Type { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

std::optional<Type> type_from_name(std::string_view name) {
  if (name == "char" || name == "int8") return Type::Int8;
  if (name == "uchar" || name == "uint8") return Type::UInt8;
  if (name == "short" || name == "int16") return Type::Int16;
  if (name == "ushort" || name == "uint16") return Type::UInt16;
  if (name == "int" || name == "int32") return Type::Int32;
  if (name == "uint" || name == "uint32") return Type::UInt32;
  if (name == "float" || name == "float32") return Type::Float32;
  if (name == "double" || name == "float64") return Type::Float64;
  return std::nullopt;
}

std::size_t type_size(Type type) {
  switch (type) {
    case Type::Int8: case Type::UInt8: return 1;
    case Type::Int16: case Type::UInt16: return 2;
    case Type::Int32: case Type::UInt32: case Type::Float32: return 4;
    case Type::Float64: return 8;
  }
  return 1;
}

bool is_integer(Type type) { return type != Type::Float32 && type != Type::Float64; }

const char* type_name(Type type) {
  constexpr const char* kNames[] = {"int8", "uint8", "int16", "uint16", "int32", "uint32", "float32", "float64"};
  return kNames[static_cast<int>(type)];
}

// The range of an integer type, as doubles (exact: at most 32 bits).
double type_min(Type type) {
  switch (type) {
    case Type::Int8: return std::numeric_limits<std::int8_t>::min();
    case Type::Int16: return std::numeric_limits<std::int16_t>::min();
    case Type::Int32: return std::numeric_limits<std::int32_t>::min();
    default: return 0;
  }
}
double type_max(Type type) {
  switch (type) {
    case Type::Int8: return std::numeric_limits<std::int8_t>::max();
    case Type::UInt8: return std::numeric_limits<std::uint8_t>::max();
    case Type::Int16: return std::numeric_limits<std::int16_t>::max();
    case Type::UInt16: return std::numeric_limits<std::uint16_t>::max();
    case Type::Int32: return std::numeric_limits<std::int32_t>::max();
    case Type::UInt32: return std::numeric_limits<std::uint32_t>::max();
    default: return std::numeric_limits<double>::max();
  }
}

// Every value is held as a double: exact for all PLY types (at most 32-bit integers, floats).
struct Property {
  std::string name;
  Type type = Type::Float32;
  bool is_list = false;
  Type count_type = Type::UInt8;
  std::vector<double> values;
  std::vector<std::int64_t> offsets{0};  // lists only: CSR offsets into values
};

struct Element {
  std::string name;
  std::int64_t count = 0;
  std::vector<Property> properties;
  Property* find(std::string_view name) {
    for (auto& p : properties)
      if (p.name == name) return &p;
    return nullptr;
  }
};

class PlyDocument final : public MeshDocument {
 public:
  Format format() const override { return Format::Ply; }
  std::vector<TriMesh>& surfaces() override { return surfaces_; }
  std::vector<std::string> notes() const override {
    if (has_normals_) return {"PLY vertex normals (nx, ny, nz) recomputed from the denoised surface"};
    return {};
  }
  Encoded encode(const EncodeOptions& options) const override;

  std::string header_;  // verbatim, through "end_header\n"
  Encoding encoding_ = Encoding::Ascii;
  std::vector<Element> elements_;
  std::size_t vertex_element_ = 0;
  bool has_normals_ = false;
  std::vector<TriMesh> surfaces_;
};

// ---- reading ----

class BinaryReader {
 public:
  BinaryReader(std::string_view data, bool swap) : data_(data), swap_(swap) {}
  double read(Type type) {
    const std::size_t size = type_size(type);
    if (pos_ + size > data_.size()) throw FormatError("PLY: the binary data ends before the declared elements do");
    unsigned char raw[8];
    std::memcpy(raw, data_.data() + pos_, size);
    pos_ += size;
    if (swap_)
      for (std::size_t i = 0; i < size / 2; ++i) std::swap(raw[i], raw[size - 1 - i]);
    switch (type) {
      case Type::Int8: { std::int8_t v; std::memcpy(&v, raw, 1); return v; }
      case Type::UInt8: { std::uint8_t v; std::memcpy(&v, raw, 1); return v; }
      case Type::Int16: { std::int16_t v; std::memcpy(&v, raw, 2); return v; }
      case Type::UInt16: { std::uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case Type::Int32: { std::int32_t v; std::memcpy(&v, raw, 4); return v; }
      case Type::UInt32: { std::uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case Type::Float32: { float v; std::memcpy(&v, raw, 4); return v; }
      case Type::Float64: { double v; std::memcpy(&v, raw, 8); return v; }
    }
    return 0;
  }
  std::size_t remaining() const { return data_.size() - pos_; }

 private:
  std::string_view data_;
  std::size_t pos_ = 0;
  bool swap_;
};

class AsciiReader {
 public:
  explicit AsciiReader(std::string_view data) : data_(data) {}
  double read(Type type) {
    while (pos_ < data_.size() && std::strchr(" \t\r\n", data_[pos_]) != nullptr) ++pos_;
    std::size_t end = pos_;
    while (end < data_.size() && std::strchr(" \t\r\n", data_[end]) == nullptr) ++end;
    const std::string_view token = data_.substr(pos_, end - pos_);
    pos_ = end;
    if (token.empty()) throw FormatError("PLY: the ascii data ends before the declared elements do");
    double value = 0;
    if (!parse_number(token, value))
      throw FormatError("PLY: '" + std::string(token.substr(0, 32)) + "' is not a number");
    if (is_integer(type) && value != std::floor(value))
      throw FormatError("PLY: '" + std::string(token.substr(0, 32)) + "' is not an integer");
    // Written back with its declared type: it must fit in it (a cast out of range is undefined).
    if (is_integer(type) ? !(value >= type_min(type) && value <= type_max(type))
                         : (type == Type::Float32 && std::isfinite(value) && std::abs(value) > std::numeric_limits<float>::max()))
      throw FormatError("PLY: '" + std::string(token.substr(0, 32)) + "' does not fit in its property's type");
    return value;
  }
  std::size_t remaining() const { return data_.size() - pos_; }

 private:
  std::string_view data_;
  std::size_t pos_ = 0;
};

template <class Reader>
void read_body(Reader& reader, std::vector<Element>& elements, std::size_t min_row_bytes_unit, const Limits& limits) {
  std::int64_t decoded_bytes = 0;
  CancelPoll cancel(limits.cancel);
  for (auto& element : elements) {
    // A row of an element without properties takes no bytes at all, so nothing would bound
    // its count (4e18 empty rows pin a thread; written back as ascii, they fill memory).
    if (element.properties.empty() && element.count > 0)
      throw FormatError("PLY: element '" + element.name + "' declares " + std::to_string(element.count) +
                        " rows but no properties");
    // Each row takes at least one unit per property (a byte in binary, "0 " in ascii).
    const auto row_min = static_cast<std::int64_t>(element.properties.size() * min_row_bytes_unit);
    if (row_min > 0 && element.count > static_cast<std::int64_t>(reader.remaining()) / row_min)
      throw FormatError("PLY: element '" + element.name + "' declares " + std::to_string(element.count) +
                        " rows, more than the remaining data can hold");
    decoded_bytes += element.count * static_cast<std::int64_t>(element.properties.size()) * 8;
    if (decoded_bytes > limits.max_decoded_bytes) throw LimitError("PLY: the declared elements exceed the decoded size limit");
    for (auto& p : element.properties) p.values.reserve(static_cast<std::size_t>(element.count) * (p.is_list ? 3 : 1));
    for (std::int64_t row = 0; row < element.count; ++row, cancel.poll())
      for (auto& p : element.properties) {
        if (!p.is_list) {
          p.values.push_back(reader.read(p.type));
          continue;
        }
        const double n = reader.read(p.count_type);
        if (n < 0 || n * static_cast<double>(min_row_bytes_unit) > static_cast<double>(reader.remaining()))
          throw FormatError("PLY: a list in element '" + element.name + "' declares " + std::to_string(n) +
                            " entries, more than the remaining data can hold");
        for (std::int64_t k = 0; k < static_cast<std::int64_t>(n); ++k) p.values.push_back(reader.read(p.type));
        p.offsets.push_back(static_cast<std::int64_t>(p.values.size()));
        decoded_bytes += static_cast<std::int64_t>(n) * 8;
        if (decoded_bytes > limits.max_decoded_bytes) throw LimitError("PLY: the lists exceed the decoded size limit");
      }
  }
}

// ---- writing ----

void write_binary(std::string& out, Type type, double value, bool swap) {
  // Integer properties (a position in an integer PLY after denoising) take the nearest integer.
  if (is_integer(type)) value = std::nearbyint(value);
  unsigned char raw[8];
  const std::size_t size = type_size(type);
  switch (type) {
    case Type::Int8: { auto v = static_cast<std::int8_t>(value); std::memcpy(raw, &v, 1); break; }
    case Type::UInt8: { auto v = static_cast<std::uint8_t>(value); std::memcpy(raw, &v, 1); break; }
    case Type::Int16: { auto v = static_cast<std::int16_t>(value); std::memcpy(raw, &v, 2); break; }
    case Type::UInt16: { auto v = static_cast<std::uint16_t>(value); std::memcpy(raw, &v, 2); break; }
    case Type::Int32: { auto v = static_cast<std::int32_t>(value); std::memcpy(raw, &v, 4); break; }
    case Type::UInt32: { auto v = static_cast<std::uint32_t>(value); std::memcpy(raw, &v, 4); break; }
    case Type::Float32: { auto v = static_cast<float>(value); std::memcpy(raw, &v, 4); break; }
    case Type::Float64: { std::memcpy(raw, &value, 8); break; }
  }
  if (swap)
    for (std::size_t i = 0; i < size / 2; ++i) std::swap(raw[i], raw[size - 1 - i]);
  out.append(reinterpret_cast<const char*>(raw), size);
}

void write_ascii(std::string& out, Type type, double value) {
  if (type == Type::Float32) append_number(out, static_cast<float>(value));
  else if (type == Type::Float64) append_number(out, value);
  else out += std::to_string(static_cast<std::int64_t>(std::nearbyint(value)));
}

Encoded PlyDocument::encode(const EncodeOptions& options) const {
  check_surface_sizes(surfaces_, {elements_[vertex_element_].count});
  if (options.format && *options.format != Format::Ply) return encode_plain(surfaces_, *options.format, options);
  const TriMesh& mesh = surfaces_.front();
  // Substitute the new positions (and normals) into a copy of the vertex element.
  Element vertex = elements_[vertex_element_];
  const char* axes[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    Property* p = vertex.find(axes[k]);
    for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
      // Written with the property's declared type: a value it cannot hold would be written as
      // "inf" (float) or wrap (integers), a file no reader takes back. Refused instead.
      const double value = mesh.V(i, k);
      const bool fits = is_integer(p->type) ? value >= type_min(p->type) && value <= type_max(p->type)
                                            : std::isfinite(value) && (p->type == Type::Float64 ||
                                                                       std::abs(value) <= std::numeric_limits<float>::max());
      if (!fits)
        throw UnsupportedError("the mesh cannot be written as PLY: vertex " + std::to_string(i) + " coordinate " + axes[k] +
                               " does not fit the file's " + type_name(p->type) + " property");
      p->values[static_cast<std::size_t>(i)] = value;
    }
  }
  if (has_normals_) {
    const Vertices N = vertex_normals(mesh.V, mesh.F);
    const char* names[3] = {"nx", "ny", "nz"};
    for (int k = 0; k < 3; ++k) {
      Property* p = vertex.find(names[k]);
      for (Eigen::Index i = 0; i < N.rows(); ++i) p->values[static_cast<std::size_t>(i)] = N(i, k);
    }
  }

  const bool host_little = std::endian::native == std::endian::little;
  const bool swap = encoding_ == Encoding::BinaryBig ? host_little : (encoding_ == Encoding::BinaryLittle && !host_little);
  std::string out = header_;
  CancelPoll cancel(options.cancel);
  for (std::size_t e = 0; e < elements_.size(); ++e) {
    const Element& element = e == vertex_element_ ? vertex : elements_[e];
    std::vector<std::size_t> cursor(element.properties.size(), 0);
    for (std::int64_t row = 0; row < element.count; ++row) {
      cancel.poll();
      for (std::size_t j = 0; j < element.properties.size(); ++j) {
        const Property& p = element.properties[j];
        if (encoding_ == Encoding::Ascii && j > 0) out += ' ';
        if (!p.is_list) {
          const double v = p.values[static_cast<std::size_t>(row)];
          encoding_ == Encoding::Ascii ? write_ascii(out, p.type, v) : write_binary(out, p.type, v, swap);
          continue;
        }
        const auto begin = p.offsets[static_cast<std::size_t>(row)], end = p.offsets[static_cast<std::size_t>(row) + 1];
        const auto n = static_cast<double>(end - begin);
        encoding_ == Encoding::Ascii ? write_ascii(out, p.count_type, n) : write_binary(out, p.count_type, n, swap);
        for (auto k = begin; k < end; ++k) {
          const double v = p.values[static_cast<std::size_t>(k)];
          if (encoding_ == Encoding::Ascii) {
            out += ' ';
            write_ascii(out, p.type, v);
          } else {
            write_binary(out, p.type, v, swap);
          }
        }
      }
      if (encoding_ == Encoding::Ascii) out += '\n';
    }
  }
  return {std::move(out), Compression::None};
}

// The header, up to end_header: the encoding, the elements and their properties.
void parse_header(LineReader& reader, PlyDocument& doc) {
  std::string_view line;
  bool have_format = false, ended = false;
  auto fail = [&](const std::string& message) -> void {
    fail_at_line("PLY header", reader, message);
  };
  while (reader.next(line)) {
    std::string_view rest = line;
    const std::string_view keyword = next_token(rest);
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
      break;
    }
    if (keyword == "format") {
      const std::string_view name = next_token(rest);
      if (name == "ascii") doc.encoding_ = Encoding::Ascii;
      else if (name == "binary_little_endian") doc.encoding_ = Encoding::BinaryLittle;
      else if (name == "binary_big_endian") doc.encoding_ = Encoding::BinaryBig;
      else fail("unknown format '" + std::string(name.substr(0, 32)) + "'");
      have_format = true;
    } else if (keyword == "element") {
      Element element;
      element.name = std::string(next_token(rest));
      if (element.name.empty() || !parse_integer(next_token(rest), element.count) || element.count < 0)
        fail("expected 'element <name> <count>'");
      doc.elements_.push_back(std::move(element));
    } else if (keyword == "property") {
      if (doc.elements_.empty()) fail("a property before any element");
      Property p;
      std::string_view type = next_token(rest);
      if (type == "list") {
        p.is_list = true;
        const auto count_type = type_from_name(next_token(rest));
        if (!count_type || !is_integer(*count_type)) fail("a list count type must be an integer type");
        p.count_type = *count_type;
        type = next_token(rest);
      }
      const auto t = type_from_name(type);
      if (!t) fail("unknown property type '" + std::string(type.substr(0, 32)) + "'");
      p.type = *t;
      p.name = std::string(next_token(rest));
      if (p.name.empty()) fail("a property without a name");
      doc.elements_.back().properties.push_back(std::move(p));
    } else {
      fail("unknown keyword '" + std::string(keyword.substr(0, 32)) + "'");
    }
  }
  if (!ended) throw FormatError("PLY: the header has no end_header line");
  if (!have_format) throw FormatError("PLY: the header has no format line");
}

// Locates the vertex and face elements and checks their shape before reading any data:
// returns their indices.
std::pair<std::size_t, std::size_t> locate_elements(PlyDocument& doc, const Limits& limits) {
  std::optional<std::size_t> vertex_index, face_index;
  for (std::size_t e = 0; e < doc.elements_.size(); ++e) {
    if (doc.elements_[e].name == "vertex") vertex_index = e;
    if (doc.elements_[e].name == "face") face_index = e;
  }
  if (!vertex_index) throw FormatError("PLY: no 'vertex' element");
  if (!face_index) throw FormatError("PLY: no 'face' element (point clouds are not supported)");
  Element& vertex = doc.elements_[*vertex_index];
  for (const char* axis : {"x", "y", "z"}) {
    const Property* p = vertex.find(axis);
    if (!p || p->is_list) throw FormatError(std::string("PLY: the vertex element has no scalar '") + axis + "' property");
  }
  const Property* nx = vertex.find("nx");
  const Property* ny = vertex.find("ny");
  const Property* nz = vertex.find("nz");
  doc.has_normals_ = nx && ny && nz && !nx->is_list && !ny->is_list && !nz->is_list;
  Element& face = doc.elements_[*face_index];
  const Property* indices = face.find("vertex_indices");
  if (!indices) indices = face.find("vertex_index");
  if (!indices || !indices->is_list) throw FormatError("PLY: the face element has no 'vertex_indices' list");
  if (!is_integer(indices->type)) throw FormatError("PLY: face vertex indices must have an integer type");
  check_count(vertex.count, limits.max_vertices, "vertices");
  check_count(face.count, limits.max_faces, "faces");
  doc.vertex_element_ = *vertex_index;

  return {*vertex_index, *face_index};
}

// The polygon mesh of the vertex element's x, y, z and the face element's index lists.
PolygonMesh polygon_mesh(Element& v, Element& f) {
  PolygonMesh poly;
  poly.V.resize(v.count, 3);
  const char* axes[3] = {"x", "y", "z"};
  for (int k = 0; k < 3; ++k) {
    const Property* p = v.find(axes[k]);
    for (std::int64_t i = 0; i < v.count; ++i) {
      const double value = p->values[static_cast<std::size_t>(i)];
      if (!std::isfinite(value)) throw FormatError("PLY: vertex " + std::to_string(i) + " has a non-finite coordinate");
      poly.V(i, k) = value;
    }
  }
  const Property* list = f.find("vertex_indices");
  if (!list) list = f.find("vertex_index");
  poly.offsets = list->offsets;
  poly.indices.assign(list->values.begin(), list->values.end());
  return poly;
}

}  // namespace

std::unique_ptr<MeshDocument> decode_ply(std::string_view bytes, const Limits& limits) {
  auto doc = std::make_unique<PlyDocument>();
  LineReader reader(bytes);
  std::string_view line;
  if (!reader.next(line) || trim(line) != "ply") throw FormatError("PLY: the input does not start with 'ply'");
  parse_header(reader, *doc);
  doc->header_.assign(bytes.substr(0, reader.position()));
  if (doc->header_.back() != '\n') doc->header_ += '\n';
  const auto [vertex_index, face_index] = locate_elements(*doc, limits);
  const std::string_view body = bytes.substr(reader.position());
  if (doc->encoding_ == Encoding::Ascii) {
    AsciiReader ascii(body);
    read_body(ascii, doc->elements_, 2, limits);
  } else {
    const bool host_little = std::endian::native == std::endian::little;
    BinaryReader binary(body, (doc->encoding_ == Encoding::BinaryLittle) != host_little);
    read_body(binary, doc->elements_, 1, limits);
  }

  const PolygonMesh poly = polygon_mesh(doc->elements_[vertex_index], doc->elements_[face_index]);
  doc->surfaces_.push_back(to_tri_mesh(poly));  // the core's documented error for non-triangles
  return doc;
}

}  // namespace mdn::io::detail
