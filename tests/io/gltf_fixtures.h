// glTF fixtures built in code: a UV sphere whose seam column is duplicated (different UVs,
// positions that differ in the last float bits), split into two primitives with two
// materials, one with a PNG texture; a points primitive; a node transform, an instanced
// mesh, extras and an unknown extension. Variants: quantized, sparse, triangle strips.
#pragma once

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

namespace mdn::test_io {

using Json = nlohmann::ordered_json;

struct SphereFixture {
  std::vector<float> clean, noisy;  // per glTF vertex, xyz
  std::vector<float> uv;            // per glTF vertex
  std::vector<float> normal;        // per glTF vertex (the clean sphere's)
  std::vector<std::uint16_t> upper, lower;  // triangle lists of the two primitives
  int rings = 12, segments = 24;
  int vertices() const { return static_cast<int>(clean.size() / 3); }
};

// Vertex (r, s) for r in [0, rings], s in [0, segments] (s = segments duplicates s = 0).
inline SphereFixture make_sphere(double noise = 0.02, unsigned seed = 11) {
  SphereFixture f;
  std::mt19937 rng(seed);
  std::normal_distribution<double> gauss(0.0, noise);
  const int cols = f.segments + 1;
  std::vector<double> offsets((f.rings + 1) * f.segments * 3);
  for (auto& o : offsets) o = gauss(rng);
  for (int r = 0; r <= f.rings; ++r)
    for (int s = 0; s <= f.segments; ++s) {
      const double th = M_PI * r / f.rings, ph = 2 * M_PI * (s % f.segments) / f.segments;
      const double p[3] = {std::sin(th) * std::cos(ph), std::sin(th) * std::sin(ph), std::cos(th)};
      // Poles: every column's copy gets the same offset (one surface vertex).
      const int key = (r == 0 || r == f.rings) ? r * f.segments : r * f.segments + (s % f.segments);
      for (int k = 0; k < 3; ++k) {
        f.clean.push_back(static_cast<float>(p[k]));
        float n = static_cast<float>(p[k] + offsets[static_cast<std::size_t>(key) * 3 + k]);
        if (s == f.segments) n = std::nextafter(n, 10.0f);  // seam copy differs in the last bit
        f.noisy.push_back(n);
        f.normal.push_back(static_cast<float>(p[k]));
      }
      f.uv.push_back(static_cast<float>(s) / f.segments);
      f.uv.push_back(static_cast<float>(r) / f.rings);
    }
  auto id = [&](int r, int s) { return static_cast<std::uint16_t>(r * cols + s); };
  for (int r = 0; r < f.rings; ++r)
    for (int s = 0; s < f.segments; ++s) {
      auto& out = r < f.rings / 2 ? f.upper : f.lower;
      // The caps get one triangle per column (the other would join two pole copies).
      if (r < f.rings - 1) out.insert(out.end(), {id(r, s), id(r + 1, s), id(r + 1, s + 1)});
      if (r > 0) out.insert(out.end(), {id(r, s), id(r + 1, s + 1), id(r, s + 1)});
    }
  return f;
}

// A 1 x 1 RGBA PNG.
inline std::string tiny_png() {
  static const unsigned char png[] = {
      0x89, 0x50, 0x4E, 0x47, 0x0D, 0x0A, 0x1A, 0x0A, 0x00, 0x00, 0x00, 0x0D, 0x49, 0x48, 0x44, 0x52, 0x00, 0x00, 0x00, 0x01,
      0x00, 0x00, 0x00, 0x01, 0x08, 0x06, 0x00, 0x00, 0x00, 0x1F, 0x15, 0xC4, 0x89, 0x00, 0x00, 0x00, 0x0D, 0x49, 0x44, 0x41,
      0x54, 0x78, 0x9C, 0x63, 0xF8, 0xCF, 0xC0, 0xF0, 0x1F, 0x00, 0x05, 0x00, 0x01, 0xFF, 0x89, 0x99, 0x3D, 0x1D, 0x00, 0x00,
      0x00, 0x00, 0x49, 0x45, 0x4E, 0x44, 0xAE, 0x42, 0x60, 0x82};
  return std::string(reinterpret_cast<const char*>(png), sizeof png);
}

enum class Variant { Plain, Quantized, Sparse };

struct Builder {
  Json json = Json::object();
  std::string bin;
  int view(const std::string& bytes, int target = 0) {
    while (bin.size() % 4) bin += '\0';
    Json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
    if (target) v["target"] = target;
    bin += bytes;
    json["bufferViews"].push_back(v);
    return static_cast<int>(json["bufferViews"].size()) - 1;
  }
  template <class T>
  int accessor(const std::vector<T>& values, int component_type, const char* type, int components, bool normalized,
               int target, bool minmax = false) {
    std::string bytes(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
    Json a = {{"bufferView", view(bytes, target)}, {"componentType", component_type},
              {"count", values.size() / static_cast<std::size_t>(components)}, {"type", type}};
    if (normalized) a["normalized"] = true;
    if (minmax) {
      Json lo = Json::array(), hi = Json::array();
      for (int k = 0; k < components; ++k) {
        T mn = values[static_cast<std::size_t>(k)], mx = mn;
        for (std::size_t i = static_cast<std::size_t>(k); i < values.size(); i += static_cast<std::size_t>(components)) {
          mn = std::min(mn, values[i]);
          mx = std::max(mx, values[i]);
        }
        lo.push_back(mn);
        hi.push_back(mx);
      }
      a["min"] = lo;
      a["max"] = hi;
    }
    json["accessors"].push_back(a);
    return static_cast<int>(json["accessors"].size()) - 1;
  }
  std::string glb() {
    while (bin.size() % 4) bin += '\0';
    json["buffers"] = Json::array({{{"byteLength", bin.size()}}});
    std::string text = json.dump();
    while (text.size() % 4) text += ' ';
    std::string out = "glTF";
    auto u32 = [&out](std::uint32_t v) { out.append(reinterpret_cast<const char*>(&v), 4); };
    u32(2);
    u32(static_cast<std::uint32_t>(12 + 8 + text.size() + 8 + bin.size()));
    u32(static_cast<std::uint32_t>(text.size()));
    u32(0x4E4F534A);
    out += text;
    u32(static_cast<std::uint32_t>(bin.size()));
    u32(0x004E4942);
    out += bin;
    return out;
  }
};

// The scene described at the top of this file, as a GLB.
inline std::string sphere_scene_glb(const SphereFixture& f, Variant variant = Variant::Plain) {
  Builder b;
  b.json["asset"] = {{"version", "2.0"}, {"generator", "mdn io test"}, {"extras", {{"origin", "fixture"}}}};
  b.json["extras"] = {{"capture", {{"station", 7}, {"operator", "ada"}}}};
  b.json["scene"] = 0;
  b.json["scenes"] = Json::array({{{"name", "scan"}, {"nodes", {0, 1, 2}}}});
  b.json["nodes"] = Json::array({
      {{"name", "scan-a"}, {"mesh", 0}, {"translation", {1.5, 0.0, -2.0}}, {"rotation", {0.0, 0.7071068, 0.0, 0.7071068}}, {"extras", {{"id", 42}}}},
      {{"name", "scan-b"}, {"mesh", 0}, {"scale", {2.0, 2.0, 2.0}}},
      {{"name", "markers"}, {"mesh", 1}},
  });
  int position = -1;
  if (variant == Variant::Quantized) {
    // KHR_mesh_quantization: SHORT normalized positions (scaled back by the node in a real asset).
    // Vertex attributes must be 4-byte aligned: 6-byte elements get a byteStride of 8.
    std::vector<std::int16_t> q;
    for (std::size_t i = 0; i < f.noisy.size(); ++i) {
      q.push_back(static_cast<std::int16_t>(std::lround(std::clamp(f.noisy[i] / 1.2f, -1.0f, 1.0f) * 32767)));
      if (i % 3 == 2) q.push_back(0);
    }
    position = b.accessor(q, 5122, "VEC4", 4, true, 34962, true);
    Json& acc = b.json["accessors"][position];
    acc["type"] = "VEC3";
    acc["min"].erase(3);
    acc["max"].erase(3);
    b.json["bufferViews"][acc["bufferView"].get<int>()]["byteStride"] = 8;
  } else if (variant == Variant::Sparse) {
    // Dense clean positions, with the noisy ones substituted through a sparse accessor on
    // every second vertex (so both paths matter).
    position = b.accessor(f.clean, 5126, "VEC3", 3, false, 34962, true);
    std::vector<std::uint16_t> idx;
    std::vector<float> values;
    for (int i = 0; i < f.vertices(); i += 2) {
      idx.push_back(static_cast<std::uint16_t>(i));
      for (int k = 0; k < 3; ++k) values.push_back(f.noisy[static_cast<std::size_t>(i * 3 + k)]);
    }
    const int iv = b.view(std::string(reinterpret_cast<const char*>(idx.data()), idx.size() * 2));
    const int vv = b.view(std::string(reinterpret_cast<const char*>(values.data()), values.size() * 4));
    b.json["accessors"][position]["sparse"] = {{"count", idx.size()}, {"indices", {{"bufferView", iv}, {"componentType", 5123}}}, {"values", {{"bufferView", vv}}}};
    // min / max of the substituted data
    Json lo = Json::array(), hi = Json::array();
    for (int k = 0; k < 3; ++k) {
      float mn = 1e9f, mx = -1e9f;
      for (int i = 0; i < f.vertices(); ++i) {
        const float v = (i % 2 == 0 ? f.noisy : f.clean)[static_cast<std::size_t>(i * 3 + k)];
        mn = std::min(mn, v);
        mx = std::max(mx, v);
      }
      lo.push_back(mn);
      hi.push_back(mx);
    }
    b.json["accessors"][position]["min"] = lo;
    b.json["accessors"][position]["max"] = hi;
  } else {
    position = b.accessor(f.noisy, 5126, "VEC3", 3, false, 34962, true);
  }
  const int normal = b.accessor(f.normal, 5126, "VEC3", 3, false, 34962);
  int uv = -1;
  if (variant == Variant::Quantized) {
    std::vector<std::uint16_t> q;
    for (float v : f.uv) q.push_back(static_cast<std::uint16_t>(std::lround(v * 65535)));
    uv = b.accessor(q, 5123, "VEC2", 2, true, 34962);
  } else {
    uv = b.accessor(f.uv, 5126, "VEC2", 2, false, 34962);
  }
  const int upper = b.accessor(f.upper, 5123, "SCALAR", 1, false, 34963);
  const int lower = b.accessor(f.lower, 5123, "SCALAR", 1, false, 34963);
  const Json attributes = {{"POSITION", position}, {"NORMAL", normal}, {"TEXCOORD_0", uv}};
  b.json["meshes"] = Json::array({
      {{"name", "sphere"}, {"extras", {{"lod", 0}}},
       {"primitives", {{{"attributes", attributes}, {"indices", upper}, {"material", 0}},
                       {{"attributes", attributes}, {"indices", lower}, {"material", 1}}}}},
  });
  // A points primitive (landmarks): must pass through untouched.
  const std::vector<float> marks = {0, 0, 1.5f, 0, 0, -1.5f};
  const int mark_acc = b.accessor(marks, 5126, "VEC3", 3, false, 34962, true);
  b.json["meshes"].push_back({{"name", "landmarks"}, {"primitives", {{{"attributes", {{"POSITION", mark_acc}}}, {"mode", 0}}}}});
  const int image_view = b.view(tiny_png());
  b.json["images"] = Json::array({{{"bufferView", image_view}, {"mimeType", "image/png"}, {"name", "albedo"}}});
  b.json["samplers"] = Json::array({{{"magFilter", 9729}, {"minFilter", 9987}}});
  b.json["textures"] = Json::array({{{"source", 0}, {"sampler", 0}}});
  b.json["materials"] = Json::array({
      {{"name", "skin"}, {"pbrMetallicRoughness", {{"baseColorTexture", {{"index", 0}}}, {"metallicFactor", 0.0}}}, {"extras", {{"shader", "pbr"}}}},
      {{"name", "plain"}, {"pbrMetallicRoughness", {{"baseColorFactor", {0.8, 0.2, 0.2, 1.0}}}}, {"doubleSided", true}},
  });
  if (variant == Variant::Quantized) b.json["extensionsUsed"] = {"KHR_mesh_quantization"}, b.json["extensionsRequired"] = {"KHR_mesh_quantization"};
  return b.glb();
}

// A ribbon of n quads as one TRIANGLE_STRIP primitive (non-indexed) and as a fan.
inline std::string strip_and_fan_glb(int n) {
  Builder b;
  b.json["asset"] = {{"version", "2.0"}};
  std::vector<float> strip;
  for (int i = 0; i <= n; ++i) strip.insert(strip.end(), {float(i), 0.0f, 0.0f, float(i), 1.0f, 0.05f * (i % 2)});
  std::vector<float> fan = {0, 0, 5};
  for (int i = 0; i <= n; ++i) fan.insert(fan.end(), {float(std::cos(i * 0.3)), float(std::sin(i * 0.3)), 5.0f});
  const int s = b.accessor(strip, 5126, "VEC3", 3, false, 34962, true);
  const int fa = b.accessor(fan, 5126, "VEC3", 3, false, 34962, true);
  b.json["meshes"] = Json::array({{{"primitives", {{{"attributes", {{"POSITION", s}}}, {"mode", 5}}}}},
                                  {{"primitives", {{{"attributes", {{"POSITION", fa}}}, {"mode", 6}}}}}});
  b.json["nodes"] = Json::array({{{"mesh", 0}}, {{"mesh", 1}}});
  b.json["scenes"] = Json::array({{{"nodes", {0, 1}}}});
  return b.glb();
}

}  // namespace mdn::test_io
