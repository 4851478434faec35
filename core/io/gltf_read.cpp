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
#include "core/io/gltf_model.h"
#include "core/io/meshopt_codec.h"
#include "core/io/tinygltf_load.h"
#include "core/io/weld.h"

namespace mdn::io::detail {
namespace gltf {
namespace {

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
// A TRIANGLES list is returned as it came (moved, not copied).
std::vector<std::uint32_t> to_triangle_list(std::vector<std::uint32_t> idx, int mode, const std::string& what) {
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

}  // namespace

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

}  // namespace gltf

using namespace gltf;


static std::unique_ptr<MeshDocument> decode_gltf_checked(std::string_view bytes, Format format, const Limits& limits,
                                                          const std::string* resource_dir, std::string* release);

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

// Refuses what the asset requires and this adapter cannot read.
void check_extensions(const Json& json) {
  for (const char* list : {"extensionsUsed", "extensionsRequired"})
    for (const auto& name : json.value(list, Json::array()))
      if (name == "KHR_meshopt_compression")
        throw UnsupportedError("glTF extension " + name.get<std::string>() + " is not supported; decompress the asset first");
  for (const auto& name : json.value("extensionsRequired", Json::array()))
    if (!understood_extension(name.get<std::string>()))
      throw UnsupportedError("glTF extension " + name.get<std::string>().substr(0, 100) +
                             " is required by the asset and not supported");
}

// tinygltf's model of the asset. tinygltf 2.7 rejects an indices accessor without a buffer
// view, which is what a Draco primitive has (valid glTF): Draco primitives are read from the
// JSON and the payload here, so tinygltf gets a copy of the JSON without their "indices".
// EXT_meshopt_compression's placeholder buffers have no data (no uri, not the GLB chunk), which
// tinygltf refuses: it is given a one-byte buffer instead; the views that name one are decoded
// from their extension's buffer later, any other view on it reaches past its end.
// `embedded`: the buffers already decoded from their data URIs (decode_lifted) or read from
// their files (resolve_external), empty elements for the others: tinygltf is given a one-byte data URI for each, and its buffer then adopts
// the decoded bytes (moved, not copied; decision 82).
tinygltf::Model load_model(const Json& json, std::string_view bytes, std::string_view text, Format format,
                           bool changed, std::vector<std::vector<unsigned char>>& embedded) {
  Json for_loader = json;
  for (std::size_t b = 0; b < embedded.size(); ++b)
    if (!embedded[b].empty()) {
      for_loader["buffers"][b]["byteLength"] = 1;
      for_loader["buffers"][b]["uri"] = "data:application/octet-stream;base64,AA==";
      changed = true;
    }
  if (for_loader.contains("meshes") && for_loader["meshes"].is_array())
    for (auto& mesh : for_loader["meshes"])
      if (mesh.is_object() && mesh.contains("primitives") && mesh["primitives"].is_array())
        for (auto& prim : mesh["primitives"])
          if (prim.is_object() && prim.contains("extensions") && prim["extensions"].is_object() &&
              prim["extensions"].contains(kDraco))
            changed |= prim.erase("indices") > 0;
  if (uses_meshopt(json) && for_loader.contains("buffers") && for_loader["buffers"].is_array())
    for (std::size_t b = 0; b < for_loader["buffers"].size(); ++b) {
      Json& buffer = for_loader["buffers"][b];
      if (!buffer.is_object() || buffer.contains("uri") || (format == Format::Glb && b == 0)) continue;
      buffer = Json{{"byteLength", 1}, {"uri", "data:application/octet-stream;base64,AA=="}};
      changed = true;
    }
  if (!changed) return load_tinygltf(bytes, format == Format::Glb);
  tinygltf::Model model;
  if (format == Format::Gltf) {
    model = load_tinygltf(for_loader.dump(), false);
  } else {
    std::string container = make_glb(for_loader.dump(), {});
    // make_glb wrote the header and the JSON chunk; the input's BIN chunk follows as is.
    const std::size_t rest = 20 + text.size();
    container += bytes.substr(rest);
    const auto total = static_cast<std::uint32_t>(container.size());
    std::memcpy(container.data() + 8, &total, 4);
    model = load_tinygltf(container, true);
  }
  for (std::size_t b = 0; b < embedded.size() && b < model.buffers.size(); ++b)
    if (!embedded[b].empty()) model.buffers[b].data = std::move(embedded[b]);
  return model;
}

// tinygltf 2.7 skips a primitive it cannot parse (no "attributes", say) instead of failing, so
// its primitive p would no longer be the JSON's primitive p, which the output is written to.
void check_meshes_match_json(const Json& json, const tinygltf::Model& model) {
  const Json meshes = json.value("meshes", Json::array());
  if (!meshes.is_array() || meshes.size() != model.meshes.size()) throw FormatError("glTF: a mesh is invalid");
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    const Json& listed = meshes[m].is_object() ? meshes[m].value("primitives", Json::array()) : Json::array();
    if (!listed.is_array() || listed.size() != model.meshes[m].primitives.size())
      throw FormatError("glTF: mesh " + std::to_string(m) +
                        " has an invalid primitive (each needs an \"attributes\" object of accessor indices)");
  }
}

// Every buffer view is copied into the output, used by a surface or not (images, animations):
// each must lie inside its buffer, and tinygltf's list must be the JSON's.
void check_views(const Json& json, const tinygltf::Model& model, const Reader& reader) {
  if (json.value("bufferViews", Json::array()).size() != model.bufferViews.size() ||
      json.value("accessors", Json::array()).size() != model.accessors.size())
    throw FormatError("glTF: a buffer view or an accessor is invalid");
  for (std::size_t i = 0; i < model.bufferViews.size(); ++i) reader.view_bytes(static_cast<int>(i), "glTF");
}

// An uncompressed primitive: its accessors, indices (or none: 0..n-1) and topology.
void read_plain_primitive(Reader& reader, const tinygltf::Primitive& prim, int mode, Primitive& out,
                          const std::string& what) {
  const auto pos = prim.attributes.find("POSITION");
  if (pos == prim.attributes.end()) throw FormatError(what + ": no POSITION attribute");
  // The declared count is checked before any attribute is allocated: an accessor without a
  // buffer view (zeros, sparse may fill) costs its whole size from a few bytes of JSON.
  const auto& model = reader.model();
  if (pos->second >= 0 && pos->second < static_cast<int>(model.accessors.size()))
    check_count(static_cast<std::int64_t>(model.accessors[static_cast<std::size_t>(pos->second)].count),
                reader.limits().max_vertices, "vertices");
  for (const auto& [semantic, accessor] : prim.attributes) {
    Attribute a = reader.read(accessor, what + " " + semantic);
    a.semantic = semantic;
    if (semantic == "POSITION") out.points = a.count;
    out.attributes.push_back(std::move(a));
  }
  for (const auto& a : out.attributes)
    if (a.count != out.points) throw FormatError(what + ": attribute " + a.semantic + " has a different count than POSITION");
  std::vector<std::uint32_t> idx;
  if (prim.indices >= 0) {
    idx = reader.read_indices(prim.indices, out.points, what);
  } else {
    idx.resize(static_cast<std::size_t>(out.points));
    for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
  }
  out.triangles = to_triangle_list(std::move(idx), mode, what);
}

// Primitive p of mesh m (Draco or plain), its POSITION / NORMAL / TANGENT located and checked.
Primitive read_primitive(Reader& reader, GltfDocument& doc, std::size_t m, std::size_t p, int mode) {
  const auto& prim = doc.model_.meshes[m].primitives[p];
  const std::string what = "mesh " + std::to_string(m) + " primitive " + std::to_string(p);
  Primitive out;
  out.mesh = static_cast<int>(m);
  out.index = static_cast<int>(p);
  out.has_targets = !prim.targets.empty();
  const Json& pj = doc.json_["meshes"][m]["primitives"][p];
  const Json ext = pj.value("extensions", Json::object()).value(kDraco, Json());
  if (!ext.is_null()) {
    read_draco_primitive(reader, ext, prim, out, what);
    if (doc.compression_ == Compression::None) doc.compression_ = Compression::Draco;
    if (out.has_targets) throw UnsupportedError(what + ": morph targets on a Draco-compressed primitive");
  } else {
    read_plain_primitive(reader, prim, mode, out, what);
  }
  for (std::size_t i = 0; i < out.attributes.size(); ++i) {
    if (out.attributes[i].semantic == "POSITION") out.position = static_cast<int>(i);
    if (out.attributes[i].semantic == "NORMAL") out.normal = static_cast<int>(i);
    if (out.attributes[i].semantic == "TANGENT") out.tangent = static_cast<int>(i);
  }
  if (out.position < 0) throw FormatError(what + ": no POSITION attribute");
  if (out.attributes[static_cast<std::size_t>(out.position)].components != 3) throw FormatError(what + ": POSITION must be VEC3");
  if (out.normal >= 0 && out.attributes[static_cast<std::size_t>(out.normal)].components != 3) throw FormatError(what + ": NORMAL must be VEC3");
  return out;
}

// A primitive's positions are finite, or a FormatError.
void check_points(Reader& reader, const Primitive& prim) {
  const std::string what = "mesh " + std::to_string(prim.mesh) + " primitive " + std::to_string(prim.index);
  const Attribute& position = prim.attributes[static_cast<std::size_t>(prim.position)];
  for (std::int64_t i = 0; i < prim.points; ++i) {
    reader.cancel().poll();
    if (!Vec3(position.value(i, 0), position.value(i, 1), position.value(i, 2)).allFinite())
      throw FormatError(what + ": non-finite POSITION");
  }
}

// Normal slots: points that share a welded vertex and (to 1e-3) an input normal share a
// recomputed normal; copies whose input normals differ (a hard edge) stay apart.
void assign_normal_slots(Surface& surface, const std::vector<std::int32_t>& weld_map, std::size_t points) {
  surface.normal_slot.assign(points, -1);
  std::map<std::tuple<std::int32_t, long, long, long>, std::int64_t> slots;
  for (const auto& prim : surface.primitives) {
    if (prim.normal < 0) continue;
    const Attribute& n = prim.attributes[static_cast<std::size_t>(prim.normal)];
    for (std::int64_t i = 0; i < prim.points; ++i) {
      const auto point = static_cast<std::size_t>(prim.point_offset + i);
      const auto key = std::make_tuple(weld_map[point], std::lround(n.value(i, 0) * 1e3), std::lround(n.value(i, 1) * 1e3),
                                       std::lround(n.value(i, 2) * 1e3));
      const auto [it, inserted] = slots.emplace(key, static_cast<std::int64_t>(slots.size()));
      surface.normal_slot[point] = it->second;
    }
  }
  surface.normal_slots = static_cast<std::int64_t>(slots.size());
}

// The surface's mesh: every primitive's points (`points` in all) welded by position, their
// triangles on the welded vertices; the surface keeps the point -> vertex map and its normal
// slots. The points are gathered once, straight from the primitives, and freed before the faces
// are allocated (decision 82: the decode's peak memory).
TriMesh weld_surface(Surface& surface, std::int64_t points, const Limits& limits) {
  Weld weld;
  {
    Vertices P(points, 3);
    for (const auto& prim : surface.primitives) {
      const Attribute& position = prim.attributes[static_cast<std::size_t>(prim.position)];
      for (std::int64_t i = 0; i < prim.points; ++i)
        P.row(prim.point_offset + i) << position.value(i, 0), position.value(i, 1), position.value(i, 2);
    }
    weld = weld_positions(P, 1e-6, limits.cancel);
  }
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
  assign_normal_slots(surface, weld.map, static_cast<std::size_t>(points));
  surface.point_to_weld = std::move(weld.map);
  surface.welded = tri.V.rows();
  return tri;
}

// Every mesh with triangle primitives becomes a surface; points and lines pass through.
void read_surfaces(Reader& reader, GltfDocument& doc, const Limits& limits) {
  const tinygltf::Model& model = doc.model_;
  std::int64_t total_points = 0, total_faces = 0;
  bool dropped_tangent = false, kept_targets = false;
  for (std::size_t m = 0; m < model.meshes.size(); ++m) {
    Surface surface;
    surface.mesh = static_cast<int>(m);
    std::int64_t points = 0;
    for (std::size_t p = 0; p < model.meshes[m].primitives.size(); ++p) {
      const int mode = model.meshes[m].primitives[p].mode < 0 ? TINYGLTF_MODE_TRIANGLES : model.meshes[m].primitives[p].mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP && mode != TINYGLTF_MODE_TRIANGLE_FAN)
        continue;  // points and lines pass through untouched
      Primitive out = read_primitive(reader, doc, m, p, mode);
      dropped_tangent |= out.tangent >= 0;
      kept_targets |= out.has_targets;
      total_points += out.points;
      total_faces += static_cast<std::int64_t>(out.triangles.size() / 3);
      check_count(total_points, limits.max_vertices, "vertices");
      check_count(total_faces, limits.max_faces, "faces");
      out.point_offset = points;
      points += out.points;
      check_points(reader, out);
      surface.primitives.push_back(std::move(out));
    }
    if (surface.primitives.empty()) continue;
    doc.meshes_.push_back(weld_surface(surface, points, limits));
    doc.surfaces_.push_back(std::move(surface));
  }
  if (doc.surfaces_.empty()) throw FormatError("glTF: the asset has no triangle primitives to denoise");
  if (dropped_tangent) doc.notes_.emplace_back("TANGENT dropped (it no longer matches the denoised surface; viewers regenerate it)");
  bool normals = false;
  for (const auto& s : doc.surfaces_) normals |= s.normal_slots > 0;
  if (normals) doc.notes_.emplace_back("NORMAL recomputed from the denoised surface, keeping the input's hard edges");
  if (kept_targets) doc.notes_.emplace_back("primitives with morph targets are written without Draco (their vertex order must be kept)");
}

}  // namespace

std::unique_ptr<MeshDocument> decode_gltf(std::string_view bytes, Format format, const Limits& limits,
                                          const std::string* resource_dir, std::string* release) {
  try {
    return decode_gltf_checked(bytes, format, limits, resource_dir, release);
  } catch (const Json::exception& e) {  // a shape check_shape does not cover: still the input's fault
    throw FormatError(std::string("glTF: unexpected JSON content (") + e.what() + ")");
  }
}

static std::unique_ptr<MeshDocument> decode_gltf_checked(std::string_view bytes, Format format, const Limits& limits,
                                                          const std::string* resource_dir, std::string* release) {
  auto doc = std::make_unique<GltfDocument>();
  doc->format_ = format;
  // A .gltf's data URIs: the JSON parsers see placeholders, each buffer is decoded once from the
  // body, which the caller may then free (decision 82).
  const LiftedJson lifted = format == Format::Gltf ? lift_data_uris(bytes) : LiftedJson{};
  const std::string_view text = format == Format::Glb ? glb_json(bytes) : lifted.literals.empty() ? bytes : lifted.text;
  std::int64_t scene_bytes = 0;
  doc->json_ = parse_bounded(text, limits, scene_bytes);
  std::vector<std::vector<unsigned char>> embedded = decode_lifted(doc->json_, bytes, lifted, limits, scene_bytes);
  if (release && !lifted.literals.empty()) {  // tinygltf reads the JSON's dump (load_model), not the body
    std::string().swap(*release);
    bytes = {};
  }
  // Before tinygltf sees the asset: without a resource folder nothing external is ever opened.
  std::int64_t external_bytes = 0;
  int external = 0;
  for (const char* key : {"buffers", "images"})
    external += resolve_external(doc->json_, key, resource_dir, limits, external_bytes, key == std::string("buffers") ? &embedded : nullptr);
  check_extensions(doc->json_);
  doc->model_ = load_model(doc->json_, bytes, text, format, external > 0 || !lifted.literals.empty(), embedded);
  if (release) std::string().swap(*release);
  check_meshes_match_json(doc->json_, doc->model_);
  Reader reader(doc->model_, limits);
  reader.charge(scene_bytes, "glTF");
  if (uses_meshopt(doc->json_) && decode_meshopt_views(doc->json_, doc->model_, reader) > 0)
    doc->compression_ = Compression::Meshopt;
  check_views(doc->json_, doc->model_, reader);
  read_surfaces(reader, *doc, limits);
  return doc;
}

}  // namespace mdn::io::detail
