// Internal to mdn_io: what the glTF reader (gltf_read.cpp) and writer (gltf_write.cpp) share:
// the accessor and primitive model, the bounds-checked Reader of a model's buffers and the
// document (GltfDocument) that decoding fills and encoding writes back.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/detail.h"
#include "core/io/tinygltf_load.h"

namespace mdn::io::detail::gltf {

using Json = nlohmann::ordered_json;
inline constexpr const char* kDraco = "KHR_draco_mesh_compression";
inline constexpr const char* kMeshopt = "EXT_meshopt_compression";
inline constexpr int kFloat = 5126, kUInt = 5125, kUShort = 5123, kUByte = 5121, kShort = 5122, kByte = 5120;
inline constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

inline int component_size(int type) {
  switch (type) {
    case kByte: case kUByte: return 1;
    case kShort: case kUShort: return 2;
    case kUInt: case kFloat: return 4;
    default: return 0;
  }
}

inline int type_components(int type) {
  switch (type) {
    case TINYGLTF_TYPE_SCALAR: return 1;
    case TINYGLTF_TYPE_VEC2: return 2;
    case TINYGLTF_TYPE_VEC3: return 3;
    case TINYGLTF_TYPE_VEC4: return 4;
    case TINYGLTF_TYPE_MAT2: return 4;
    case TINYGLTF_TYPE_MAT3: return 9;
    case TINYGLTF_TYPE_MAT4: return 16;
    default: return 0;
  }
}

inline const char* type_name(int components) {
  switch (components) {
    case 1: return "SCALAR";
    case 2: return "VEC2";
    case 3: return "VEC3";
    default: return "VEC4";
  }
}

// One vertex attribute, tightly packed: count x components values of component_type.
struct Attribute {
  std::string semantic;
  int accessor = -1;  // the input accessor
  int component_type = kFloat;
  bool normalized = false;
  int components = 3;
  std::int64_t count = 0;
  std::vector<std::uint8_t> bytes;
  std::size_t element_size() const { return static_cast<std::size_t>(components * component_size(component_type)); }
  // Reads component k of element i as a number (KHR_mesh_quantization's dequantisation for
  // normalized integers: max(c / (2^(n-1) - 1), -1) signed, c / (2^n - 1) unsigned; with
  // `dequantize` false, the stored integer).
  double value(std::int64_t i, int k, bool dequantize = true) const {
    const bool normalized = this->normalized && dequantize;
    const std::uint8_t* p = bytes.data() + static_cast<std::size_t>(i) * element_size() +
                            static_cast<std::size_t>(k * component_size(component_type));
    switch (component_type) {
      case kFloat: { float v; std::memcpy(&v, p, 4); return v; }
      case kUInt: { std::uint32_t v; std::memcpy(&v, p, 4); return v; }
      case kUShort: { std::uint16_t v; std::memcpy(&v, p, 2); return normalized ? v / 65535.0 : v; }
      case kShort: { std::int16_t v; std::memcpy(&v, p, 2); return normalized ? std::max(v / 32767.0, -1.0) : v; }
      case kUByte: return normalized ? p[0] / 255.0 : p[0];
      case kByte: { auto v = static_cast<std::int8_t>(p[0]); return normalized ? std::max(v / 127.0, -1.0) : v; }
      default: return 0;
    }
  }
};

struct Primitive {
  int mesh = 0, index = 0;
  bool from_draco = false;
  bool has_targets = false;
  std::vector<Attribute> attributes;       // in the input's attribute order
  std::vector<std::uint32_t> triangles;    // triangle list (strips / fans converted), local points
  std::int64_t points = 0;
  std::int64_t point_offset = 0;           // into the surface's concatenated points
  int position = -1, normal = -1, tangent = -1;  // indices into attributes
};

struct Surface {
  int mesh = 0;
  std::vector<Primitive> primitives;
  std::vector<std::int32_t> point_to_weld;  // concatenated points -> welded vertex
  std::vector<std::int64_t> normal_slot;    // concatenated points -> normal slot (-1: none)
  std::int64_t normal_slots = 0;
  std::int64_t welded = 0;
};

// Bounds-checked access to the model's buffers.
class Reader {
 public:
  Reader(const tinygltf::Model& model, const Limits& limits) : model_(model), limits_(limits), cancel_(limits.cancel) {}

  std::string_view view_bytes(int index, const std::string& what) const {
    if (index < 0 || index >= static_cast<int>(model_.bufferViews.size()))
      throw FormatError(what + ": buffer view " + std::to_string(index) + " does not exist");
    const auto& view = model_.bufferViews[static_cast<std::size_t>(index)];
    if (view.buffer < 0 || view.buffer >= static_cast<int>(model_.buffers.size()))
      throw FormatError(what + ": buffer view " + std::to_string(index) + " names a missing buffer");
    const auto& data = model_.buffers[static_cast<std::size_t>(view.buffer)].data;
    if (view.byteOffset > data.size() || view.byteLength > data.size() - view.byteOffset)
      throw FormatError(what + ": buffer view " + std::to_string(index) + " reaches past the end of its buffer");
    return std::string_view(reinterpret_cast<const char*>(data.data()) + view.byteOffset, view.byteLength);
  }

  void charge(std::int64_t bytes, const std::string& what) {
    decoded_ += bytes;
    if (decoded_ > limits_.max_decoded_bytes)
      throw LimitError(what + ": decoding would take more than the limit of " + std::to_string(limits_.max_decoded_bytes) + " bytes");
  }

  Attribute read(int index, const std::string& what) {
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      throw FormatError(what + ": accessor " + std::to_string(index) + " does not exist");
    const auto& acc = model_.accessors[static_cast<std::size_t>(index)];
    Attribute a;
    a.accessor = index;
    a.component_type = acc.componentType;
    a.normalized = acc.normalized;
    a.components = type_components(acc.type);
    a.count = static_cast<std::int64_t>(acc.count);
    const std::string where = what + " (accessor " + std::to_string(index) + ")";
    if (component_size(a.component_type) == 0) throw FormatError(where + ": unknown componentType " + std::to_string(a.component_type));
    if (a.components == 0 || a.components > 4) throw FormatError(where + ": type must be SCALAR or VEC2..VEC4");
    if (a.count < 0 || a.count > limits_.max_vertices * 3)
      throw LimitError(where + ": count " + std::to_string(a.count) + " exceeds the limits");
    const std::size_t element = a.element_size();
    const auto total = static_cast<std::int64_t>(element) * a.count;
    charge(total, where);
    if (acc.bufferView >= 0) {
      const std::string_view data = view_bytes(acc.bufferView, where);
      const auto& view = model_.bufferViews[static_cast<std::size_t>(acc.bufferView)];
      const std::size_t stride = view.byteStride ? view.byteStride : element;
      if (stride < element) throw FormatError(where + ": byteStride is smaller than an element");
      if (a.count > 0 && (acc.byteOffset > data.size() ||
                          (static_cast<std::size_t>(a.count) - 1) > (data.size() - acc.byteOffset - std::min(data.size() - acc.byteOffset, element)) / stride ||
                          data.size() - acc.byteOffset < element))
        throw FormatError(where + ": " + std::to_string(a.count) + " elements do not fit in buffer view " + std::to_string(acc.bufferView));
      a.bytes.resize(static_cast<std::size_t>(total));
      for (std::int64_t i = 0; i < a.count; ++i, cancel_.poll())
        std::memcpy(a.bytes.data() + static_cast<std::size_t>(i) * element,
                    data.data() + acc.byteOffset + static_cast<std::size_t>(i) * stride, element);
    } else {
      a.bytes.assign(static_cast<std::size_t>(total), 0);  // no buffer view: zeros (sparse may fill)
    }
    if (acc.sparse.isSparse) apply_sparse(acc, a, where);
    return a;
  }

  std::vector<std::uint32_t> read_indices(int index, std::int64_t points, const std::string& what) {
    Attribute a = read(index, what + " indices");
    if (a.components != 1 || (a.component_type != kUByte && a.component_type != kUShort && a.component_type != kUInt))
      throw FormatError(what + ": indices must be SCALAR unsigned byte, short or int");
    if (a.count > limits_.max_faces * 3) throw LimitError(what + ": more indices than the face limit allows");
    std::vector<std::uint32_t> out(static_cast<std::size_t>(a.count));
    for (std::int64_t i = 0; i < a.count; ++i) {
      cancel_.poll();
      const double v = a.value(i, 0);
      if (v >= static_cast<double>(points))
        throw FormatError(what + ": index " + std::to_string(static_cast<std::int64_t>(v)) + " is out of range (" +
                          std::to_string(points) + " vertices)");
      out[static_cast<std::size_t>(i)] = static_cast<std::uint32_t>(v);
    }
    return out;
  }

  const tinygltf::Model& model() const { return model_; }
  const Limits& limits() const { return limits_; }
  CancelPoll& cancel() { return cancel_; }

 private:
  void apply_sparse(const tinygltf::Accessor& acc, Attribute& a, const std::string& where) {
    const auto n = static_cast<std::int64_t>(acc.sparse.count);
    if (n < 1 || n > a.count) throw FormatError(where + ": sparse count out of range");
    const int index_size = component_size(acc.sparse.indices.componentType);
    if (acc.sparse.indices.componentType != kUByte && acc.sparse.indices.componentType != kUShort &&
        acc.sparse.indices.componentType != kUInt)
      throw FormatError(where + ": sparse indices must be unsigned byte, short or int");
    const std::string_view indices = view_bytes(acc.sparse.indices.bufferView, where + " sparse indices");
    const std::string_view values = view_bytes(acc.sparse.values.bufferView, where + " sparse values");
    const auto io = static_cast<std::size_t>(acc.sparse.indices.byteOffset);
    const auto vo = static_cast<std::size_t>(acc.sparse.values.byteOffset);
    const std::size_t element = a.element_size();
    if (io > indices.size() || static_cast<std::size_t>(n) > (indices.size() - io) / static_cast<std::size_t>(index_size) ||
        vo > values.size() || static_cast<std::size_t>(n) > (values.size() - vo) / element)
      throw FormatError(where + ": sparse data does not fit in its buffer views");
    std::int64_t previous = -1;
    for (std::int64_t s = 0; s < n; ++s) {
      std::uint32_t target = 0;
      const char* p = indices.data() + io + static_cast<std::size_t>(s * index_size);
      if (index_size == 1) target = static_cast<std::uint8_t>(*p);
      else if (index_size == 2) { std::uint16_t v; std::memcpy(&v, p, 2); target = v; }
      else std::memcpy(&target, p, 4);
      if (static_cast<std::int64_t>(target) >= a.count || static_cast<std::int64_t>(target) <= previous)
        throw FormatError(where + ": sparse indices must be increasing and below count");
      previous = target;
      std::memcpy(a.bytes.data() + target * element, values.data() + vo + static_cast<std::size_t>(s) * element, element);
    }
  }

  const tinygltf::Model& model_;
  const Limits& limits_;
  CancelPoll cancel_;
  std::int64_t decoded_ = 0;
};

class GltfDocument final : public MeshDocument {
 public:
  Format format() const override { return format_; }
  std::vector<TriMesh>& surfaces() override { return meshes_; }
  std::vector<std::string> notes() const override { return notes_; }
  Compression compression() const override { return compression_; }
  std::vector<std::vector<Eigen::Matrix4d>> placements() const override;
  Encoded encode(const EncodeOptions& options) const override {
    try {
      return encode_json(options);
    } catch (const Json::exception& e) {  // the input's JSON, in a shape decoding let through
      throw FormatError(std::string("glTF: unexpected JSON content (") + e.what() + ")");
    }
  }
  Encoded encode_json(const EncodeOptions& options) const;

  Format format_ = Format::Glb;
  Compression compression_ = Compression::None;  // the input's
  Json json_;
  tinygltf::Model model_;
  std::vector<Surface> surfaces_;
  std::vector<TriMesh> meshes_;
  std::vector<std::string> notes_;
};

// A GLB container around a JSON chunk (padded with spaces) and a BIN chunk (if any).
std::string make_glb(std::string text, std::string_view bin);

// gltf_json.cpp: the asset's JSON before tinygltf sees it.
// The JSON chunk of a GLB, with the container's lengths checked.
std::string_view glb_json(std::string_view bytes);
// Parses the JSON with its nesting depth and size bounded (Limits), checks the shape of what
// the decoder reads, and charges `bytes` with what the parsed scene will hold.
Json parse_bounded(std::string_view text, const Limits& limits, std::int64_t& bytes);
// A .gltf's external buffers or images (`key`) read from `resource_dir` and embedded (images as
// data URIs; buffers, given `buffers`, as their bytes in element i, their uri cut to a data URI's
// header, the file's size checked against byteLength); without a folder any external URI is an
// UnsupportedError. Returns how many were read.
int resolve_external(Json& json, const char* key, const std::string* resource_dir, const Limits& limits,
                     std::int64_t& read_bytes, std::vector<std::vector<unsigned char>>* buffers = nullptr);
// Whether a required extension is one this adapter reads or carries over (glTF 2.0, 3.12).
bool understood_extension(std::string_view name);

// gltf_data_uri.cpp: a .gltf's data-URI buffers decoded from the body (decision 82).
// A string literal of the body whose text starts with "data:" (not an object key; no escape but
// "\/"): its text's place in the body.
struct LiftedLiteral {
  std::size_t offset = 0, length = 0, escapes = 0;
};
// The body's JSON with each such literal replaced by a short placeholder (`text`; empty, and no
// literals, when there is none).
struct LiftedJson {
  std::string text;
  std::vector<LiftedLiteral> literals;
};
LiftedJson lift_data_uris(std::string_view text);
// Resolves the placeholders of the parsed `json`: each buffer's data URI is checked (a media
// type tinygltf reads, base64, its byteLength) and decoded from `body` into element b of the
// result (empty for a buffer that had none), its uri cut to the data URI's header; its byteLength
// is added to `charged` and checked against limits.max_decoded_bytes first. Every other
// placeholder (an image's uri, an extra) gets its text back. Throws FormatError or LimitError.
std::vector<std::vector<unsigned char>> decode_lifted(Json& json, std::string_view body, const LiftedJson& lifted,
                                                      const Limits& limits, std::int64_t& charged);

}  // namespace mdn::io::detail::gltf
