// glTF output, the compact half: KHR_mesh_quantization (positions on an integer grid, or kept
// in the input's integer types) and EXT_meshopt_compression buffer views (decisions 70, 71).
#include <meshoptimizer.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>

#include "core/io/gltf_write.h"

namespace mdn::io::detail::gltf {
namespace {

constexpr const char* kQuantization = "KHR_mesh_quantization";

std::string type_text(int component_type, bool normalized) {
  const char* name = "float";
  switch (component_type) {
    case kByte: name = "byte"; break;
    case kUByte: name = "unsigned byte"; break;
    case kShort: name = "short"; break;
    case kUShort: name = "unsigned short"; break;
    case kUInt: name = "unsigned int"; break;
    default: break;
  }
  return std::string(name) + (normalized ? " normalized" : "");
}

// The stored integer range of a component type, and the factor from a normalized value.
struct IntRange {
  double lo, hi, unit;
};
IntRange int_range(int component_type) {
  switch (component_type) {
    case kByte: return {-128, 127, 127};
    case kUByte: return {0, 255, 255};
    case kShort: return {-32768, 32767, 32767};
    case kUShort: return {0, 65535, 65535};
    default: return {0, 4294967295.0, 4294967295.0};
  }
}

const char* mode_name(MeshoptMode mode) {
  switch (mode) {
    case MeshoptMode::Attributes: return "ATTRIBUTES";
    case MeshoptMode::Triangles: return "TRIANGLES";
    case MeshoptMode::Indices: return "INDICES";
  }
  return "ATTRIBUTES";
}

// Why a mesh's nodes cannot carry a dequantisation transform (empty: they can). A child node
// per instancing node takes the mesh and the transform; a skin ignores the node's transform,
// GPU instancing applies to the node that holds the mesh, morph targets' deltas would need the
// same scale, and points or lines of the mesh are not on the grid.
std::string grid_blocker(const Json& json, const Surface& surface) {
  for (const auto& prim : surface.primitives)
    if (prim.has_targets) return "the mesh has morph targets";
  if (json["meshes"][surface.mesh].value("primitives", Json::array()).size() != surface.primitives.size())
    return "the mesh also holds points or lines";
  for (const auto& node : json.value("nodes", Json::array())) {
    if (!node.is_object() || node.value("mesh", -1) != surface.mesh) continue;
    if (node.contains("skin")) return "the mesh is skinned";
    if (node.value("extensions", Json::object()).contains("EXT_mesh_gpu_instancing")) return "the mesh uses GPU instancing";
  }
  return {};
}

// Element i's bytes of `a` for each point of `order`, tightly packed.
Attribute gathered(const Attribute& a, const std::vector<std::uint32_t>& order) {
  Attribute out = a;
  const std::size_t element = a.element_size();
  out.count = static_cast<std::int64_t>(order.size());
  out.bytes.resize(element * order.size());
  for (std::size_t i = 0; i < order.size(); ++i)
    std::memcpy(out.bytes.data() + element * i, a.bytes.data() + element * order[i], element);
  return out;
}

// Float UVs within [0, 1] as unsigned short normalized, on a grid of 2^bits - 1 steps
// (nullopt: the UVs leave [0, 1], which normalized integers cannot hold without a texture
// transform).
std::optional<Attribute> quantized_uvs(const Attribute& uv, int bits) {
  const double steps = std::ldexp(1.0, bits) - 1;
  Eigen::MatrixXd values(uv.count, uv.components);
  for (std::int64_t i = 0; i < uv.count; ++i)
    for (int k = 0; k < uv.components; ++k) {
      const double u = uv.value(i, k);
      if (!(u >= 0 && u <= 1)) return std::nullopt;
      values(i, k) = std::round(u * steps) / steps;
    }
  return integer_attribute(uv.semantic, uv.accessor, values, kUShort, true);
}

// The recomputed NORMAL through the octahedral filter: 8-bit components (stride 4) for up to
// 8 bits or a byte input, 16-bit (stride 8) up to 16 bits or a short input; float otherwise.
bool write_oct_normal(Output& out, Json& pj, const Attribute& normal, int input_type, int bits) {
  int type = input_type == kByte ? kByte : input_type == kShort ? kShort : bits <= 8 ? kByte : bits <= 16 ? kShort : kFloat;
  if (type == kFloat) return false;
  const int stride = type == kByte ? 4 : 8;
  bits = std::min(bits, type == kByte ? 8 : 16);
  std::vector<float> unit(static_cast<std::size_t>(normal.count) * 4, 0.0f);
  for (std::int64_t i = 0; i < normal.count; ++i) {
    Vec3 n(normal.value(i, 0), normal.value(i, 1), normal.value(i, 2));
    n = n.squaredNorm() > 0 ? n.normalized() : Vec3(0, 0, 1);
    for (int k = 0; k < 3; ++k) unit[static_cast<std::size_t>(i * 4 + k)] = static_cast<float>(n(k));
  }
  const MeshoptView layout{stride, normal.count, MeshoptMode::Attributes, MeshoptFilter::Octahedral};
  const int view = out.append_meshopt_view(meshopt_encode_filter(unit.data(), layout, bits), layout, kArrayBuffer);
  Attribute stored = normal;
  stored.component_type = type;
  stored.normalized = true;
  const int acc = out.claim(normal.accessor, out.uses);
  set_accessor(out.json["accessors"][acc], stored, view);
  pj["attributes"]["NORMAL"] = acc;
  return true;
}

}  // namespace

int Output::append_meshopt_view(const std::string& plain, const MeshoptView& layout, std::optional<int> target) {
  Json view = Json::object();
  view["buffer"] = 0;
  view["byteLength"] = plain.size();
  if (layout.mode == MeshoptMode::Attributes) view["byteStride"] = layout.byte_stride;
  if (target) view["target"] = *target;
  Json ext = Json::object();
  ext["byteStride"] = layout.byte_stride;
  ext["mode"] = mode_name(layout.mode);
  ext["count"] = layout.count;
  if (layout.filter == MeshoptFilter::Octahedral) ext["filter"] = "OCTAHEDRAL";
  json["bufferViews"].push_back(view);
  new_views.push_back(meshopt_encode(plain, layout));
  new_meshopt.push_back(ext);
  return static_cast<int>(json["bufferViews"].size()) - 1;
}

std::optional<Attribute> integer_attribute(const std::string& semantic, int accessor, const Eigen::MatrixXd& values,
                                           int component_type, bool normalized) {
  const IntRange r = int_range(component_type);
  const int size = component_size(component_type);
  Attribute a;
  a.semantic = semantic;
  a.accessor = accessor;
  a.component_type = component_type;
  a.normalized = normalized;
  a.components = static_cast<int>(values.cols());
  a.count = values.rows();
  a.bytes.resize(static_cast<std::size_t>(a.count) * a.element_size());
  std::uint8_t* p = a.bytes.data();
  for (Eigen::Index i = 0; i < values.rows(); ++i)
    for (Eigen::Index k = 0; k < values.cols(); ++k, p += size) {
      const double q = std::round(normalized ? values(i, k) * r.unit : values(i, k));
      if (!(q >= r.lo && q <= r.hi)) return std::nullopt;
      const auto s32 = static_cast<std::int64_t>(q);
      const auto u32 = static_cast<std::uint32_t>(s32);
      std::memcpy(p, &u32, static_cast<std::size_t>(size));  // little-endian: the low bytes
    }
  return a;
}

PositionPlan plan_positions(const Json& json, const Surface& surface, const TriMesh& mesh, Compression compression,
                            const EncodeOptions& options, std::vector<std::string>& notes) {
  PositionPlan plan;
  if (compression == Compression::Draco) return plan;  // Draco quantises on its own grid
  const std::string where = "mesh " + std::to_string(surface.mesh) + ": POSITION written as ";
  const auto input = [&](const Primitive& p) { return p.attributes[static_cast<std::size_t>(p.position)]; };
  const Attribute& first = input(surface.primitives.front());
  bool same = true;
  for (const auto& prim : surface.primitives)
    same &= input(prim).component_type == first.component_type && input(prim).normalized == first.normalized;
  const std::string input_type = type_text(first.component_type, first.normalized);
  if (first.component_type != kFloat && same) {  // decision 71: a quantized input stays quantized
    if (integer_attribute("POSITION", -1, mesh.V, first.component_type, first.normalized)) {
      plan.kind = PositionPlan::Kind::AsInput;
      plan.component_type = first.component_type;
      plan.normalized = first.normalized;
      notes.push_back(where + input_type + ", as the input (KHR_mesh_quantization)");
    } else {
      notes.push_back(where + "float: the denoised positions leave the input's " + input_type + " range");
    }
    return plan;
  }
  if (compression != Compression::Meshopt) return plan;
  if (options.position_bits > 16) {
    notes.push_back(where + "float (position_bits " + std::to_string(options.position_bits) + " > 16)");
    return plan;
  }
  if (const std::string why = grid_blocker(json, surface); !why.empty()) {
    notes.push_back(where + "float (" + why + ")");
    return plan;
  }
  const Vec3 lo = mesh.V.colwise().minCoeff().transpose(), hi = mesh.V.colwise().maxCoeff().transpose();
  const double extent = (hi - lo).maxCoeff();
  plan.kind = PositionPlan::Kind::Grid;
  plan.component_type = kUShort;
  plan.bits = options.position_bits;
  plan.origin = lo;
  plan.scale = extent > 0 ? extent / (std::ldexp(1.0, plan.bits) - 1) : 1.0;
  notes.push_back(where + "unsigned short on a " + std::to_string(plan.bits) +
                  "-bit grid (KHR_mesh_quantization; a child node of each node instancing the mesh carries the scale)");
  return plan;
}

void store_quantized(std::vector<Attribute>& attributes, const Primitive& prim, const PositionPlan& plan,
                     Compression compression) {
  for (Attribute& a : attributes) {
    if (a.semantic == "POSITION" && plan.kind != PositionPlan::Kind::Float) {
      Vertices values(a.count, 3);
      for (std::int64_t i = 0; i < a.count; ++i)
        for (int k = 0; k < 3; ++k) values(i, k) = a.value(i, k);
      if (plan.kind == PositionPlan::Kind::Grid)
        values = ((values.rowwise() - plan.origin.transpose()) / plan.scale).eval();
      if (auto stored = integer_attribute("POSITION", a.accessor, values, plan.component_type, plan.normalized))
        a = std::move(*stored);  // the plan checked every welded position: always fits
    } else if (a.semantic == "NORMAL" && compression == Compression::None && prim.normal >= 0) {
      const Attribute& original = prim.attributes[static_cast<std::size_t>(prim.normal)];
      if (original.component_type != kByte && original.component_type != kShort) continue;
      Vertices values(a.count, 3);
      for (std::int64_t i = 0; i < a.count; ++i)
        for (int k = 0; k < 3; ++k) values(i, k) = a.value(i, k);
      if (auto stored = integer_attribute("NORMAL", a.accessor, values, original.component_type, true)) a = std::move(*stored);
    }
  }
}

void write_meshopt_primitive(Output& out, Json& pj, const Primitive& prim, const std::vector<Attribute>& attributes,
                             const EncodeOptions& options) {
  // The points the triangles use, in first-use order, then reordered as gltfpack does.
  std::vector<std::int64_t> local(static_cast<std::size_t>(prim.points), -1);
  std::vector<std::uint32_t> used;
  std::vector<unsigned int> first(prim.triangles.size());
  for (std::size_t c = 0; c < prim.triangles.size(); ++c) {
    const std::uint32_t p = prim.triangles[c];
    if (local[p] < 0) {
      local[p] = static_cast<std::int64_t>(used.size());
      used.push_back(p);
    }
    first[c] = static_cast<unsigned int>(local[p]);
  }
  const std::size_t n = used.size();
  std::vector<unsigned int> indices(first.size()), remap(n);
  meshopt_optimizeVertexCache(indices.data(), first.data(), first.size(), n);
  meshopt_optimizeVertexFetchRemap(remap.data(), indices.data(), indices.size(), n);
  std::vector<std::uint32_t> order(n);
  for (std::size_t v = 0; v < n; ++v) order[remap[v]] = used[v];
  for (unsigned int& i : indices) i = remap[i];

  const int input_normal = prim.normal >= 0 ? prim.attributes[static_cast<std::size_t>(prim.normal)].component_type : kFloat;
  for (const Attribute& a : attributes) {
    Attribute s = gathered(a, order);
    if (a.semantic == "NORMAL" && a.component_type == kFloat && write_oct_normal(out, pj, s, input_normal, options.normal_bits))
      continue;
    if (a.semantic.rfind("TEXCOORD_", 0) == 0 && a.component_type == kFloat && options.texcoord_bits > 0 &&
        options.texcoord_bits <= 16)
      if (auto q = quantized_uvs(s, options.texcoord_bits)) s = std::move(*q);
    std::string plain;
    const int padded = packed_vertex_bytes(s, plain);
    const MeshoptView layout{padded ? padded : static_cast<std::int64_t>(s.element_size()), s.count, MeshoptMode::Attributes,
                             MeshoptFilter::None};
    const int view = out.append_meshopt_view(plain, layout, kArrayBuffer);
    const int acc = out.claim(a.accessor, out.uses);
    set_accessor(out.json["accessors"][acc], s, view);
    pj["attributes"][a.semantic] = acc;
  }
  const bool short_indices = n <= 65536;
  std::string plain(indices.size() * (short_indices ? 2 : 4), '\0');
  for (std::size_t i = 0; i < indices.size(); ++i) {
    if (short_indices) {
      const auto v = static_cast<std::uint16_t>(indices[i]);
      std::memcpy(plain.data() + 2 * i, &v, 2);
    } else {
      std::memcpy(plain.data() + 4 * i, &indices[i], 4);
    }
  }
  const auto count = static_cast<std::int64_t>(indices.size());
  const int view = out.append_meshopt_view(plain, {short_indices ? 2 : 4, count, MeshoptMode::Triangles, MeshoptFilter::None},
                                           kElementArrayBuffer);
  indices_accessor(out, pj, short_indices ? kUShort : kUInt, count, view);
  pj.erase("mode");  // a triangle list
  if (pj.contains("extensions")) {
    pj["extensions"].erase(kDraco);
    if (pj["extensions"].empty()) pj.erase("extensions");
  }
}

void add_grid_nodes(Json& json, const std::vector<std::pair<int, PositionPlan>>& grids) {
  if (!json.contains("nodes")) return;
  const std::size_t count = json["nodes"].size();
  for (const auto& [mesh, plan] : grids)
    for (std::size_t k = 0; k < count; ++k) {
      Json& node = json["nodes"][k];
      if (!node.is_object() || node.value("mesh", -1) != mesh) continue;
      Json child = Json::object();
      child["mesh"] = mesh;
      child["translation"] = {plan.origin(0), plan.origin(1), plan.origin(2)};
      child["scale"] = {plan.scale, plan.scale, plan.scale};
      node.erase("mesh");
      if (!node.contains("children")) node["children"] = Json::array();
      node["children"].push_back(json["nodes"].size());
      json["nodes"].push_back(child);
    }
}

void set_extension_lists(Json& json) {
  bool draco = false, meshopt = false, quantized = false;
  const auto quantized_use = [](const std::string& semantic, const Json& acc) {
    const int type = acc.value("componentType", kFloat);
    if (type == kFloat) return false;
    if (semantic == "POSITION" || semantic == "NORMAL" || semantic == "TANGENT") return true;
    if (semantic.rfind("TEXCOORD_", 0) == 0) return type == kByte || type == kShort || !acc.value("normalized", false);
    return false;
  };
  const Json accessors = json.value("accessors", Json::array());
  const auto accessor = [&](const Json& index) {
    return index.is_number_integer() && index.get<std::size_t>() < accessors.size() ? accessors[index.get<std::size_t>()]
                                                                                    : Json::object();
  };
  for (const auto& mesh : json.value("meshes", Json::array()))
    for (const auto& prim : mesh.value("primitives", Json::array())) {
      if (prim.contains("extensions") && prim["extensions"].contains(kDraco)) draco = true;
      const Json attributes = prim.value("attributes", Json::object());  // named: items() must not outlive it
      for (const auto& [semantic, index] : attributes.items()) quantized |= quantized_use(semantic, accessor(index));
      for (const auto& target : prim.value("targets", Json::array()))
        for (const auto& [semantic, index] : target.items()) quantized |= quantized_use(semantic, accessor(index));
    }
  for (const auto& view : json.value("bufferViews", Json::array()))
    meshopt |= view.value("extensions", Json::object()).contains(kMeshopt);
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    Json names = json.value(list, Json::array());
    for (const char* ours : {kDraco, kMeshopt, kQuantization})
      names.erase(std::remove(names.begin(), names.end(), Json(ours)), names.end());
    if (draco) names.push_back(kDraco);
    if (meshopt) names.push_back(kMeshopt);  // decision 70: no fallback buffer with data, so required
    if (quantized) names.push_back(kQuantization);
    if (names.empty()) json.erase(list);
    else json[list] = names;
  }
}

}  // namespace mdn::io::detail::gltf
