// Internal to mdn_io: what the glTF writer (gltf_write.cpp) shares with its compact half
// (gltf_write_compact.cpp: KHR_mesh_quantization and EXT_meshopt_compression output).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/io/gltf_model.h"
#include "core/io/meshopt_codec.h"

namespace mdn::io::detail::gltf {

// The output being written: the input's JSON, edited, and the bytes of the new buffer views.
struct Output {
  Json json;
  std::vector<std::string> new_views;  // bytes of buffer views appended to json["bufferViews"]
  // Per new view: null, or its EXT_meshopt_compression object (without buffer / byteOffset /
  // byteLength, which pack_views sets) when new_views holds the compressed stream.
  std::vector<Json> new_meshopt;
  std::int64_t old_views = 0;
  std::vector<int> uses;               // accessor -> uses outside the denoised primitives
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
    new_meshopt.emplace_back(nullptr);
    return static_cast<int>(json["bufferViews"].size()) - 1;
  }
  // A view whose data is `plain` (count x byte_stride bytes), stored compressed.
  int append_meshopt_view(const std::string& plain, const MeshoptView& layout, std::optional<int> target);
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

// Tightly packed attribute bytes, each element padded to a multiple of 4 bytes as glTF
// requires of vertex attributes (returns the stride used, 0 when no padding was needed).
int packed_vertex_bytes(const Attribute& a, std::string& out);
// A float32 attribute of `values` (#values by 3).
Attribute float_attribute(const std::string& semantic, int accessor, const Vertices& values);
// Accessor JSON for attribute data: keeps name/extras/extensions of the input accessor; POSITION
// gets min / max (in the stored component values, as glTF 2.0 and KHR_mesh_quantization say).
void set_accessor(Json& acc, const Attribute& a, std::optional<int> view);
// An indices accessor of `count` SCALARs of `component_type`, claimed for the primitive.
int indices_accessor(Output& out, Json& pj, int component_type, std::int64_t count, std::optional<int> view);

// How a surface's POSITION is written (decisions 70 and 71).
struct PositionPlan {
  enum class Kind { Float, AsInput, Grid } kind = Kind::Float;
  int component_type = kFloat;  // AsInput: the input's; Grid: unsigned short
  bool normalized = false;
  Vec3 origin = Vec3::Zero();   // Grid: stored q = round((p - origin) / scale), in [0, 2^bits - 1]
  double scale = 1;
  int bits = 0;
};

// The plan for `surface` (its denoised mesh `mesh`) given the resolved compression: the input's
// integer type where every denoised position fits it (uncompressed or meshopt output); for
// meshopt output of float positions with position_bits <= 16, a grid on the mesh's box when
// nodes can carry the scale; float32 otherwise. `note` receives what was chosen and why.
PositionPlan plan_positions(const Json& json, const Surface& surface, const TriMesh& mesh, Compression compression,
                            const EncodeOptions& options, std::vector<std::string>& notes);
// `values` (#points by components, in the accessor's number space: dequantised for normalized types)
// stored as `component_type`; nullopt when a value does not fit.
std::optional<Attribute> integer_attribute(const std::string& semantic, int accessor, const Eigen::MatrixXd& values,
                                           int component_type, bool normalized);
// The written POSITION / NORMAL of a primitive in the types `plan` and the input call for
// (uncompressed output: NORMAL in the input's integer type; meshopt writes normals itself).
void store_quantized(std::vector<Attribute>& attributes, const Primitive& prim, const PositionPlan& plan,
                     Compression compression);

// A primitive as EXT_meshopt_compression views: its points reordered for the vertex cache and
// fetch (meshopt_optimizeVertexCache / VertexFetchRemap), every attribute in a view of its own
// (NORMAL through the octahedral filter, UVs quantised by texcoord_bits), the triangles in
// TRIANGLES mode.
void write_meshopt_primitive(Output& out, Json& pj, const Primitive& prim, const std::vector<Attribute>& attributes,
                             const EncodeOptions& options);

// Nodes that instance a Grid mesh get a child node carrying the mesh and the grid's scale
// and offset (KHR_mesh_quantization's dequantisation transform).
void add_grid_nodes(Json& json, const std::vector<std::pair<int, PositionPlan>>& grids);
// extensionsUsed / extensionsRequired: KHR_draco_mesh_compression, EXT_meshopt_compression
// and KHR_mesh_quantization listed iff the output uses them.
void set_extension_lists(Json& json);

}  // namespace mdn::io::detail::gltf
