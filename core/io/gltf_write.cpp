// glTF 2.0 writing (.glb, and .gltf with embedded data URIs).
//
// Writing: the output JSON is the input JSON with only the denoised primitives, their
// accessors, the buffer views and the buffers changed. Materials, textures, images, nodes,
// animations, names, extras and unknown extensions are carried over verbatim (key order
// included). Attributes other than POSITION / NORMAL / TANGENT keep their values exactly
// (with Draco, they are stored losslessly unless the caller asks for quantisation). NORMAL
// is recomputed keeping the input's hard edges; TANGENT is dropped (see notes()). Unused
// buffer views are removed and all buffers are merged into one, so replaced geometry does
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
#include "core/io/gltf_write.h"
#include "core/io/plain.h"
#include "core/io/weld.h"

namespace mdn::io::detail {
namespace gltf {
namespace {

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

}  // namespace


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
      double mn = a.value(0, k, false), mx = mn;
      for (std::int64_t i = 1; i < a.count; ++i) {
        mn = std::min(mn, a.value(i, k, false));
        mx = std::max(mx, a.value(i, k, false));
      }
      lo.push_back(mn);
      hi.push_back(mx);
    }
    acc["min"] = lo;
    acc["max"] = hi;
  }
}


// An indices accessor of `count` SCALARs of `component_type`, claimed for the primitive.
int indices_accessor(Output& out, Json& pj, int component_type, std::int64_t count, std::optional<int> view) {
  Attribute indices;
  indices.semantic = "indices";
  indices.component_type = component_type;
  indices.components = 1;
  indices.count = count;
  const int acc = out.claim(pj.contains("indices") ? pj["indices"].get<int>() : -1, out.uses);
  set_accessor(out.json["accessors"][acc], indices, view);
  pj["indices"] = acc;
  return acc;
}

namespace {

// Uses of each accessor outside the denoised primitives (lines, animations, skins, ...).
std::vector<int> outside_uses(const Json& json, const std::vector<Surface>& surfaces) {
  std::vector<int> uses = accessor_uses(json);
  for (const auto& surface : surfaces)
    for (const auto& prim : surface.primitives) {
      const Json& pj = json["meshes"][prim.mesh]["primitives"][prim.index];
      for (const auto& [semantic, acc] : pj["attributes"].items())
        if (acc.is_number_integer() && acc.get<std::size_t>() < uses.size()) --uses[acc.get<std::size_t>()];
      if (pj.contains("indices") && pj["indices"].is_number_integer() && pj["indices"].get<std::size_t>() < uses.size())
        --uses[pj["indices"].get<std::size_t>()];
    }
  return uses;
}

// Recomputed normals, one per slot (welded vertex x input normal): hard edges stay split.
Vertices slot_normals(const Surface& surface, const TriMesh& mesh) {
  if (surface.normal_slots == 0) return {};
  std::vector<std::int64_t> corner_slot(static_cast<std::size_t>(mesh.F.rows()) * 3, -1);
  Eigen::Index f = 0;
  for (const auto& prim : surface.primitives)
    for (std::size_t c = 0; c < prim.triangles.size(); ++c) {
      const auto point = static_cast<std::size_t>(prim.point_offset) + prim.triangles[c];
      corner_slot[static_cast<std::size_t>(f) * 3 + c % 3] = surface.normal_slot[point];
      if (c % 3 == 2) ++f;
    }
  return accumulate_normals(mesh.V, mesh.F, corner_slot, surface.normal_slots);
}

// One position grid for every Draco payload of a mesh, slightly larger than its box so that
// float rounding of the bounds cannot push a vertex outside.
QuantizationBox position_grid(const TriMesh& mesh) {
  QuantizationBox box;
  const Eigen::RowVector3d lo = mesh.V.colwise().minCoeff(), hi = mesh.V.colwise().maxCoeff();
  const double range = std::max((hi - lo).maxCoeff(), 1e-12) * (1 + 1e-5);
  for (int k = 0; k < 3; ++k) box.origin[k] = static_cast<float>(lo(k) - range * 1e-6);
  box.range = static_cast<float>(range * (1 + 4e-6));
  return box;
}

// A primitive's attributes as written: new per-point positions and normals, the others as
// read, TANGENT dropped (see notes()).
std::vector<Attribute> written_attributes(const Primitive& prim, const Surface& surface, const TriMesh& mesh,
                                          const Vertices& normals) {
  Vertices P(prim.points, 3), N;
  for (std::int64_t p = 0; p < prim.points; ++p)
    P.row(p) = mesh.V.row(surface.point_to_weld[static_cast<std::size_t>(prim.point_offset + p)]);
  if (prim.normal >= 0) {
    N.resize(prim.points, 3);
    const Attribute& original = prim.attributes[static_cast<std::size_t>(prim.normal)];
    for (std::int64_t p = 0; p < prim.points; ++p) {
      const std::int64_t slot = surface.normal_slot[static_cast<std::size_t>(prim.point_offset + p)];
      const Vec3 n = normals.row(slot);
      // A point on no face keeps its input normal.
      N.row(p) = n.squaredNorm() > 0 ? n.transpose() : Eigen::RowVector3d(original.value(p, 0), original.value(p, 1), original.value(p, 2));
    }
  }
  std::vector<Attribute> attributes;
  for (std::size_t i = 0; i < prim.attributes.size(); ++i) {
    const Attribute& a = prim.attributes[i];
    if (static_cast<int>(i) == prim.tangent) continue;
    if (static_cast<int>(i) == prim.position) attributes.push_back(float_attribute("POSITION", a.accessor, P));
    else if (static_cast<int>(i) == prim.normal) attributes.push_back(float_attribute("NORMAL", a.accessor, N));
    else attributes.push_back(a);
  }
  return attributes;
}

// The Draco mesh of a primitive: the points its triangles use (primitives often share one
// vertex array), every attribute, a triangle list. `ids` receives each attribute's id.
void build_draco_mesh(const Primitive& prim, const std::vector<Attribute>& attributes, draco::Mesh& dm,
                      std::vector<int>& ids) {
  std::vector<std::int64_t> local(static_cast<std::size_t>(prim.points), -1);
  std::vector<std::uint32_t> used_points;
  for (const std::uint32_t p : prim.triangles)
    if (local[p] < 0) {
      local[p] = static_cast<std::int64_t>(used_points.size());
      used_points.push_back(p);
    }
  const auto n = static_cast<std::uint32_t>(used_points.size());
  dm.set_num_points(n);
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
}

// A primitive as KHR_draco_mesh_compression: one payload, accessors without views stating the
// decoded counts.
void write_draco_primitive(Output& out, Json& pj, const Primitive& prim, const std::vector<Attribute>& attributes,
                           const EncodeOptions& options, const QuantizationBox& box) {
  draco::Mesh dm;
  std::vector<int> ids;
  build_draco_mesh(prim, attributes, dm, ids);
  std::string payload = draco_encode(dm, options, box);
  // Draco merges identical points and drops degenerate faces: the accessors must state the
  // decoded counts, so read them back from the payload itself.
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
    const int acc = out.claim(a.accessor, out.uses);
    set_accessor(out.json["accessors"][acc], a, std::nullopt);
    pj["attributes"][a.semantic] = acc;
  }
  indices_accessor(out, pj, decoded->num_points() <= 65535 ? kUShort : kUInt,
                   static_cast<std::int64_t>(decoded->num_faces()) * 3, std::nullopt);
  pj.erase("mode");  // Draco stores a triangle list
  if (!pj.contains("extensions")) pj["extensions"] = Json::object();
  pj["extensions"][kDraco] = ext;
}

// A primitive uncompressed: new views for what changed. Primitives of one mesh that shared an
// input accessor share its rewrite (`rewritten`): the same points weld to the same vertices.
void write_plain_primitive(Output& out, Json& pj, const Primitive& prim, const std::vector<Attribute>& attributes,
                           std::map<std::pair<int, std::string>, int>& rewritten) {
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
    const int acc = out.claim(a.accessor, out.uses);
    set_accessor(out.json["accessors"][acc], a, view);
    pj["attributes"][a.semantic] = acc;
    if (!prim.from_draco) rewritten[key] = acc;
  }
  if (!prim.from_draco) return;
  std::string bytes(prim.triangles.size() * 4, '\0');
  std::memcpy(bytes.data(), prim.triangles.data(), bytes.size());
  const int view = out.append_view(std::move(bytes), kElementArrayBuffer);
  indices_accessor(out, pj, kUInt, static_cast<std::int64_t>(prim.triangles.size()), view);
  pj.erase("mode");
  pj["extensions"].erase(kDraco);
  if (pj["extensions"].empty()) pj.erase("extensions");
}

// Keeps only referenced buffer views, renumbered in order, and merges every buffer into one:
// returns its bytes (padded to 4). EXT_meshopt_compression views keep their compressed stream
// there and point at the fallback buffer (index 1, no data, decision 70), whose length is
// returned in `fallback`.
std::string pack_views(Output& out, const tinygltf::Model& model, std::size_t& fallback) {
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
      bytes = Reader(model, {}).view_bytes(static_cast<int>(i), "glTF");  // checked at decode too
    } else {
      bytes = out.new_views[i - static_cast<std::size_t>(out.old_views)];
    }
    pad_to_4(bin, '\0');
    const Json* meshopt = static_cast<std::int64_t>(i) < out.old_views ? nullptr : &out.new_meshopt[i - static_cast<std::size_t>(out.old_views)];
    if (meshopt && !meshopt->is_null()) {
      Json ext = *meshopt;
      ext["buffer"] = 0;
      ext["byteOffset"] = bin.size();
      ext["byteLength"] = bytes.size();
      fallback = (fallback + 3) / 4 * 4;
      view["buffer"] = 1;
      view["byteOffset"] = fallback;
      fallback += view["byteLength"].get<std::size_t>();
      view["extensions"] = Json::object();
      view["extensions"][kMeshopt] = ext;
    } else {
      erase_extension(view, kMeshopt);
      view["buffer"] = 0;
      view["byteOffset"] = bin.size();
      view["byteLength"] = bytes.size();
    }
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
  return bin;
}

// The one buffer: the input's first buffer's other fields, a data URI in a .gltf; and the
// meshopt fallback buffer when `fallback` > 0.
void set_buffer(Json& json, const Json& input, const std::string& bin, Format target, std::size_t fallback) {
  Json buffer = input.contains("buffers") && !input["buffers"].empty() ? input["buffers"][0] : Json::object();
  buffer.erase("uri");
  erase_extension(buffer, kMeshopt);  // a fallback buffer's mark
  buffer["byteLength"] = bin.size();
  if (target == Format::Gltf && !bin.empty()) buffer["uri"] = "data:application/octet-stream;base64," + base64_encode(bin);
  if (bin.empty()) json.erase("buffers");
  else json["buffers"] = Json::array({buffer});
  if (fallback == 0 || bin.empty()) return;
  Json placeholder = Json::object();
  placeholder["byteLength"] = fallback;
  placeholder["extensions"] = Json::object();
  placeholder["extensions"][kMeshopt] = Json{{"fallback", true}};
  json["buffers"].push_back(placeholder);
}

}  // namespace

Encoded GltfDocument::encode_json(const EncodeOptions& options) const {
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
  out.uses = outside_uses(json_, surfaces_);
  out.claimed.assign(out.uses.size(), 0);
  std::vector<std::string> written;  // what the positions became (Encoded::notes)
  std::vector<std::pair<int, PositionPlan>> grids;
  for (std::size_t s = 0; s < surfaces_.size(); ++s) {
    const Surface& surface = surfaces_[s];
    const TriMesh& mesh = meshes_[s];
    const Vertices normals = slot_normals(surface, mesh);
    const QuantizationBox box = position_grid(mesh);
    const PositionPlan plan = plan_positions(json_, surface, mesh, compression, options, written);
    if (plan.kind == PositionPlan::Kind::Grid) grids.emplace_back(surface.mesh, plan);
    std::map<std::pair<int, std::string>, int> rewritten;
    for (const auto& prim : surface.primitives) {
      Json& pj = out.json["meshes"][prim.mesh]["primitives"][prim.index];
      std::vector<Attribute> attributes = written_attributes(prim, surface, mesh, normals);
      store_quantized(attributes, prim, plan, compression);
      if (prim.tangent >= 0) pj["attributes"].erase("TANGENT");
      if (compression == Compression::Draco && !prim.has_targets) {
        write_draco_primitive(out, pj, prim, attributes, options, box);
      } else if (compression == Compression::Meshopt && !prim.has_targets) {
        write_meshopt_primitive(out, pj, prim, attributes, options);
      } else {
        write_plain_primitive(out, pj, prim, attributes, rewritten);
      }
    }
  }
  add_grid_nodes(out.json, grids);
  std::size_t fallback = 0;
  const std::string bin = pack_views(out, model_, fallback);
  set_buffer(out.json, json_, bin, target, fallback);
  set_extension_lists(out.json);
  std::string text = out.json.dump();
  if (target == Format::Gltf) return {std::move(text), compression, std::move(written)};
  return {make_glb(std::move(text), bin), compression, std::move(written)};
}

}  // namespace gltf

using namespace gltf;

Encoded write_plain_gltf(const std::vector<TriMesh>& all, Format format, const EncodeOptions& options) {
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
