// glTF 2.0 (.glb, and .gltf with embedded data URIs).
//
// Reading: tinygltf parses the container and decodes the embedded buffers (no file system,
// no images); every accessor read here is bounds-checked against its buffer view and buffer
// and against Limits before anything is allocated. KHR_draco_mesh_compression payloads are
// decoded with Draco's core Decoder; KHR_mesh_quantization component types, sparse
// accessors, strips and fans and non-indexed primitives are read. EXT_meshopt_compression buffer
// views are decoded with libmeshoptimizer (meshopt_codec.h) before anything reads them; the
// output is written without it (its views hold the decoded bytes).
//
// Surfaces: one per mesh that has TRIANGLES / TRIANGLE_STRIP / TRIANGLE_FAN primitives
// (however many nodes instance it); all those primitives' vertices are welded by position.
// Points and lines pass through untouched.
//
// Writing: the output JSON is the input JSON with only the denoised primitives, their
// accessors, the buffer views and the buffers changed. Materials, textures, images, nodes,
// animations, names, extras and unknown extensions are carried over verbatim (key order
// included). Attributes other than POSITION / NORMAL / TANGENT keep their values exactly
// (with Draco, they are stored losslessly unless the caller asks for quantisation). NORMAL
// is recomputed keeping the input's hard edges; TANGENT is dropped (see notes()). Unused
// buffer views are removed and all buffers are merged into one, so replaced geometry does
// not stay in the file.
#include <draco/mesh/mesh.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <string>
#include <tuple>

#include "core/io/detail.h"
#include "core/io/draco_codec.h"
#include "core/io/meshopt_codec.h"
#include "core/io/plain.h"
#include "core/io/tinygltf_load.h"
#include "core/io/weld.h"

namespace mdn::io::detail {
namespace {

using Json = nlohmann::ordered_json;
constexpr const char* kDraco = "KHR_draco_mesh_compression";
constexpr const char* kMeshopt = "EXT_meshopt_compression";
constexpr int kFloat = 5126, kUInt = 5125, kUShort = 5123, kUByte = 5121, kShort = 5122, kByte = 5120;
constexpr int kArrayBuffer = 34962, kElementArrayBuffer = 34963;

int component_size(int type) {
  switch (type) {
    case kByte: case kUByte: return 1;
    case kShort: case kUShort: return 2;
    case kUInt: case kFloat: return 4;
    default: return 0;
  }
}

int type_components(int type) {
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

const char* type_name(int components) {
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
  // normalized integers: max(c / (2^(n-1) - 1), -1) signed, c / (2^n - 1) unsigned).
  double value(std::int64_t i, int k) const {
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

class GltfDocument;

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

int gltf_component_type(draco::DataType type) {
  switch (type) {
    case draco::DT_INT8: return kByte;
    case draco::DT_UINT8: return kUByte;
    case draco::DT_INT16: return kShort;
    case draco::DT_UINT16: return kUShort;
    case draco::DT_UINT32: return kUInt;
    case draco::DT_FLOAT32: return kFloat;
    default: return 0;
  }
}

draco::DataType draco_data_type(int component_type) {
  switch (component_type) {
    case kByte: return draco::DT_INT8;
    case kUByte: return draco::DT_UINT8;
    case kShort: return draco::DT_INT16;
    case kUShort: return draco::DT_UINT16;
    case kUInt: return draco::DT_UINT32;
    default: return draco::DT_FLOAT32;
  }
}

draco::GeometryAttribute::Type draco_semantic(const std::string& semantic) {
  if (semantic == "POSITION") return draco::GeometryAttribute::POSITION;
  if (semantic == "NORMAL") return draco::GeometryAttribute::NORMAL;
  if (semantic.rfind("TEXCOORD_", 0) == 0) return draco::GeometryAttribute::TEX_COORD;
  if (semantic.rfind("COLOR_", 0) == 0) return draco::GeometryAttribute::COLOR;
  return draco::GeometryAttribute::GENERIC;
}

// Reads a KHR_draco_mesh_compression primitive: every attribute from the payload.
void read_draco_primitive(Reader& reader, const Json& ext, const tinygltf::Primitive& prim, Primitive& out,
                          const std::string& what) {
  if (!ext.is_object() || !ext.contains("bufferView") || !ext["bufferView"].is_number_integer() ||
      !ext.contains("attributes") || !ext["attributes"].is_object())
    throw FormatError(what + ": " + kDraco + " needs a bufferView and attributes");
  const std::string_view payload = reader.view_bytes(ext["bufferView"].get<int>(), what);
  const auto mesh = draco_decode(payload, what, reader.limits());
  reader.charge(static_cast<std::int64_t>(mesh->num_points()) * 64 + static_cast<std::int64_t>(mesh->num_faces()) * 12, what);
  out.points = mesh->num_points();
  for (const auto& [semantic, accessor] : prim.attributes) {
    if (!ext["attributes"].contains(semantic) || !ext["attributes"][semantic].is_number_integer())
      throw UnsupportedError(what + ": attribute " + semantic + " is outside the Draco payload");
    const auto* att = mesh->GetAttributeByUniqueId(ext["attributes"][semantic].get<std::uint32_t>());
    if (att == nullptr) throw FormatError(what + ": the Draco payload has no attribute for " + semantic);
    Attribute a;
    a.semantic = semantic;
    a.accessor = accessor;
    a.component_type = gltf_component_type(att->data_type());
    if (a.component_type == 0) throw UnsupportedError(what + ": Draco attribute " + semantic + " has an unsupported data type");
    a.components = att->num_components();
    if (a.components < 1 || a.components > 4) throw FormatError(what + ": Draco attribute " + semantic + " has a bad size");
    if (accessor >= 0 && accessor < static_cast<int>(reader.model().accessors.size()))
      a.normalized = reader.model().accessors[static_cast<std::size_t>(accessor)].normalized;
    a.count = out.points;
    const std::size_t element = a.element_size();
    if (static_cast<std::size_t>(att->byte_stride()) != element)
      throw FormatError(what + ": Draco attribute " + semantic + " has an unexpected layout");
    a.bytes.resize(element * static_cast<std::size_t>(out.points));
    for (draco::PointIndex p(0); p < mesh->num_points(); ++p)
      att->GetValue(att->mapped_index(p), a.bytes.data() + element * p.value());
    out.attributes.push_back(std::move(a));
  }
  const Triangles F = draco_faces(*mesh);
  out.triangles.assign(F.data(), F.data() + F.size());
  out.from_draco = true;
}

// Converts strips and fans to lists (glTF 2.0 spec, 3.7.2.1 "Topology types").
std::vector<std::uint32_t> to_triangle_list(const std::vector<std::uint32_t>& idx, int mode, const std::string& what) {
  std::vector<std::uint32_t> out;
  if (mode == TINYGLTF_MODE_TRIANGLES) {
    if (idx.size() % 3 != 0) throw FormatError(what + ": a TRIANGLES primitive's index count is not a multiple of 3");
    return idx;
  }
  if (idx.size() < 3) throw FormatError(what + ": a strip or fan needs at least 3 vertices");
  out.reserve((idx.size() - 2) * 3);
  for (std::size_t i = 0; i + 2 < idx.size(); ++i) {
    if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
      // Triangle i is (v_i, v_{i+1+i%2}, v_{i+2-i%2}): keeps a consistent winding.
      out.insert(out.end(), {idx[i], idx[i + 1 + i % 2], idx[i + 2 - i % 2]});
    } else {
      out.insert(out.end(), {idx[i + 1], idx[i + 2], idx[0]});
    }
  }
  return out;
}

class GltfDocument final : public MeshDocument {
 public:
  Format format() const override { return format_; }
  std::vector<TriMesh>& surfaces() override { return meshes_; }
  std::vector<std::string> notes() const override { return notes_; }
  Compression compression() const override { return compression_; }
  std::vector<std::vector<Eigen::Matrix4d>> placements() const override;
  std::string encode(const EncodeOptions& options) const override {
    try {
      return encode_json(options);
    } catch (const Json::exception& e) {  // the input's JSON, in a shape decoding let through
      throw FormatError(std::string("glTF: unexpected JSON content (") + e.what() + ")");
    }
  }
  std::string encode_json(const EncodeOptions& options) const;

  Format format_ = Format::Glb;
  Compression compression_ = Compression::None;  // the input's
  Json json_;
  tinygltf::Model model_;
  std::vector<Surface> surfaces_;
  std::vector<TriMesh> meshes_;
  std::vector<std::string> notes_;
};

// A node's local matrix (glTF 2.0, 5.25): `matrix` if given, else T * R * S.
Eigen::Matrix4d local_matrix(const tinygltf::Node& node) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
  if (node.matrix.size() == 16) {
    for (int i = 0; i < 16; ++i) m(i % 4, i / 4) = node.matrix[static_cast<std::size_t>(i)];  // column-major
    return m;
  }
  Eigen::Affine3d t = Eigen::Affine3d::Identity();
  if (node.translation.size() == 3) t.translate(Eigen::Vector3d(node.translation[0], node.translation[1], node.translation[2]));
  if (node.rotation.size() == 4)  // (x, y, z, w)
    t.rotate(Eigen::Quaterniond(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]).normalized());
  if (node.scale.size() == 3) t.scale(Eigen::Vector3d(node.scale[0], node.scale[1], node.scale[2]));
  return t.matrix();
}

std::vector<std::vector<Eigen::Matrix4d>> GltfDocument::placements() const {
  const auto& nodes = model_.nodes;
  const auto n = static_cast<int>(nodes.size());
  std::vector<int> surface_of_mesh(model_.meshes.size(), -1);
  for (std::size_t i = 0; i < surfaces_.size(); ++i) surface_of_mesh[static_cast<std::size_t>(surfaces_[i].mesh)] = static_cast<int>(i);
  std::vector<int> roots;
  if (!model_.scenes.empty()) {
    const int scene = model_.defaultScene >= 0 && model_.defaultScene < static_cast<int>(model_.scenes.size()) ? model_.defaultScene : 0;
    roots = model_.scenes[static_cast<std::size_t>(scene)].nodes;
  } else {
    std::vector<bool> child(nodes.size(), false);
    for (const auto& node : nodes)
      for (int c : node.children)
        if (c >= 0 && c < n) child[static_cast<std::size_t>(c)] = true;
    for (int i = 0; i < n; ++i)
      if (!child[static_cast<std::size_t>(i)]) roots.push_back(i);
  }
  // Depth-first, without recursion; a node is visited once (the spec makes the hierarchy a
  // forest; a malformed asset with a cycle or a shared child stops there).
  std::vector<std::vector<Eigen::Matrix4d>> out(surfaces_.size());
  std::vector<bool> visited(nodes.size(), false);
  std::vector<std::pair<int, Eigen::Matrix4d>> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.emplace_back(*it, Eigen::Matrix4d::Identity());
  while (!stack.empty()) {
    const auto [index, parent] = stack.back();
    stack.pop_back();
    if (index < 0 || index >= n || visited[static_cast<std::size_t>(index)]) continue;
    visited[static_cast<std::size_t>(index)] = true;
    const tinygltf::Node& node = nodes[static_cast<std::size_t>(index)];
    const Eigen::Matrix4d world = parent * local_matrix(node);
    if (node.mesh >= 0 && node.mesh < static_cast<int>(surface_of_mesh.size()) && surface_of_mesh[static_cast<std::size_t>(node.mesh)] >= 0)
      out[static_cast<std::size_t>(surface_of_mesh[static_cast<std::size_t>(node.mesh)])].push_back(world);
    for (auto c = node.children.rbegin(); c != node.children.rend(); ++c) stack.emplace_back(*c, world);
  }
  return out;
}

// ---- encoding helpers ----

struct Output {
  Json json;
  std::vector<std::string> new_views;  // bytes of buffer views appended to json["bufferViews"]
  std::int64_t old_views = 0;
  std::vector<int> claimed;            // accessor -> times claimed by a rewritten primitive

  int append_view(std::string bytes, std::optional<int> target, std::optional<int> stride = std::nullopt) {
    Json view = Json::object();
    view["buffer"] = 0;
    view["byteOffset"] = 0;
    view["byteLength"] = bytes.size();
    if (stride) view["byteStride"] = *stride;
    if (target) view["target"] = *target;
    json["bufferViews"].push_back(view);
    new_views.push_back(std::move(bytes));
    return static_cast<int>(json["bufferViews"].size()) - 1;
  }
  // The accessor to rewrite for a primitive: the input's own the first time, if nothing but
  // the denoised primitives uses it (so no stale copy stays behind); otherwise a new copy.
  int claim(int accessor, const std::vector<int>& external_uses) {
    if (accessor >= 0 && accessor < static_cast<int>(external_uses.size()) &&
        external_uses[static_cast<std::size_t>(accessor)] == 0 && claimed[static_cast<std::size_t>(accessor)]++ == 0)
      return accessor;
    Json copy = accessor >= 0 && accessor < static_cast<int>(json["accessors"].size()) ? json["accessors"][accessor] : Json::object();
    json["accessors"].push_back(copy);
    return static_cast<int>(json["accessors"].size()) - 1;
  }
};

// Every index that points into "accessors": how many places use each accessor.
std::vector<int> accessor_uses(const Json& json) {
  std::vector<int> uses(json.contains("accessors") ? json["accessors"].size() : 0, 0);
  auto use = [&](const Json& v) {
    if (v.is_number_integer() && v.get<std::int64_t>() >= 0 && v.get<std::size_t>() < uses.size()) ++uses[v.get<std::size_t>()];
  };
  for (const auto& mesh : json.value("meshes", Json::array()))
    for (const auto& prim : mesh.value("primitives", Json::array())) {
      const Json attributes = prim.value("attributes", Json::object());  // named: items() must not outlive it
      for (const auto& [k, v] : attributes.items()) use(v);
      if (prim.contains("indices")) use(prim["indices"]);
      for (const auto& target : prim.value("targets", Json::array()))
        for (const auto& [k, v] : target.items()) use(v);
    }
  for (const auto& skin : json.value("skins", Json::array()))
    if (skin.contains("inverseBindMatrices")) use(skin["inverseBindMatrices"]);
  for (const auto& anim : json.value("animations", Json::array()))
    for (const auto& sampler : anim.value("samplers", Json::array())) {
      if (sampler.contains("input")) use(sampler["input"]);
      if (sampler.contains("output")) use(sampler["output"]);
    }
  for (const auto& node : json.value("nodes", Json::array())) {
    const Json instancing = node.value("extensions", Json::object()).value("EXT_mesh_gpu_instancing", Json::object());
    const Json attributes = instancing.value("attributes", Json::object());
    for (const auto& [k, v] : attributes.items()) use(v);
  }
  return uses;
}

// Applies f to every integer "bufferView" property anywhere in the JSON (accessors, sparse,
// images, Draco and unknown extensions alike).
template <class F>
void for_each_view_ref(Json& node, F&& f) {
  if (node.is_object()) {
    for (auto& [key, value] : node.items()) {
      if (key == "bufferView" && value.is_number_integer()) f(value);
      else for_each_view_ref(value, f);
    }
  } else if (node.is_array()) {
    for (auto& value : node) for_each_view_ref(value, f);
  }
}

// Removes extensions[name] from a JSON object, and "extensions" if that leaves it empty.
void erase_extension(Json& object, const char* name) {
  const auto it = object.find("extensions");
  if (it == object.end() || !it->is_object()) return;
  it->erase(name);
  if (it->empty()) object.erase("extensions");
}

void pad_to_4(std::string& bytes, char fill) {
  while (bytes.size() % 4) bytes += fill;
}

// Tightly packed attribute bytes, each element padded to a multiple of 4 bytes as glTF
// requires of vertex attributes (returns the stride used, 0 when no padding was needed).
int packed_vertex_bytes(const Attribute& a, std::string& out) {
  const std::size_t element = a.element_size();
  const std::size_t stride = (element + 3) / 4 * 4;
  out.assign(stride * static_cast<std::size_t>(a.count), '\0');
  for (std::int64_t i = 0; i < a.count; ++i)
    std::memcpy(out.data() + stride * static_cast<std::size_t>(i), a.bytes.data() + element * static_cast<std::size_t>(i), element);
  return stride == element ? 0 : static_cast<int>(stride);
}

Attribute float_attribute(const std::string& semantic, int accessor, const Vertices& values) {
  Attribute a;
  a.semantic = semantic;
  a.accessor = accessor;
  a.component_type = kFloat;
  a.components = 3;
  a.count = values.rows();
  a.bytes.resize(static_cast<std::size_t>(a.count) * 12);
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (int k = 0; k < 3; ++k) {
      const auto v = static_cast<float>(values(i, k));
      std::memcpy(a.bytes.data() + static_cast<std::size_t>(i * 12 + k * 4), &v, 4);
    }
  return a;
}

// Accessor JSON for attribute data: keeps name/extras/extensions of the input accessor.
void set_accessor(Json& acc, const Attribute& a, std::optional<int> view) {
  acc.erase("sparse");
  acc.erase("byteOffset");
  if (view) acc["bufferView"] = *view;
  else acc.erase("bufferView");
  acc["componentType"] = a.component_type;
  if (a.normalized) acc["normalized"] = true;
  else acc.erase("normalized");
  acc["count"] = a.count;
  acc["type"] = type_name(a.components);
  acc.erase("min");
  acc.erase("max");
  if (a.semantic == "POSITION" && a.count > 0) {
    Json lo = Json::array(), hi = Json::array();
    for (int k = 0; k < 3; ++k) {
      double mn = a.value(0, k), mx = mn;
      for (std::int64_t i = 1; i < a.count; ++i) {
        mn = std::min(mn, a.value(i, k));
        mx = std::max(mx, a.value(i, k));
      }
      lo.push_back(mn);
      hi.push_back(mx);
    }
    acc["min"] = lo;
    acc["max"] = hi;
  }
}

// A GLB container: header, JSON chunk (padded with spaces), BIN chunk if any (glTF 2.0, 4.4).
std::string make_glb(std::string text, std::string_view bin) {
  pad_to_4(text, ' ');
  std::string glb;
  const auto u32 = [&glb](std::uint32_t v) { glb.append(reinterpret_cast<const char*>(&v), 4); };
  const std::size_t total = 12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size());
  glb.append("glTF", 4);
  u32(2);
  u32(static_cast<std::uint32_t>(total));
  u32(static_cast<std::uint32_t>(text.size()));
  u32(0x4E4F534A);  // "JSON"
  glb += text;
  if (!bin.empty()) {
    u32(static_cast<std::uint32_t>(bin.size()));
    u32(0x004E4942);  // "BIN\0"
    glb.append(bin);
  }
  return glb;
}

std::string GltfDocument::encode_json(const EncodeOptions& options) const {
  std::vector<std::int64_t> counts;
  for (const auto& s : surfaces_) counts.push_back(s.welded);
  check_surface_sizes(meshes_, counts);
  const Format target = options.format.value_or(format_);
  if (target != Format::Glb && target != Format::Gltf) return encode_plain(meshes_, target, options);
  check_float_coordinates(meshes_, target);
  const Compression compression = resolve_compression(options, compression_);

  Output out;
  out.json = json_;
  if (!out.json.contains("bufferViews")) out.json["bufferViews"] = Json::array();
  if (!out.json.contains("accessors")) out.json["accessors"] = Json::array();
  out.old_views = static_cast<std::int64_t>(out.json["bufferViews"].size());
  // Uses of each accessor outside the denoised primitives (lines, animations, skins, ...).
  std::vector<int> uses = accessor_uses(json_);
  for (const auto& surface : surfaces_)
    for (const auto& prim : surface.primitives) {
      const Json& pj = json_["meshes"][prim.mesh]["primitives"][prim.index];
      for (const auto& [semantic, acc] : pj["attributes"].items())
        if (acc.is_number_integer() && acc.get<std::size_t>() < uses.size()) --uses[acc.get<std::size_t>()];
      if (pj.contains("indices") && pj["indices"].is_number_integer() && pj["indices"].get<std::size_t>() < uses.size())
        --uses[pj["indices"].get<std::size_t>()];
    }
  out.claimed.assign(uses.size(), 0);

  for (std::size_t s = 0; s < surfaces_.size(); ++s) {
    const Surface& surface = surfaces_[s];
    const TriMesh& mesh = meshes_[s];
    // Recomputed normals, one per slot (welded vertex x input normal): hard edges stay split.
    Vertices slot_normals;
    if (surface.normal_slots > 0) {
      Triangles FW(mesh.F.rows(), 3);
      std::vector<std::int64_t> corner_slot(static_cast<std::size_t>(mesh.F.rows()) * 3, -1);
      Eigen::Index f = 0;
      for (const auto& prim : surface.primitives)
        for (std::size_t c = 0; c < prim.triangles.size(); ++c) {
          const auto point = static_cast<std::size_t>(prim.point_offset) + prim.triangles[c];
          corner_slot[static_cast<std::size_t>(f) * 3 + c % 3] = surface.normal_slot[point];
          if (c % 3 == 2) ++f;
        }
      slot_normals = accumulate_normals(mesh.V, mesh.F, corner_slot, surface.normal_slots);
    }

    // One position grid for every Draco payload of this mesh, slightly larger than its box
    // so that float rounding of the bounds cannot push a vertex outside.
    QuantizationBox box;
    {
      const Eigen::RowVector3d lo = mesh.V.colwise().minCoeff(), hi = mesh.V.colwise().maxCoeff();
      const double range = std::max((hi - lo).maxCoeff(), 1e-12) * (1 + 1e-5);
      for (int k = 0; k < 3; ++k) box.origin[k] = static_cast<float>(lo(k) - range * 1e-6);
      box.range = static_cast<float>(range * (1 + 4e-6));
    }
    // Uncompressed primitives of one mesh that shared an input accessor share its rewrite:
    // the same points weld to the same vertices, so the new data is the same.
    std::map<std::pair<int, std::string>, int> rewritten;
    for (const auto& prim : surface.primitives) {
      Json& pj = out.json["meshes"][prim.mesh]["primitives"][prim.index];
      // New per-point positions and normals.
      Vertices P(prim.points, 3), N;
      for (std::int64_t p = 0; p < prim.points; ++p)
        P.row(p) = mesh.V.row(surface.point_to_weld[static_cast<std::size_t>(prim.point_offset + p)]);
      if (prim.normal >= 0) {
        N.resize(prim.points, 3);
        const Attribute& original = prim.attributes[static_cast<std::size_t>(prim.normal)];
        for (std::int64_t p = 0; p < prim.points; ++p) {
          const std::int64_t slot = surface.normal_slot[static_cast<std::size_t>(prim.point_offset + p)];
          const Vec3 n = slot_normals.row(slot);
          // A point on no face keeps its input normal.
          N.row(p) = n.squaredNorm() > 0 ? n.transpose() : Eigen::RowVector3d(original.value(p, 0), original.value(p, 1), original.value(p, 2));
        }
      }
      std::vector<Attribute> attributes;
      for (std::size_t i = 0; i < prim.attributes.size(); ++i) {
        const Attribute& a = prim.attributes[i];
        if (static_cast<int>(i) == prim.tangent) continue;  // dropped (see notes)
        if (static_cast<int>(i) == prim.position) attributes.push_back(float_attribute("POSITION", a.accessor, P));
        else if (static_cast<int>(i) == prim.normal) attributes.push_back(float_attribute("NORMAL", a.accessor, N));
        else attributes.push_back(a);
      }
      if (prim.tangent >= 0) pj["attributes"].erase("TANGENT");

      const bool draco = compression == Compression::Draco && !prim.has_targets;
      if (draco) {
        // Build the Draco mesh from the points this primitive's triangles use (primitives
        // often share one vertex array), all attributes, as a triangle list.
        std::vector<std::int64_t> local(static_cast<std::size_t>(prim.points), -1);
        std::vector<std::uint32_t> used_points;
        for (const std::uint32_t p : prim.triangles)
          if (local[p] < 0) {
            local[p] = static_cast<std::int64_t>(used_points.size());
            used_points.push_back(p);
          }
        const auto n = static_cast<std::uint32_t>(used_points.size());
        draco::Mesh dm;
        dm.set_num_points(n);
        std::vector<int> ids;
        for (const auto& a : attributes) {
          draco::GeometryAttribute ga;
          ga.Init(draco_semantic(a.semantic), nullptr, static_cast<std::uint8_t>(a.components),
                  draco_data_type(a.component_type), a.normalized, static_cast<std::int64_t>(a.element_size()), 0);
          const int id = dm.AddAttribute(ga, true, n);
          for (std::uint32_t p = 0; p < n; ++p)
            dm.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(p), a.bytes.data() + a.element_size() * used_points[p]);
          ids.push_back(id);
        }
        dm.SetNumFaces(prim.triangles.size() / 3);
        for (std::size_t f = 0; f < prim.triangles.size() / 3; ++f) {
          draco::Mesh::Face face;
          for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(static_cast<std::uint32_t>(local[prim.triangles[f * 3 + k]]));
          dm.SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), face);
        }
        std::string payload = draco_encode(dm, options, box);
        // Draco merges identical points and drops degenerate faces: the accessors must state
        // the decoded counts, so read them back from the payload itself.
        const auto decoded = draco_decode(payload, "encoded primitive", Limits{});
        const int view = out.append_view(std::move(payload), std::nullopt);
        Json ext = Json::object();
        ext["bufferView"] = view;
        ext["attributes"] = Json::object();
        for (std::size_t i = 0; i < attributes.size(); ++i) {
          Attribute a = attributes[i];
          const std::uint32_t uid = dm.attribute(ids[i])->unique_id();
          const auto* att = decoded->GetAttributeByUniqueId(uid);
          ext["attributes"][a.semantic] = uid;
          a.count = decoded->num_points();
          if (a.semantic == "POSITION") {  // min / max of what a decoder will produce
            a.bytes.resize(static_cast<std::size_t>(a.count) * 12);
            for (draco::PointIndex p(0); p < decoded->num_points(); ++p) att->GetValue(att->mapped_index(p), a.bytes.data() + 12 * p.value());
          }
          const int acc = out.claim(a.accessor, uses);
          set_accessor(out.json["accessors"][acc], a, std::nullopt);
          pj["attributes"][a.semantic] = acc;
        }
        Attribute indices;
        indices.semantic = "indices";
        indices.component_type = decoded->num_points() <= 65535 ? kUShort : kUInt;
        indices.components = 1;
        indices.count = static_cast<std::int64_t>(decoded->num_faces()) * 3;
        const int acc = out.claim(pj.contains("indices") ? pj["indices"].get<int>() : -1, uses);
        set_accessor(out.json["accessors"][acc], indices, std::nullopt);
        pj["indices"] = acc;
        pj.erase("mode");  // Draco stores a triangle list
        if (!pj.contains("extensions")) pj["extensions"] = Json::object();
        pj["extensions"][kDraco] = ext;
      } else {
        for (const auto& a : attributes) {
          const bool replaced = a.semantic == "POSITION" || a.semantic == "NORMAL";
          if (!replaced && !prim.from_draco) continue;  // untouched accessor: exactly as it was
          const auto key = std::make_pair(a.accessor, a.semantic);
          if (!prim.from_draco && rewritten.count(key)) {
            pj["attributes"][a.semantic] = rewritten[key];
            continue;
          }
          std::string bytes;
          const int stride = packed_vertex_bytes(a, bytes);
          const int view = out.append_view(std::move(bytes), kArrayBuffer, stride ? std::optional<int>(stride) : std::nullopt);
          const int acc = out.claim(a.accessor, uses);
          set_accessor(out.json["accessors"][acc], a, view);
          pj["attributes"][a.semantic] = acc;
          if (!prim.from_draco) rewritten[key] = acc;
        }
        if (prim.from_draco) {
          Attribute indices;
          indices.semantic = "indices";
          indices.component_type = kUInt;
          indices.components = 1;
          indices.count = static_cast<std::int64_t>(prim.triangles.size());
          std::string bytes(prim.triangles.size() * 4, '\0');
          std::memcpy(bytes.data(), prim.triangles.data(), bytes.size());
          const int view = out.append_view(std::move(bytes), kElementArrayBuffer);
          const int acc = out.claim(pj.contains("indices") ? pj["indices"].get<int>() : -1, uses);
          set_accessor(out.json["accessors"][acc], indices, view);
          pj["indices"] = acc;
          pj.erase("mode");
          pj["extensions"].erase(kDraco);
          if (pj["extensions"].empty()) pj.erase("extensions");
        }
      }
    }
  }

  // extensionsUsed / extensionsRequired: KHR_draco_mesh_compression iff a primitive uses it.
  bool any_draco = false;
  for (const auto& mesh : out.json.value("meshes", Json::array()))
    for (const auto& prim : mesh.value("primitives", Json::array()))
      if (prim.contains("extensions") && prim["extensions"].contains(kDraco)) any_draco = true;
  // EXT_meshopt_compression views were decoded: the output's views hold plain bytes.
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    Json names = out.json.value(list, Json::array());
    names.erase(std::remove(names.begin(), names.end(), Json(kDraco)), names.end());
    names.erase(std::remove(names.begin(), names.end(), Json(kMeshopt)), names.end());
    if (any_draco) names.push_back(kDraco);
    if (names.empty()) out.json.erase(list);
    else out.json[list] = names;
  }

  // Keep only referenced buffer views, renumbered in order, and merge every buffer into one.
  std::vector<char> used(out.json["bufferViews"].size(), 0);
  for_each_view_ref(out.json, [&](Json& v) {
    const auto i = v.get<std::int64_t>();
    if (i >= 0 && i < static_cast<std::int64_t>(used.size())) used[static_cast<std::size_t>(i)] = 1;
  });
  std::vector<std::int64_t> renumber(used.size(), -1);
  Json views = Json::array();
  std::string bin;
  for (std::size_t i = 0; i < used.size(); ++i) {
    if (!used[i]) continue;
    renumber[i] = static_cast<std::int64_t>(views.size());
    Json view = out.json["bufferViews"][i];
    std::string_view bytes;
    if (static_cast<std::int64_t>(i) < out.old_views) {
      bytes = Reader(model_, {}).view_bytes(static_cast<int>(i), "glTF");  // checked at decode too
    } else {
      bytes = out.new_views[i - static_cast<std::size_t>(out.old_views)];
    }
    pad_to_4(bin, '\0');
    erase_extension(view, kMeshopt);
    view["buffer"] = 0;
    view["byteOffset"] = bin.size();
    view["byteLength"] = bytes.size();
    if (view["byteOffset"] == 0) view.erase("byteOffset");
    bin.append(bytes);
    views.push_back(view);
  }
  for_each_view_ref(out.json, [&](Json& v) {
    const auto i = v.get<std::int64_t>();
    if (i >= 0 && i < static_cast<std::int64_t>(renumber.size())) v = renumber[static_cast<std::size_t>(i)];
  });
  // Buffer views first in the stored order: keep the key where the input had it.
  if (views.empty()) out.json.erase("bufferViews");
  else out.json["bufferViews"] = views;
  if (out.json["accessors"].empty()) out.json.erase("accessors");
  pad_to_4(bin, '\0');
  Json buffer = json_.contains("buffers") && !json_["buffers"].empty() ? json_["buffers"][0] : Json::object();
  buffer.erase("uri");
  erase_extension(buffer, kMeshopt);  // a fallback buffer's mark
  buffer["byteLength"] = bin.size();
  if (target == Format::Gltf && !bin.empty()) buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(bin);
  if (bin.empty()) out.json.erase("buffers");
  else out.json["buffers"] = Json::array({buffer});

  std::string text = out.json.dump();
  if (target == Format::Gltf) return text;
  return make_glb(std::move(text), bin);
}

// The JSON chunk of a GLB, with the container's lengths checked.
std::string_view glb_json(std::string_view bytes) {
  auto u32 = [&](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  if (bytes.size() < 20 || bytes.substr(0, 4) != "glTF") throw FormatError("GLB: missing the 'glTF' header");
  if (u32(4) != 2) throw UnsupportedError("GLB: container version " + std::to_string(u32(4)) + " (only 2 is supported)");
  if (u32(8) > bytes.size()) throw FormatError("GLB: the header declares more bytes than the input has (truncated?)");
  const std::uint32_t length = u32(12);
  if (u32(16) != 0x4E4F534A) throw FormatError("GLB: the first chunk is not JSON");
  if (length > bytes.size() - 20) throw FormatError("GLB: the JSON chunk reaches past the end of the input");
  return bytes.substr(20, length);
}

// A relative URI reference (RFC 3986) as a path inside the resource folder: percent-decoded,
// refused with UnsupportedError if it has a scheme, is absolute, climbs out with "..", or
// holds a backslash or a NUL.
std::filesystem::path resource_path(const std::string& uri, const std::string& where) {
  const auto refuse = [&](const char* why) -> std::filesystem::path {
    throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + where + " refused: " + why);
  };
  const std::size_t colon = uri.find(':');
  if (colon != std::string::npos && uri.find_first_of("/?#") > colon) refuse("a URI with a scheme is never fetched");
  std::string decoded;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '?' || uri[i] == '#') break;  // query and fragment name no file
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      decoded += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      decoded += uri[i];
    }
  }
  if (decoded.empty()) refuse("empty");
  if (decoded.find('\\') != std::string::npos || decoded.find('\0') != std::string::npos) refuse("a backslash or NUL in a path");
  if (decoded.front() == '/') refuse("an absolute path; only files inside the .gltf's folder are read");
  const std::filesystem::path relative = std::filesystem::path(decoded).lexically_normal();
  for (const auto& part : relative)
    if (part == "..") refuse("it leads out of the .gltf's folder");
  return relative;
}

// Buffers and images referenced by URI: refused (the service), or, with a resource folder
// (the command-line tool), read from it and embedded as data URIs before anything else reads
// the asset, so the rest of the decoder and the encoder only ever see embedded data. Returns
// how many were read.
int resolve_external(Json& json, const char* key, const std::string* resource_dir, const Limits& limits,
                     std::int64_t& read_bytes) {
  if (!json.contains(key) || !json[key].is_array()) return 0;
  int read = 0;
  for (std::size_t i = 0; i < json[key].size(); ++i) {
    Json& item = json[key][i];
    if (!item.is_object() || !item.contains("uri")) continue;
    if (!item["uri"].is_string()) throw FormatError(std::string("glTF: a uri in ") + key + " is not a string");
    const std::string uri = item["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0) continue;
    if (!resource_dir)
      throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + key + " refused: only embedded data is read");
    const std::string where = std::string(key) + "[" + std::to_string(i) + "]";
    const std::filesystem::path file = std::filesystem::path(*resource_dir) / resource_path(uri, where);
    std::error_code ec;
    // A symbolic link inside the folder must not lead out of it either.
    const std::filesystem::path root = std::filesystem::weakly_canonical(*resource_dir, ec);
    const std::filesystem::path real = std::filesystem::weakly_canonical(file, ec);
    const auto [r, f] = std::mismatch(root.begin(), root.end(), real.begin(), real.end());
    if (r != root.end())
      throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + where + " refused: it leads out of the .gltf's folder");
    const auto size = std::filesystem::file_size(file, ec);
    if (ec || !std::filesystem::is_regular_file(file, ec))
      throw FormatError("glTF: " + where + " names '" + uri.substr(0, 200) + "', which cannot be read (" +
                        (ec ? ec.message() : std::string("not a regular file")) + ")");
    read_bytes += static_cast<std::int64_t>(size);
    if (read_bytes > limits.max_decoded_bytes)
      throw LimitError("glTF: the external files come to more than " + std::to_string(limits.max_decoded_bytes) + " bytes");
    std::ifstream in(file, std::ios::binary);
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) throw FormatError("glTF: cannot read '" + uri.substr(0, 200) + "'");
    std::string mime = "application/octet-stream";
    if (std::string(key) == "images") {
      mime = item.value("mimeType", std::string());
      if (mime.empty()) {
        const std::string ext = file.extension().string();
        mime = ext == ".png" ? "image/png" : ext == ".jpg" || ext == ".jpeg" ? "image/jpeg" : ext == ".webp" ? "image/webp" : "application/octet-stream";
      }
    }
    item["uri"] = "data:" + mime + ";base64," + base64_encode(data);
    ++read;
  }
  return read;
}

}  // namespace

namespace {

// Required extensions this adapter reads (geometry) or that do not change what the geometry
// is (materials, textures, lights, instancing of nodes): all are carried over verbatim. A
// loader must refuse any other required extension (glTF 2.0, 3.12).
bool understood_extension(std::string_view name) {
  static constexpr std::string_view kKnown[] = {
      kDraco, kMeshopt, "KHR_mesh_quantization", "KHR_texture_transform", "KHR_texture_basisu", "KHR_lights_punctual",
      "KHR_materials_variants", "EXT_mesh_gpu_instancing", "EXT_texture_webp", "EXT_texture_avif"};
  for (const auto known : kKnown)
    if (name == known) return true;
  return name.rfind("KHR_materials_", 0) == 0;
}

// The JSON's shape where this adapter reads it: wrong types are a FormatError here instead of a
// JSON type error later (e.g. "nodes": 0).
// Entries of json[key] when it is an array (no copy), else 0.
std::size_t size_of(const Json& json, const char* key) {
  const auto it = json.find(key);
  return it != json.end() && it->is_array() ? it->size() : 0;
}

void check_shape(const Json& json) {
  const auto fail = [](const std::string& where, const char* expected) {
    throw FormatError("glTF: " + where + " must be " + expected);
  };
  const auto objects = [&](const Json& parent, const char* key, const std::string& where) {
    if (!parent.contains(key)) return;
    const Json& list = parent[key];
    if (!list.is_array()) fail(where + key, "an array");
    for (std::size_t i = 0; i < list.size(); ++i)
      if (!list[i].is_object()) fail(where + key + "[" + std::to_string(i) + "]", "an object");
  };
  const auto object = [&](const Json& parent, const char* key, const std::string& where) {
    if (parent.contains(key) && !parent[key].is_object()) fail(where + key, "an object");
  };
  const auto integer = [&](const Json& parent, const char* key, const std::string& where) {
    if (parent.contains(key) && !parent[key].is_number_integer()) fail(where + key, "an integer");
  };
  for (const char* key : {"accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials", "meshes",
                          "nodes", "samplers", "scenes", "skins", "textures"})
    objects(json, key, "");
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    if (!json.contains(key)) continue;
    if (!json[key].is_array()) fail(key, "an array of strings");
    for (const auto& name : json[key])
      if (!name.is_string()) fail(key, "an array of strings");
  }
  object(json, "asset", "");
  object(json, "extensions", "");
  integer(json, "scene", "");
  for (std::size_t m = 0; m < size_of(json, "meshes"); ++m) {
    const Json& mesh = json["meshes"][m];
    const std::string where = "meshes[" + std::to_string(m) + "].";
    objects(mesh, "primitives", where);
    for (std::size_t p = 0; p < size_of(mesh, "primitives"); ++p) {
      const Json& prim = mesh["primitives"][p];
      const std::string at = where + "primitives[" + std::to_string(p) + "].";
      object(prim, "attributes", at);
      object(prim, "extensions", at);
      integer(prim, "indices", at);
      integer(prim, "mode", at);
      objects(prim, "targets", at);
      if (prim.contains("attributes"))
        for (const auto& [semantic, index] : prim["attributes"].items())
          if (!index.is_number_integer()) fail(at + "attributes." + semantic, "an integer");
    }
  }
  for (std::size_t n = 0; n < size_of(json, "nodes"); ++n) {
    const Json& node = json["nodes"][n];
    const std::string where = "nodes[" + std::to_string(n) + "].";
    object(node, "extensions", where);
    if (node.contains("extensions") && node["extensions"].contains("EXT_mesh_gpu_instancing")) {
      const Json& instancing = node["extensions"]["EXT_mesh_gpu_instancing"];
      if (!instancing.is_object()) fail(where + "extensions.EXT_mesh_gpu_instancing", "an object");
      object(instancing, "attributes", where + "extensions.EXT_mesh_gpu_instancing.");
    }
  }
  for (std::size_t a = 0; a < size_of(json, "animations"); ++a)
    objects(json["animations"][a], "samplers", "animations[" + std::to_string(a) + "].");
}

// Parses the JSON with its nesting depth and size bounded before anything recursive walks it
// (tinygltf's parser overflows the stack at a depth of about 20,000), and charges what the
// parsed scene will hold: our two copies of the JSON and tinygltf's objects.
Json parse_bounded(std::string_view text, const Limits& limits, std::int64_t& bytes) {
  // One linear pass over the text (nlohmann's callback parser is quadratic on long arrays):
  // the nesting depth, and the number of values (commas and openings; exact for valid JSON).
  std::int64_t values = 1;
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      ++values;
      if (++depth > limits.max_json_depth)
        throw LimitError("glTF: the JSON nests deeper than the limit of " + std::to_string(limits.max_json_depth) +
                         " (max_json_depth)");
    } else if (c == '}' || c == ']') {
      --depth;
    } else if (c == ',') {
      ++values;
    }
  }
  Json json;
  try {
    json = Json::parse(text);
  } catch (const Json::exception& e) {
    throw FormatError(std::string("glTF: invalid JSON (") + e.what() + ")");
  }
  if (!json.is_object()) throw FormatError("glTF: the JSON is not an object");
  check_shape(json);
  const auto count = [&](const char* key) { return static_cast<std::int64_t>(size_of(json, key)); };
  const auto limit = [](std::int64_t n, std::int64_t max, const char* what, const char* name) {
    if (n > max)
      throw LimitError("glTF: the asset has " + std::to_string(n) + " " + what + ", more than the limit of " + std::to_string(max) +
                       " (" + name + ")");
  };
  limit(count("nodes"), limits.max_nodes, "nodes", "max_nodes");
  limit(count("accessors") + count("bufferViews"), limits.max_accessors, "accessors and buffer views", "max_accessors");
  std::int64_t primitives = 0;
  for (std::size_t m = 0; m < size_of(json, "meshes"); ++m) primitives += static_cast<std::int64_t>(size_of(json["meshes"][m], "primitives"));
  limit(primitives, limits.max_accessors, "primitives", "max_accessors");
  // About 3 x 64 bytes per JSON value (the JSON, the copy given to tinygltf, tinygltf's own).
  bytes = values * 192 + count("nodes") * static_cast<std::int64_t>(sizeof(tinygltf::Node)) +
          count("accessors") * static_cast<std::int64_t>(sizeof(tinygltf::Accessor)) +
          count("bufferViews") * static_cast<std::int64_t>(sizeof(tinygltf::BufferView)) +
          count("meshes") * static_cast<std::int64_t>(sizeof(tinygltf::Mesh)) +
          primitives * static_cast<std::int64_t>(sizeof(tinygltf::Primitive)) +
          count("materials") * static_cast<std::int64_t>(sizeof(tinygltf::Material)) + static_cast<std::int64_t>(text.size()) * 2;
  if (bytes > limits.max_decoded_bytes)
    throw LimitError("glTF: the scene would take about " + std::to_string(bytes) + " bytes of memory, more than the limit of " +
                     std::to_string(limits.max_decoded_bytes) + " (max_decoded_bytes)");
  return json;
}

}  // namespace

static std::unique_ptr<MeshDocument> decode_gltf_checked(std::string_view bytes, Format format, const Limits& limits,
                                                          const std::string* resource_dir);

namespace {

bool uses_meshopt(const Json& json) {
  for (const char* list : {"extensionsUsed", "extensionsRequired"})
    for (const auto& name : json.value(list, Json::array()))
      if (name == kMeshopt) return true;
  for (const auto& view : json.value("bufferViews", Json::array()))
    if (view.is_object() && view.contains("extensions") && view["extensions"].is_object() && view["extensions"].contains(kMeshopt))
      return true;
  return false;
}

// A non-negative integer property of an extension object (or `fallback` if absent and given).
std::int64_t unsigned_property(const Json& ext, const char* key, const std::string& where, std::optional<std::int64_t> fallback = {}) {
  const auto it = ext.find(key);
  if (it == ext.end()) {
    if (fallback) return *fallback;
    throw FormatError(where + ": EXT_meshopt_compression has no \"" + key + "\"");
  }
  if (!it->is_number_unsigned() || it->get<std::uint64_t>() > (std::uint64_t{1} << 53))
    throw FormatError(where + ": EXT_meshopt_compression \"" + key + "\" is not a non-negative integer");
  return static_cast<std::int64_t>(it->get<std::uint64_t>());
}

// Decodes every EXT_meshopt_compression buffer view into a buffer of its own and points the
// model's view at it, so that everything downstream (accessors, sparse, the output's copy of
// every view) reads the decoded bytes through the same bounds checks. The declared layout is
// checked against the compressed data's bounds, the parent view and the limits before any
// byte is decoded (the extension's validity rules, "JSON schema updates"). Returns how many
// views were decoded.
int decode_meshopt_views(const Json& json, tinygltf::Model& model, Reader& reader) {
  int decoded_views = 0;
  const Json views = json.value("bufferViews", Json::array());
  for (std::size_t i = 0; i < views.size() && i < model.bufferViews.size(); ++i) {
    if (!views[i].is_object() || !views[i].contains("extensions") || !views[i]["extensions"].is_object()) continue;
    const auto found = views[i]["extensions"].find(kMeshopt);
    if (found == views[i]["extensions"].end()) continue;
    const std::string where = "glTF buffer view " + std::to_string(i);
    const Json& ext = *found;
    if (!ext.is_object()) throw FormatError(where + ": EXT_meshopt_compression is not an object");
    const std::int64_t buffer = unsigned_property(ext, "buffer", where);
    const std::int64_t offset = unsigned_property(ext, "byteOffset", where, 0);
    const std::int64_t length = unsigned_property(ext, "byteLength", where);
    MeshoptView layout;
    layout.byte_stride = unsigned_property(ext, "byteStride", where);
    layout.count = unsigned_property(ext, "count", where);
    const std::string mode = ext.value("mode", std::string());
    if (mode == "ATTRIBUTES") layout.mode = MeshoptMode::Attributes;
    else if (mode == "TRIANGLES") layout.mode = MeshoptMode::Triangles;
    else if (mode == "INDICES") layout.mode = MeshoptMode::Indices;
    else throw FormatError(where + ": EXT_meshopt_compression mode '" + mode.substr(0, 32) + "' is not ATTRIBUTES, TRIANGLES or INDICES");
    const std::string filter = ext.value("filter", std::string("NONE"));
    if (filter == "NONE") layout.filter = MeshoptFilter::None;
    else if (filter == "OCTAHEDRAL") layout.filter = MeshoptFilter::Octahedral;
    else if (filter == "QUATERNION") layout.filter = MeshoptFilter::Quaternion;
    else if (filter == "EXPONENTIAL") layout.filter = MeshoptFilter::Exponential;
    else throw FormatError(where + ": EXT_meshopt_compression filter '" + filter.substr(0, 32) + "' is not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL");
    check_meshopt_view(layout, where);
    // The decoded size, bounded before it is multiplied or allocated.
    const Limits& limits = reader.limits();
    if (layout.count > 3 * std::max(limits.max_vertices, limits.max_faces))
      throw LimitError(where + ": EXT_meshopt_compression declares " + std::to_string(layout.count) + " elements, more than the limits allow");
    const std::int64_t decoded = layout.count * layout.byte_stride;
    tinygltf::BufferView& view = model.bufferViews[i];
    if (static_cast<std::int64_t>(view.byteLength) != decoded || (view.byteStride != 0 && static_cast<std::int64_t>(view.byteStride) != layout.byte_stride))
      throw FormatError(where + ": byteLength " + std::to_string(view.byteLength) + " / byteStride " + std::to_string(view.byteStride) +
                        " disagree with EXT_meshopt_compression's " + std::to_string(layout.count) + " elements of " +
                        std::to_string(layout.byte_stride) + " bytes");
    if (buffer >= static_cast<std::int64_t>(model.buffers.size()))
      throw FormatError(where + ": EXT_meshopt_compression names buffer " + std::to_string(buffer) + ", which does not exist");
    const auto& source = model.buffers[static_cast<std::size_t>(buffer)].data;
    if (offset > static_cast<std::int64_t>(source.size()) || length > static_cast<std::int64_t>(source.size()) - offset)
      throw FormatError(where + ": EXT_meshopt_compression's " + std::to_string(length) + " bytes at " + std::to_string(offset) +
                        " reach past the end of buffer " + std::to_string(buffer) + " (" + std::to_string(source.size()) + " bytes)");
    reader.charge(decoded, where);
    const std::string_view compressed(reinterpret_cast<const char*>(source.data()) + offset, static_cast<std::size_t>(length));
    tinygltf::Buffer plain;
    plain.data = meshopt_decode(compressed, layout, where);
    model.buffers.push_back(std::move(plain));
    view.buffer = static_cast<int>(model.buffers.size()) - 1;
    view.byteOffset = 0;
    ++decoded_views;
  }
  return decoded_views;
}

}  // namespace

std::unique_ptr<MeshDocument> decode_gltf(std::string_view bytes, Format format, const Limits& limits,
                                          const std::string* resource_dir) {
  try {
    return decode_gltf_checked(bytes, format, limits, resource_dir);
  } catch (const Json::exception& e) {  // a shape check_shape does not cover: still the input's fault
    throw FormatError(std::string("glTF: unexpected JSON content (") + e.what() + ")");
  }
}

static std::unique_ptr<MeshDocument> decode_gltf_checked(std::string_view bytes, Format format, const Limits& limits,
                                                          const std::string* resource_dir) {
  auto doc = std::make_unique<GltfDocument>();
  doc->format_ = format;
  const std::string_view text = format == Format::Glb ? glb_json(bytes) : bytes;
  std::int64_t scene_bytes = 0;
  doc->json_ = parse_bounded(text, limits, scene_bytes);
  // Before tinygltf sees the asset: without a resource folder nothing external is ever opened.
  std::int64_t external_bytes = 0;
  int external = 0;
  for (const char* key : {"buffers", "images"})
    external += resolve_external(doc->json_, key, resource_dir, limits, external_bytes);
  for (const char* list : {"extensionsUsed", "extensionsRequired"})
    for (const auto& name : doc->json_.value(list, Json::array()))
      if (name == "KHR_meshopt_compression")
        throw UnsupportedError("glTF extension " + name.get<std::string>() + " is not supported; decompress the asset first");
  for (const auto& name : doc->json_.value("extensionsRequired", Json::array()))
    if (!understood_extension(name.get<std::string>()))
      throw UnsupportedError("glTF extension " + name.get<std::string>().substr(0, 100) +
                             " is required by the asset and not supported");
  // tinygltf 2.7 rejects an indices accessor without a buffer view, which is what a Draco
  // primitive has (valid glTF). Draco primitives are read from the JSON and the payload
  // here, so tinygltf gets a copy of the JSON without their "indices".
  Json for_loader = doc->json_;
  bool changed = external > 0;
  if (for_loader.contains("meshes") && for_loader["meshes"].is_array())
    for (auto& mesh : for_loader["meshes"])
      if (mesh.is_object() && mesh.contains("primitives") && mesh["primitives"].is_array())
        for (auto& prim : mesh["primitives"])
          if (prim.is_object() && prim.contains("extensions") && prim["extensions"].is_object() &&
              prim["extensions"].contains(kDraco))
            changed |= prim.erase("indices") > 0;
  // EXT_meshopt_compression's placeholder buffers have no data (no uri, not the GLB chunk),
  // which tinygltf refuses: it is given a one-byte buffer instead. The views that name one are
  // decoded from their extension's buffer below; any other view on it reaches past its end.
  const bool meshopt = uses_meshopt(doc->json_);
  if (meshopt && for_loader.contains("buffers") && for_loader["buffers"].is_array())
    for (std::size_t b = 0; b < for_loader["buffers"].size(); ++b) {
      Json& buffer = for_loader["buffers"][b];
      if (!buffer.is_object() || buffer.contains("uri") || (format == Format::Glb && b == 0)) continue;
      buffer = Json{{"byteLength", 1}, {"uri", "data:application/octet-stream;base64,AA=="}};
      changed = true;
    }
  if (!changed) {
    doc->model_ = load_tinygltf(bytes, format == Format::Glb);
  } else if (format == Format::Gltf) {
    doc->model_ = load_tinygltf(for_loader.dump(), false);
  } else {
    std::string container = make_glb(for_loader.dump(), {});
    // make_glb wrote the header and the JSON chunk; the input's BIN chunk follows as is.
    const std::size_t rest = 20 + text.size();
    container += bytes.substr(rest);
    const auto total = static_cast<std::uint32_t>(container.size());
    std::memcpy(container.data() + 8, &total, 4);
    doc->model_ = load_tinygltf(container, true);
  }
  const tinygltf::Model& model = doc->model_;
  // tinygltf 2.7 skips a primitive it cannot parse (no "attributes", say) instead of failing, so
  // its primitive p would no longer be the JSON's primitive p, which the output is written to.
  const Json meshes = doc->json_.value("meshes", Json::array());
  if (!meshes.is_array() || meshes.size() != model.meshes.size()) throw FormatError("glTF: a mesh is invalid");
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    const Json& listed = meshes[m].is_object() ? meshes[m].value("primitives", Json::array()) : Json::array();
    if (!listed.is_array() || listed.size() != model.meshes[m].primitives.size())
      throw FormatError("glTF: mesh " + std::to_string(m) +
                        " has an invalid primitive (each needs an \"attributes\" object of accessor indices)");
  }

  Reader reader(model, limits);
  reader.charge(scene_bytes, "glTF");
  if (meshopt && decode_meshopt_views(doc->json_, doc->model_, reader) > 0) doc->compression_ = Compression::Meshopt;
  // Every buffer view is copied into the output, used by a surface or not (images, animations):
  // each must lie inside its buffer, and tinygltf's list must be the JSON's.
  if (doc->json_.value("bufferViews", Json::array()).size() != model.bufferViews.size() ||
      doc->json_.value("accessors", Json::array()).size() != model.accessors.size())
    throw FormatError("glTF: a buffer view or an accessor is invalid");
  for (std::size_t i = 0; i < model.bufferViews.size(); ++i) reader.view_bytes(static_cast<int>(i), "glTF");
  std::int64_t total_points = 0, total_faces = 0;
  bool dropped_tangent = false, kept_targets = false;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    Surface surface;
    surface.mesh = static_cast<int>(m);
    Vertices points;
    std::vector<Vec3> all_points;
    std::vector<std::pair<std::int64_t, Vec3>> normals;  // per concatenated point, if any
    for (std::size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      const auto& prim = model.meshes[m].primitives[p];
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
        continue;  // points and lines pass through untouched
      const std::string what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
      Primitive out;
      out.mesh = static_cast<int>(m);
      out.index = static_cast<int>(p);
      out.has_targets = !prim.targets.empty();
      const Json& pj = doc->json_["meshes"][m]["primitives"][p];
      const Json ext = pj.value("extensions", Json::object()).value(kDraco, Json());
      if (!ext.is_null()) {
        read_draco_primitive(reader, ext, prim, out, what);
        if (doc->compression_ == Compression::None) doc->compression_ = Compression::Draco;
        if (out.has_targets) throw UnsupportedError(what + ": morph targets on a Draco-compressed primitive");
      } else {
        const auto pos = prim.attributes.find("POSITION");
        if (pos == prim.attributes.end()) throw FormatError(what + ": no POSITION attribute");
        for (const auto& [semantic, accessor] : prim.attributes) {
          Attribute a = reader.read(accessor, what + " " + semantic);
          a.semantic = semantic;
          out.attributes.push_back(std::move(a));
        }
        out.points = reader.read(pos->second, what + " POSITION").count;
        for (const auto& a : out.attributes)
          if (a.count != out.points) throw FormatError(what + ": attribute " + a.semantic + " has a different count than POSITION");
        std::vector<std::uint32_t> idx;
        if (prim.indices >= 0) {
          idx = reader.read_indices(prim.indices, out.points, what);
        } else {
          idx.resize(static_cast<std::size_t>(out.points));
          for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
        }
        out.triangles = to_triangle_list(idx, mode, what);
      }
      for (std::size_t i = 0; i < out.attributes.size(); ++i) {
        if (out.attributes[i].semantic == "POSITION") out.position = static_cast<int>(i);
        if (out.attributes[i].semantic == "NORMAL") out.normal = static_cast<int>(i);
        if (out.attributes[i].semantic == "TANGENT") out.tangent = static_cast<int>(i);
      }
      if (out.position < 0) throw FormatError(what + ": no POSITION attribute");
      if (out.attributes[static_cast<std::size_t>(out.position)].components != 3) throw FormatError(what + ": POSITION must be VEC3");
      if (out.normal >= 0 && out.attributes[static_cast<std::size_t>(out.normal)].components != 3) throw FormatError(what + ": NORMAL must be VEC3");
      dropped_tangent |= out.tangent >= 0;
      kept_targets |= out.has_targets;
      total_points += out.points;
      total_faces += static_cast<std::int64_t>(out.triangles.size() / 3);
      check_count(total_points, limits.max_vertices, "vertices");
      check_count(total_faces, limits.max_faces, "faces");
      out.point_offset = static_cast<std::int64_t>(all_points.size());
      const Attribute& position = out.attributes[static_cast<std::size_t>(out.position)];
      for (std::int64_t i = 0; i < out.points; ++i) {
        reader.cancel().poll();
        const Vec3 v(position.value(i, 0), position.value(i, 1), position.value(i, 2));
        if (!v.allFinite()) throw FormatError(what + ": non-finite POSITION");
        all_points.push_back(v);
      }
      surface.primitives.push_back(std::move(out));
    }
    if (surface.primitives.empty()) continue;

    Vertices P(static_cast<Eigen::Index>(all_points.size()), 3);
    for (std::size_t i = 0; i < all_points.size(); ++i) P.row(static_cast<Eigen::Index>(i)) = all_points[i].transpose();
    Weld weld = weld_positions(P, 1e-6, limits.cancel);
    TriMesh tri;
    tri.V = std::move(weld.V);
    std::int64_t faces = 0;
    for (const auto& prim : surface.primitives) faces += static_cast<std::int64_t>(prim.triangles.size() / 3);
    tri.F.resize(faces, 3);
    Eigen::Index f = 0;
    for (const auto& prim : surface.primitives)
      for (std::size_t c = 0; c < prim.triangles.size(); c += 3, ++f)
        for (int k = 0; k < 3; ++k)
          tri.F(f, k) = weld.map[static_cast<std::size_t>(prim.point_offset) + prim.triangles[c + static_cast<std::size_t>(k)]];
    // Normal slots: points that share a welded vertex and (to 1e-3) an input normal share a
    // recomputed normal; copies whose input normals differ (a hard edge) stay apart.
    surface.normal_slot.assign(all_points.size(), -1);
    std::map<std::tuple<std::int32_t, long, long, long>, std::int64_t> slots;
    for (const auto& prim : surface.primitives) {
      if (prim.normal < 0) continue;
      const Attribute& n = prim.attributes[static_cast<std::size_t>(prim.normal)];
      for (std::int64_t i = 0; i < prim.points; ++i) {
        const auto point = static_cast<std::size_t>(prim.point_offset + i);
        const auto key = std::make_tuple(weld.map[point], std::lround(n.value(i, 0) * 1e3), std::lround(n.value(i, 1) * 1e3),
                                         std::lround(n.value(i, 2) * 1e3));
        const auto [it, inserted] = slots.emplace(key, static_cast<std::int64_t>(slots.size()));
        surface.normal_slot[point] = it->second;
      }
    }
    surface.normal_slots = static_cast<std::int64_t>(slots.size());
    surface.point_to_weld = std::move(weld.map);
    surface.welded = tri.V.rows();
    doc->meshes_.push_back(std::move(tri));
    doc->surfaces_.push_back(std::move(surface));
  }
  if (doc->surfaces_.empty()) throw FormatError("glTF: the asset has no triangle primitives to denoise");
  if (dropped_tangent) doc->notes_.emplace_back("TANGENT dropped (it no longer matches the denoised surface; viewers regenerate it)");
  bool normals = false;
  for (const auto& s : doc->surfaces_) normals |= s.normal_slots > 0;
  if (normals) doc->notes_.emplace_back("NORMAL recomputed from the denoised surface, keeping the input's hard edges");
  if (kept_targets) doc->notes_.emplace_back("primitives with morph targets are written without Draco (their vertex order must be kept)");
  return doc;
}

std::string write_plain_gltf(const std::vector<TriMesh>& all, Format format, const EncodeOptions& options) {
  // glTF accessors hold at least one element: surfaces without triangles are left out.
  std::vector<TriMesh> surfaces;
  for (const TriMesh& m : all)
    if (m.F.rows() > 0) surfaces.push_back(m);
  if (surfaces.empty()) throw UnsupportedError("the mesh has no triangles: there is nothing to write as glTF");
  // A minimal asset (one node per surface), then the regular encoder for Draco and layout.
  Json json = {{"asset", {{"version", "2.0"}, {"generator", "meshdenoise"}}}};
  json["scene"] = 0;
  json["scenes"] = Json::array({Json::object()});
  json["scenes"][0]["nodes"] = Json::array();
  std::string bin;
  for (std::size_t s = 0; s < surfaces.size(); ++s) {
    const TriMesh& m = surfaces[s];
    const std::size_t pos_offset = bin.size();
    Vertices lo = m.V.colwise().minCoeff(), hi = m.V.colwise().maxCoeff();
    for (Eigen::Index i = 0; i < m.V.rows(); ++i)
      for (int k = 0; k < 3; ++k) {
        const auto v = static_cast<float>(m.V(i, k));
        bin.append(reinterpret_cast<const char*>(&v), 4);
      }
    const std::size_t idx_offset = bin.size();
    bin.append(reinterpret_cast<const char*>(m.F.data()), static_cast<std::size_t>(m.F.size()) * 4);
    const auto views = json.value("bufferViews", Json::array()).size();
    json["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", pos_offset}, {"byteLength", idx_offset - pos_offset}, {"target", kArrayBuffer}});
    json["bufferViews"].push_back({{"buffer", 0}, {"byteOffset", idx_offset}, {"byteLength", bin.size() - idx_offset}, {"target", kElementArrayBuffer}});
    const auto accessors = json.value("accessors", Json::array()).size();
    Json acc_min = Json::array(), acc_max = Json::array();
    for (int k = 0; k < 3; ++k) {
      acc_min.push_back(static_cast<float>(lo(0, k)));
      acc_max.push_back(static_cast<float>(hi(0, k)));
    }
    json["accessors"].push_back({{"bufferView", views}, {"componentType", kFloat}, {"count", m.V.rows()}, {"type", "VEC3"}, {"min", acc_min}, {"max", acc_max}});
    json["accessors"].push_back({{"bufferView", views + 1}, {"componentType", kUInt}, {"count", m.F.size()}, {"type", "SCALAR"}});
    json["meshes"].push_back({{"primitives", Json::array({{{"attributes", {{"POSITION", accessors}}}, {"indices", accessors + 1}}})}});
    json["nodes"].push_back({{"mesh", s}});
    json["scenes"][0]["nodes"].push_back(s);
  }
  json["buffers"] = Json::array({{{"byteLength", bin.size()}, {"uri", "data:application/octet-stream;base64," + base64_encode(bin)}}});
  const std::string text = json.dump();
  auto doc = decode_gltf(text, Format::Gltf, Limits{}, nullptr);
  // Exact positions rather than their float copies (when welding merged nothing).
  bool same_sizes = doc->surfaces().size() == surfaces.size();
  for (std::size_t s = 0; same_sizes && s < surfaces.size(); ++s) same_sizes = doc->surfaces()[s].V.rows() == surfaces[s].V.rows();
  if (same_sizes)
    for (std::size_t s = 0; s < surfaces.size(); ++s) doc->surfaces()[s].V = surfaces[s].V;
  EncodeOptions same = options;
  same.format = format;
  return doc->encode(same);
}

}  // namespace mdn::io::detail
