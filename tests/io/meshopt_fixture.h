// A GLB of the test sphere compressed with EXT_meshopt_compression by libmeshoptimizer's own
// encoders (through core/io/meshopt_codec.h) (every mode and filter), and the same asset uncompressed (its views hold exactly
// what the meshopt decoder yields, so both must decode to the same surfaces bit for bit).
//   POSITION   SHORT normalized VEC3 (KHR_mesh_quantization, stride 8), node scale 1.2  mode ATTRIBUTES
//   NORMAL     BYTE normalized VEC3 (stride 4)                                          filter OCTAHEDRAL
//   TEXCOORD_0 FLOAT VEC2 (stride 8)                                                    filter EXPONENTIAL
//   _ROTATION  SHORT normalized VEC4 (stride 8)                                         filter QUATERNION
//   indices    upper primitive UNSIGNED_SHORT                                           mode TRIANGLES
//              lower primitive UNSIGNED_SHORT                                           mode INDICES
#pragma once

#include <cmath>
#include <string>
#include <vector>

#include "core/io/meshopt_codec.h"
#include "gltf_fixtures.h"

namespace mdn::test_io {

constexpr double kMeshoptScale = 1.2;  // POSITION = node scale x dequantized SHORT

struct MeshoptStream {
  std::string encoded, plain;  // the extension's bytes; the decoded view's bytes
  io::detail::MeshoptView layout;
};

inline const char* mode_name(io::detail::MeshoptMode m) {
  return m == io::detail::MeshoptMode::Attributes ? "ATTRIBUTES" : m == io::detail::MeshoptMode::Triangles ? "TRIANGLES" : "INDICES";
}
inline const char* filter_name(io::detail::MeshoptFilter f) {
  using F = io::detail::MeshoptFilter;
  return f == F::None ? "NONE" : f == F::Octahedral ? "OCTAHEDRAL" : f == F::Quaternion ? "QUATERNION" : "EXPONENTIAL";
}

// `data`: the stored bytes (for a filter: what its encoder wrote). `plain` is what a loader
// gets back: the filter's decoding of them.
inline MeshoptStream meshopt_stream(const std::string& data, io::detail::MeshoptView layout) {
  MeshoptStream s;
  s.layout = layout;
  s.encoded = io::detail::meshopt_encode(data, layout);
  const std::vector<unsigned char> plain = io::detail::meshopt_decode(s.encoded, layout, "fixture");
  s.plain.assign(plain.begin(), plain.end());
  return s;
}

// A GLB of `json` (its "buffers" as given: buffer 0 is the BIN chunk) and `bin`.
inline std::string pack_glb(const Json& json, const std::string& bin) {
  std::string text = json.dump();
  while (text.size() % 4) text += ' ';
  std::string out = "glTF";
  const auto u32 = [&out](std::size_t v) {
    const auto w = static_cast<std::uint32_t>(v);
    out.append(reinterpret_cast<const char*>(&w), 4);
  };
  u32(2);
  u32(12 + 8 + text.size() + 8 + bin.size());
  u32(text.size());
  u32(0x4E4F534A);
  out += text;
  u32(bin.size());
  u32(0x004E4942);
  return out + bin;
}

template <class T>
std::string bytes_of(const std::vector<T>& v) {
  return std::string(reinterpret_cast<const char*>(v.data()), v.size() * sizeof(T));
}

// The sphere fixture (its noisy positions), compressed or not.
inline std::string meshopt_sphere_glb(const SphereFixture& f, bool compressed) {
  const int n = f.vertices();
  std::vector<std::int16_t> position(std::size_t(n) * 4, 0);
  std::vector<float> normal(std::size_t(n) * 4, 0), uv(std::size_t(n) * 2), rotation(std::size_t(n) * 4);
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 3; ++k) {
      position[std::size_t(4 * i + k)] =
          static_cast<std::int16_t>(std::lround(f.noisy[std::size_t(3 * i + k)] / kMeshoptScale * 32767.0));
      normal[std::size_t(4 * i + k)] = f.normal[std::size_t(3 * i + k)];
    }
    uv[std::size_t(2 * i)] = f.uv[std::size_t(2 * i)];
    uv[std::size_t(2 * i + 1)] = f.uv[std::size_t(2 * i + 1)];
    const double angle = 0.1 * i, c = std::cos(angle / 2), s = std::sin(angle / 2);
    rotation[std::size_t(4 * i)] = float(s * 0.6), rotation[std::size_t(4 * i + 1)] = float(s * 0.8);
    rotation[std::size_t(4 * i + 2)] = 0, rotation[std::size_t(4 * i + 3)] = float(c);
  }
  using io::detail::MeshoptFilter;
  using io::detail::MeshoptMode;
  using io::detail::MeshoptView;
  const MeshoptView oct{4, n, MeshoptMode::Attributes, MeshoptFilter::Octahedral};
  const MeshoptView exp{8, n, MeshoptMode::Attributes, MeshoptFilter::Exponential};
  const MeshoptView quat{8, n, MeshoptMode::Attributes, MeshoptFilter::Quaternion};
  const std::vector<MeshoptStream> streams = {
      meshopt_stream(bytes_of(position), {8, n, MeshoptMode::Attributes, MeshoptFilter::None}),
      meshopt_stream(io::detail::meshopt_encode_filter(normal.data(), oct, 8), oct),
      meshopt_stream(io::detail::meshopt_encode_filter(uv.data(), exp, 15), exp),
      meshopt_stream(io::detail::meshopt_encode_filter(rotation.data(), quat, 12), quat),
      meshopt_stream(bytes_of(f.upper), {2, std::int64_t(f.upper.size()), MeshoptMode::Triangles, MeshoptFilter::None}),
      meshopt_stream(bytes_of(f.lower), {2, std::int64_t(f.lower.size()), MeshoptMode::Indices, MeshoptFilter::None})};

  Json json;
  json["asset"] = {{"version", "2.0"}, {"generator", "mdn io test (libmeshoptimizer)"}};
  json["scene"] = 0;
  json["scenes"] = Json::array({{{"nodes", {0}}}});
  json["nodes"] = Json::array({{{"mesh", 0}, {"scale", {kMeshoptScale, kMeshoptScale, kMeshoptScale}}}});
  std::string bin;  // buffer 0: the GLB chunk (compressed streams, or the plain views)
  std::size_t fallback = 0;
  for (const MeshoptStream& s : streams) {
    while (bin.size() % 4) bin += '\0';
    const bool indices = s.layout.mode != MeshoptMode::Attributes;
    Json view = {{"buffer", compressed ? 1 : 0}, {"byteOffset", compressed ? fallback : bin.size()},
                 {"byteLength", s.plain.size()}};
    if (!indices) view["byteStride"] = s.layout.byte_stride;
    view["target"] = indices ? 34963 : 34962;
    if (compressed) {
      Json ext = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", s.encoded.size()},
                  {"byteStride", s.layout.byte_stride}, {"count", s.layout.count}, {"mode", mode_name(s.layout.mode)}};
      if (s.layout.filter != MeshoptFilter::None) ext["filter"] = filter_name(s.layout.filter);
      view["extensions"] = {{"EXT_meshopt_compression", ext}};
      bin += s.encoded;
      fallback += (s.plain.size() + 3) / 4 * 4;
    } else {
      bin += s.plain;
    }
    json["bufferViews"].push_back(view);
  }
  while (bin.size() % 4) bin += '\0';
  const auto accessor = [&](int view, int component_type, const char* type, int count, bool normalized) {
    Json a = {{"bufferView", view}, {"componentType", component_type}, {"count", count}, {"type", type}};
    if (normalized) a["normalized"] = true;
    json["accessors"].push_back(a);
  };
  accessor(0, 5122, "VEC3", n, true);
  json["accessors"][0]["min"] = {-32767, -32767, -32767};
  json["accessors"][0]["max"] = {32767, 32767, 32767};
  accessor(1, 5120, "VEC3", n, true);
  accessor(2, 5126, "VEC2", n, false);
  accessor(3, 5122, "VEC4", n, true);
  accessor(4, 5123, "SCALAR", static_cast<int>(f.upper.size()), false);
  accessor(5, 5123, "SCALAR", static_cast<int>(f.lower.size()), false);
  const Json attributes = {{"POSITION", 0}, {"NORMAL", 1}, {"TEXCOORD_0", 2}, {"_ROTATION", 3}};
  json["meshes"] = Json::array({{{"primitives", {{{"attributes", attributes}, {"indices", 4}},
                                                 {{"attributes", attributes}, {"indices", 5}}}}}});
  json["buffers"] = Json::array({{{"byteLength", bin.size()}}});
  json["extensionsUsed"] = {"KHR_mesh_quantization"};
  json["extensionsRequired"] = {"KHR_mesh_quantization"};
  if (compressed) {
    json["buffers"].push_back({{"byteLength", fallback}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
    json["extensionsUsed"].push_back("EXT_meshopt_compression");
    json["extensionsRequired"].push_back("EXT_meshopt_compression");
  }
  return pack_glb(json, bin);
}

}  // namespace mdn::test_io
