// EXT_meshopt_compression on input (every mode and filter, with KHR_mesh_quantization), the
// output's compression following the input (resolve_compression), and buffers that lie.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <random>

#include "core/io/document.h"
#include "core/io/meshopt_codec.h"
#include "io/io_test_support.h"
#include "io/meshopt_fixture.h"
#include "support/mutate.h"

namespace mdn::io {
namespace {

using test_io::Json;

struct Glb {
  Json json;
  std::string bin;
};

Glb split_glb(const std::string& glb) {
  std::uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  return {Json::parse(glb.substr(20, length)), glb.substr(20 + length + 8)};
}

std::string pack(const Glb& g) { return test_io::pack_glb(g.json, g.bin); }

const test_io::SphereFixture& fixture() {
  static const test_io::SphereFixture f = test_io::make_sphere();
  return f;
}

TEST(Meshopt, DecodesToTheUncompressedSourceBitForBit) {
  const auto compressed = decode(test_io::meshopt_sphere_glb(fixture(), true), Format::Glb);
  const auto plain = decode(test_io::meshopt_sphere_glb(fixture(), false), Format::Glb);
  EXPECT_EQ(compressed->compression(), Compression::Meshopt);
  EXPECT_EQ(plain->compression(), Compression::None);
  ASSERT_EQ(compressed->surfaces().size(), 1u);
  EXPECT_EQ(compressed->surfaces()[0].V, plain->surfaces()[0].V);
  EXPECT_EQ(compressed->surfaces()[0].F, plain->surfaces()[0].F);  // TRIANGLES and INDICES modes
  // Against the float source: the dequantized SHORT positions (KHR_mesh_quantization) under
  // the node's scale are within half a quantization step of the fixture's noisy points.
  const TriMesh& s = compressed->surfaces()[0];
  double worst = 0;
  for (Eigen::Index v = 0; v < s.V.rows(); ++v) {
    double nearest = 1e9;
    for (int i = 0; i < fixture().vertices(); ++i) {
      const Vec3 p(fixture().noisy[3 * i], fixture().noisy[3 * i + 1], fixture().noisy[3 * i + 2]);
      nearest = std::min(nearest, (s.V.row(v).transpose() * test_io::kMeshoptScale - p).cwiseAbs().maxCoeff());
    }
    worst = std::max(worst, nearest);
  }
  std::printf("meshopt fixture: %lld vertices, %lld faces, max |position - source| = %.3g (step %.3g)\n",
              static_cast<long long>(s.V.rows()), static_cast<long long>(s.F.rows()), worst, test_io::kMeshoptScale / 32767);
  EXPECT_LE(worst, 0.5 * test_io::kMeshoptScale / 32767 + 1e-7);
}

TEST(Meshopt, FiltersDecodeToTheirSourceWithinTheirPrecision) {
  using detail::MeshoptFilter;
  using detail::MeshoptMode;
  const int n = 64;
  std::vector<float> normals(4 * n), quats(4 * n), values(2 * n);
  std::mt19937 rng(5);
  std::normal_distribution<float> g(0, 1);
  for (int i = 0; i < n; ++i) {
    Eigen::Vector3f v(g(rng), g(rng), g(rng));
    v.normalize();
    Eigen::Vector4f q(g(rng), g(rng), g(rng), g(rng));
    q.normalize();
    for (int k = 0; k < 3; ++k) normals[4 * i + k] = v(k);
    for (int k = 0; k < 4; ++k) quats[4 * i + k] = q(k);
    values[2 * i] = 1000 * g(rng), values[2 * i + 1] = 1e-3f * g(rng);
  }
  const detail::MeshoptView oct{8, n, MeshoptMode::Attributes, MeshoptFilter::Octahedral};
  const detail::MeshoptView quat{8, n, MeshoptMode::Attributes, MeshoptFilter::Quaternion};
  const detail::MeshoptView exp{8, n, MeshoptMode::Attributes, MeshoptFilter::Exponential};
  const auto roundtrip = [](const std::vector<float>& data, const detail::MeshoptView& view, int bits) {
    return detail::meshopt_decode(detail::meshopt_encode(detail::meshopt_encode_filter(data.data(), view, bits), view), view, "test");
  };
  const auto o = roundtrip(normals, oct, 16), q = roundtrip(quats, quat, 16), e = roundtrip(values, exp, 20);
  double normal_error = 0, quat_error = 0, exp_error = 0;
  for (int i = 0; i < n; ++i) {
    std::int16_t on[4], qn[4];
    float ev[2];
    std::memcpy(on, o.data() + 8 * i, 8);
    std::memcpy(qn, q.data() + 8 * i, 8);
    std::memcpy(ev, e.data() + 8 * i, 8);
    double sign = 0;  // q and -q are the same rotation
    for (int k = 0; k < 4; ++k) sign += qn[k] / 32767.0 * quats[4 * i + k];
    for (int k = 0; k < 3; ++k) normal_error = std::max(normal_error, std::abs(on[k] / 32767.0 - normals[4 * i + k]));
    for (int k = 0; k < 4; ++k)
      quat_error = std::max(quat_error, std::abs((sign < 0 ? -1 : 1) * qn[k] / 32767.0 - quats[4 * i + k]));
    for (int k = 0; k < 2; ++k)
      // libmeshoptimizer 0.18 shares one exponent across a vector's components: relative to
      // the vector's largest component.
      exp_error = std::max(exp_error, double(std::abs(ev[k] - values[2 * i + k]) /
                                             std::max(std::abs(values[2 * i]), std::abs(values[2 * i + 1]))));
  }
  std::printf("filters: octahedral %.3g, quaternion %.3g, exponential (relative) %.3g\n", normal_error, quat_error, exp_error);
  EXPECT_LT(normal_error, 1e-3);
  EXPECT_LT(quat_error, 1e-3);
  EXPECT_LT(exp_error, 1e-5);
}

// The rows of V sorted: the meshopt writer reorders vertices for the vertex cache.
Vertices sorted_rows(const Vertices& V) {
  std::vector<std::array<double, 3>> rows(static_cast<std::size_t>(V.rows()));
  for (Eigen::Index i = 0; i < V.rows(); ++i) rows[static_cast<std::size_t>(i)] = {V(i, 0), V(i, 1), V(i, 2)};
  std::sort(rows.begin(), rows.end());
  Vertices out(V.rows(), 3);
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int k = 0; k < 3; ++k) out(i, k) = rows[static_cast<std::size_t>(i)][static_cast<std::size_t>(k)];
  return out;
}

// The largest distance (max norm) from a row of A to its nearest row of B.
double farthest_from(const Vertices& A, const Vertices& B) {
  double worst = 0;
  for (Eigen::Index i = 0; i < A.rows(); ++i)
    worst = std::max(worst, (B.rowwise() - A.row(i)).cwiseAbs().rowwise().maxCoeff().minCoeff());
  return worst;
}

bool listed(const Json& json, const char* list, const char* name) {
  const Json names = json.value(list, Json::array());
  return std::find(names.begin(), names.end(), Json(name)) != names.end();
}

TEST(Meshopt, OutputFollowsTheInputAndKeepsItsTypes) {
  const std::string input = test_io::meshopt_sphere_glb(fixture(), true);
  const auto compressed = decode(input, Format::Glb);
  const auto plain = decode(test_io::meshopt_sphere_glb(fixture(), false), Format::Glb);
  EncodeOptions as_input;
  as_input.compression = Compression::AsInput;
  // Meshopt in, meshopt out (decision 70): required, with a fallback buffer without data.
  const Encoded out = compressed->encode(as_input);
  EXPECT_EQ(out.compression, Compression::Meshopt);
  const Glb g = split_glb(out.bytes);
  for (const char* list : {"extensionsUsed", "extensionsRequired"}) {
    EXPECT_TRUE(listed(g.json, list, "EXT_meshopt_compression")) << list;
    EXPECT_TRUE(listed(g.json, list, "KHR_mesh_quantization")) << list;
    EXPECT_FALSE(listed(g.json, list, "KHR_draco_mesh_compression")) << list;
  }
  ASSERT_EQ(g.json["buffers"].size(), 2u);
  EXPECT_FALSE(g.json["buffers"][1].contains("uri"));
  EXPECT_EQ(g.json["buffers"][1]["extensions"]["EXT_meshopt_compression"]["fallback"], true);
  // Quantized in, quantized out (decision 71): POSITION in the input's type; the node's
  // dequantisation transform is the input's, untouched.
  const Glb in = split_glb(input);
  const Json& prim = g.json["meshes"][0]["primitives"][0];
  const Json& in_prim = in.json["meshes"][0]["primitives"][0];
  for (const char* semantic : {"POSITION", "TEXCOORD_0"}) {
    const Json& acc = g.json["accessors"][prim["attributes"][semantic].get<int>()];
    const Json& in_acc = in.json["accessors"][in_prim["attributes"][semantic].get<int>()];
    EXPECT_EQ(acc["componentType"], in_acc["componentType"]) << semantic;
    EXPECT_EQ(acc.value("normalized", false), in_acc.value("normalized", false)) << semantic;
    EXPECT_TRUE(g.json["bufferViews"][acc["bufferView"].get<int>()]["extensions"].contains("EXT_meshopt_compression")) << semantic;
  }
  EXPECT_EQ(g.json["nodes"], in.json["nodes"]);
  EXPECT_NE(std::find(out.notes.begin(), out.notes.end(),
                      "mesh 0: POSITION written as short normalized, as the input (KHR_mesh_quantization)"),
            out.notes.end());
  // Nothing was denoised: the same positions come back exactly (the same integers).
  const auto back = decode(out.bytes, Format::Glb);
  EXPECT_EQ(back->compression(), Compression::Meshopt);
  EXPECT_LT((sorted_rows(back->surfaces()[0].V) - sorted_rows(compressed->surfaces()[0].V)).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_EQ(back->surfaces()[0].F.rows(), compressed->surfaces()[0].F.rows());
  // Uncompressed in, uncompressed out, positions float32 as they came.
  const std::string none = plain->encode(as_input).bytes;
  EXPECT_EQ(split_glb(none).json.dump().find("EXT_meshopt_compression"), std::string::npos);
  EXPECT_LT((decode(none, Format::Glb)->surfaces()[0].V - plain->surfaces()[0].V).cwiseAbs().maxCoeff(), 1e-7);
  // The library's default (compression unset) still writes Draco; None writes none, and a
  // quantized input keeps its POSITION type there too.
  EXPECT_NE(split_glb(compressed->encode({}).bytes).json.dump().find("KHR_draco_mesh_compression"), std::string::npos);
  EncodeOptions no_draco;
  no_draco.compression = Compression::None;
  const Glb g_none = split_glb(compressed->encode(no_draco).bytes);
  EXPECT_EQ(g_none.json.dump().find("EXT_meshopt_compression"), std::string::npos);
  EXPECT_EQ(g_none.json["accessors"][g_none.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()]["componentType"],
            5122);
  EXPECT_TRUE(listed(g_none.json, "extensionsRequired", "KHR_mesh_quantization"));
}

// A float32 glTF of a jittered sphere (from OFF: our writer's minimal asset, one node).
std::unique_ptr<MeshDocument> float_sphere() {
  const TriMesh m = test_io::sphere(24, 48);
  const Vertices V = test_io::jitter(m.V, 0.01);
  const std::string off = test_io::off_text(V, m.F);
  EncodeOptions glb;
  glb.format = Format::Glb;
  glb.compression = Compression::None;
  return decode(decode(off, Format::Off)->encode(glb).bytes, Format::Glb);
}

TEST(Meshopt, FloatInputIsQuantizedOnAGridCarriedByANode) {
  const auto plain = float_sphere();
  for (const int bits : {14, 16}) {
    EncodeOptions meshopt;
    meshopt.compression = Compression::Meshopt;
    meshopt.position_bits = bits;
    const Encoded out = plain->encode(meshopt);
    const Glb g = split_glb(out.bytes);
    const Json& pos = g.json["accessors"][g.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()];
    EXPECT_EQ(pos["componentType"], 5123);
    EXPECT_FALSE(pos.value("normalized", false));
    EXPECT_LE(pos["max"][0].get<double>(), std::ldexp(1.0, bits) - 1);
    // The node that held the mesh now holds a child with the mesh and the grid's transform.
    ASSERT_EQ(g.json["nodes"].size(), 2u);
    EXPECT_FALSE(g.json["nodes"][0].contains("mesh"));
    EXPECT_EQ(g.json["nodes"][0]["children"], Json::array({1}));
    EXPECT_EQ(g.json["nodes"][1]["mesh"], 0);
    // Read back in the scene's frame (our reader's placements), every vertex is within half a
    // grid step of the float input.
    const auto back = decode(out.bytes, Format::Glb);
    const auto placements = back->placements();
    ASSERT_EQ(placements[0].size(), 1u);
    const Eigen::Matrix4d& world = placements[0][0];
    Vertices placed = back->surfaces()[0].V;
    for (Eigen::Index i = 0; i < placed.rows(); ++i)
      placed.row(i) = (world * Eigen::Vector4d(placed(i, 0), placed(i, 1), placed(i, 2), 1)).head<3>().transpose();
    const auto in_placements = plain->placements();
    Vertices expected = plain->surfaces()[0].V;
    for (Eigen::Index i = 0; i < expected.rows(); ++i)
      expected.row(i) = (in_placements[0][0] * Eigen::Vector4d(expected(i, 0), expected(i, 1), expected(i, 2), 1)).head<3>().transpose();
    ASSERT_EQ(placed.rows(), expected.rows());
    const double extent = (expected.colwise().maxCoeff() - expected.colwise().minCoeff()).maxCoeff();
    const double step = extent / (std::ldexp(1.0, bits) - 1);
    EXPECT_LT(farthest_from(placed, expected), 0.51 * step) << bits << " bits";
    EXPECT_LT(farthest_from(expected, placed), 0.51 * step) << bits << " bits";
  }
  // More than 16 bits: float32 positions, still meshopt-compressed, no node added.
  EncodeOptions wide;
  wide.compression = Compression::Meshopt;
  wide.position_bits = 20;
  const Encoded out = plain->encode(wide);
  const Glb g = split_glb(out.bytes);
  EXPECT_EQ(g.json["accessors"][g.json["meshes"][0]["primitives"][0]["attributes"]["POSITION"].get<int>()]["componentType"], 5126);
  EXPECT_EQ(g.json["nodes"].size(), 1u);
  EXPECT_EQ(out.notes, std::vector<std::string>{"mesh 0: POSITION written as float (position_bits 20 > 16)"});
}

TEST(Compression, ResolvedInOnePlace) {
  EncodeOptions o;
  EXPECT_EQ(resolve_compression(o, Compression::None), Compression::Draco);  // unset: `draco`
  o.compression = mdn::io::Compression::None;
  EXPECT_EQ(resolve_compression(o, Compression::Draco), Compression::None);
  o.compression = Compression::AsInput;
  EXPECT_EQ(resolve_compression(o, Compression::Draco), Compression::Draco);
  EXPECT_EQ(resolve_compression(o, Compression::None), Compression::None);
  EXPECT_EQ(resolve_compression(o, Compression::Meshopt), Compression::Meshopt);
  o.compression = Compression::Draco;
  EXPECT_EQ(resolve_compression(o, Compression::None), Compression::Draco);
  o.compression = Compression::None;
  EXPECT_EQ(resolve_compression(o, Compression::Draco), Compression::None);
  for (const Compression c : {Compression::AsInput, Compression::None, Compression::Draco, Compression::Meshopt})
    EXPECT_EQ(compression_from_string(to_string(c)), c);
  EXPECT_EQ(compression_from_string("gzip"), std::nullopt);
  // Draco in -> Draco out when following the input.
  const auto plain = decode(test_io::meshopt_sphere_glb(fixture(), false), Format::Glb);
  const auto draco = decode(plain->encode({}).bytes, Format::Glb);
  EXPECT_EQ(draco->compression(), Compression::Draco);
  EncodeOptions as_input;
  as_input.compression = Compression::AsInput;
  EXPECT_NE(split_glb(draco->encode(as_input).bytes).json.dump().find("KHR_draco_mesh_compression"), std::string::npos);
}

template <class Error>
std::string error_of(const Glb& g) {
  try {
    decode(pack(g), Format::Glb);
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong error type: ") + e.what();
  }
  return "no error";
}

Json& ext(Glb& g, int view) { return g.json["bufferViews"][view]["extensions"]["EXT_meshopt_compression"]; }

TEST(MeshoptHostile, LyingBuffersAreClearErrors) {
  const Glb good = split_glb(test_io::meshopt_sphere_glb(fixture(), true));
  Glb g = good;
  ext(g, 0)["count"] = 1000000;
  EXPECT_NE(error_of<FormatError>(g).find("disagree with EXT_meshopt_compression's 1000000 elements"), std::string::npos);
  g = good;
  ext(g, 0)["count"] = std::int64_t{1} << 40;
  EXPECT_NE(error_of<LimitError>(g).find("more than the limits allow"), std::string::npos);
  g = good;
  ext(g, 0)["byteLength"] = 1 << 30;
  EXPECT_NE(error_of<FormatError>(g).find("reach past the end of buffer 0"), std::string::npos);
  g = good;
  ext(g, 1)["byteStride"] = 6;
  EXPECT_NE(error_of<FormatError>(g).find("multiple of 4"), std::string::npos);
  g = good;
  ext(g, 2)["filter"] = "QUATERNION";  // stride 8 is fine for it: decodes, but as another filter
  EXPECT_EQ(error_of<FormatError>(g), "no error");
  g = good;
  ext(g, 1)["filter"] = "QUATERNION";  // stride 4
  EXPECT_NE(error_of<FormatError>(g).find("QUATERNION needs byteStride 8"), std::string::npos);
  g = good;
  ext(g, 4)["filter"] = "OCTAHEDRAL";
  EXPECT_NE(error_of<FormatError>(g).find("filter must be NONE"), std::string::npos);
  g = good;
  ext(g, 4)["mode"] = "STRIPS";
  EXPECT_NE(error_of<FormatError>(g).find("mode 'STRIPS'"), std::string::npos);
  g = good;
  ext(g, 0)["byteLength"] = ext(g, 0)["byteLength"].get<int>() - 20;  // the tail cut off
  EXPECT_NE(error_of<FormatError>(g).find("does not decode"), std::string::npos);
  g = good;
  ext(g, 0)["buffer"] = 7;
  EXPECT_NE(error_of<FormatError>(g).find("buffer 7"), std::string::npos);
  g = good;
  ext(g, 0)["buffer"] = 1;  // the fallback buffer holds no data
  EXPECT_NE(error_of<FormatError>(g).find("reach past the end of buffer 1"), std::string::npos);
  g = good;
  ext(g, 0).erase("count");
  EXPECT_NE(error_of<FormatError>(g).find("no \"count\""), std::string::npos);
  g = good;
  g.json["bufferViews"][0]["extensions"].erase("EXT_meshopt_compression");  // a plain view on the fallback
  EXPECT_NE(error_of<FormatError>(g).find("reaches past the end of its buffer"), std::string::npos);
}

// Seeded mutants of the meshopt GLB (binary mutations: counts, truncations, bit flips in the
// compressed streams): each decodes or raises a typed error, never a crash.
TEST(MeshoptHostile, MutantsDecodeOrRaiseTypedErrors) {
  const std::string seed = test_io::meshopt_sphere_glb(fixture(), true);
  std::mt19937_64 rng(18);
  const int mutants = test::mutants_per_seed(400);
  int decoded = 0;
  for (int i = 0; i < mutants; ++i) {
    const std::string bytes = test::mutate(seed, false, rng);
    try {
      auto doc = decode(bytes, Format::Glb);
      for (const TriMesh& s : doc->surfaces()) ASSERT_TRUE(s.V.allFinite()) << "mutant " << i;
      ++decoded;
    } catch (const FormatError&) {
    } catch (const UnsupportedError&) {
    } catch (const LimitError&) {
    } catch (const InvalidMeshError&) {
    }
  }
  EXPECT_GT(decoded, 0);
  EXPECT_LT(decoded, mutants);
}

}  // namespace
}  // namespace mdn::io
