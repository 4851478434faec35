// STL adapter: binary and ASCII, the "solid" header trap, the weld (facet order and count kept),
// round trips, and bad input (truncation, counts against the size, non-finite numbers, limits).
#include <gtest/gtest.h>

#include <cstring>
#include <random>

#include "core/io/document.h"
#include "io_test_support.h"
#include "support/mutate.h"

namespace mdn::io {
namespace {

using test_io::grid;
using test_io::sphere;

// A soup of `mesh`: every facet with its own three corners, as STL writers emit it.
std::string binary_stl(const TriMesh& mesh, std::string header = "made by a test", std::uint16_t attribute = 0) {
  header.resize(80, ' ');
  std::string out = header;
  const auto n = static_cast<std::uint32_t>(mesh.F.rows());
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    float values[12] = {0, 0, 1};
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < 3; ++k) values[3 + 3 * c + k] = float(mesh.V(mesh.F(f, c), k));
    out.append(reinterpret_cast<const char*>(values), sizeof values);
    out.append(reinterpret_cast<const char*>(&attribute), 2);
  }
  return out;
}

std::string ascii_stl(const TriMesh& mesh, const std::string& name = "part") {
  std::string out = "solid " + name + "\n";
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    out += " facet normal 0 0 1\n  outer loop\n";
    for (int c = 0; c < 3; ++c) {
      char line[128];
      std::snprintf(line, sizeof line, "   vertex %.9g %.9g %.9g\n", mesh.V(mesh.F(f, c), 0), mesh.V(mesh.F(f, c), 1),
                    mesh.V(mesh.F(f, c), 2));
      out += line;
    }
    out += "  endloop\n endfacet\n";
  }
  return out + "endsolid " + name + "\n";
}

// Each facet's corners, in the order written, as a #F*3 by 3 matrix.
Vertices corners(const TriMesh& m) {
  Vertices C(m.F.rows() * 3, 3);
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    for (int c = 0; c < 3; ++c) C.row(3 * f + c) = m.V.row(m.F(f, c));
  return C;
}

TEST(StlDetection, SizeIdentityTellsSolidHeadedBinaryFromAscii) {
  const TriMesh m = grid(3);
  EXPECT_EQ(format_from_extension("scan/Part.STL"), Format::Stl);
  EXPECT_EQ(format_from_string("stl"), Format::Stl);
  EXPECT_EQ(to_string(Format::Stl), "stl");
  EXPECT_EQ(media_type(Format::Stl), "model/stl");
  EXPECT_EQ(sniff_format(binary_stl(m)), Format::Stl);
  EXPECT_EQ(sniff_format(binary_stl(m, "solid part exported by CAD")), Format::Stl);
  EXPECT_EQ(sniff_format(ascii_stl(m)), Format::Stl);
  EXPECT_EQ(sniff_format("solid empty\nendsolid empty\n"), Format::Stl);
  // "solid" alone is not enough: it must read on as facets, or have the binary size.
  EXPECT_EQ(sniff_format("solid state physics\nis a field\n"), std::nullopt);
  // A binary file whose header starts with "solid" decodes as binary (18 facets, welded grid).
  auto doc = decode(binary_stl(m, "solid part"), Format::Stl);
  EXPECT_EQ(doc->surfaces()[0].F.rows(), m.F.rows());
  EXPECT_EQ(doc->surfaces()[0].V.rows(), m.V.rows());
}

TEST(Stl, WeldFindsSharedCornersAndKeepsFacetOrderAndCount) {
  const TriMesh m = sphere(8, 12);
  for (const std::string& bytes : {binary_stl(m), ascii_stl(m)}) {
    auto doc = decode(bytes, Format::Stl);
    ASSERT_EQ(doc->surfaces().size(), 1u);
    const TriMesh& s = doc->surfaces()[0];
    EXPECT_EQ(s.V.rows(), m.V.rows());  // 3 #F corners welded back to the sphere's vertices
    EXPECT_EQ(s.F.rows(), m.F.rows());
    EXPECT_LT((corners(s) - corners(m)).cwiseAbs().maxCoeff(), 1e-6);  // facet f is still facet f
  }
}

TEST(Stl, BinaryRoundTripKeepsHeaderAttributesAndRecomputesNormals) {
  const TriMesh m = grid(4);
  const std::string input = binary_stl(m, "solid colours", 0x7c1f);
  auto doc = decode(input, Format::Stl);
  Vertices moved = test_io::jitter(doc->surfaces()[0].V, 0.01);
  doc->surfaces()[0].V = moved;
  const std::string out = doc->encode({}).bytes;
  ASSERT_EQ(out.size(), input.size());
  EXPECT_EQ(out.substr(0, 84), input.substr(0, 84));
  auto back = decode(out, Format::Stl);
  EXPECT_EQ(back->surfaces()[0].F, doc->surfaces()[0].F);
  EXPECT_LT((back->surfaces()[0].V - moved).cwiseAbs().maxCoeff(), 1e-6);  // float32
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const char* facet = out.data() + 84 + 50 * f;
    float normal[3];
    std::uint16_t attribute = 0;
    std::memcpy(normal, facet, 12);
    std::memcpy(&attribute, facet + 48, 2);
    EXPECT_EQ(attribute, 0x7c1f);
    const TriMesh& s = doc->surfaces()[0];
    const Vec3 a = s.V.row(s.F(f, 0)), b = s.V.row(s.F(f, 1)), c = s.V.row(s.F(f, 2));
    const Vec3 expected = (b - a).cross(c - a).normalized();
    EXPECT_NEAR(normal[0], expected(0), 1e-6);
    EXPECT_NEAR(normal[2], expected(2), 1e-6);
  }
}

TEST(Stl, AsciiStaysAsciiAndOtherContainersWork) {
  const TriMesh m = grid(3);
  auto doc = decode(ascii_stl(m, "bracket"), Format::Stl);
  const std::string out = doc->encode({}).bytes;
  EXPECT_EQ(out.substr(0, 14), "solid bracket\n");
  EXPECT_NE(out.find("endsolid bracket"), std::string::npos);
  auto back = decode(out, Format::Stl);
  // Written as float32 (STL's precision) in shortest text: the second round trip is exact.
  EXPECT_LT((back->surfaces()[0].V - doc->surfaces()[0].V).cwiseAbs().maxCoeff(), 1e-7);
  EXPECT_EQ(back->encode({}).bytes, out);
  EXPECT_EQ(back->surfaces()[0].F, doc->surfaces()[0].F);
  // To another container and from another container (binary STL).
  EncodeOptions to_ply;
  to_ply.format = Format::Ply;
  EXPECT_EQ(decode(doc->encode(to_ply).bytes, Format::Ply)->surfaces()[0].F, doc->surfaces()[0].F);
  EncodeOptions to_stl;
  to_stl.format = Format::Stl;
  auto ply = decode(doc->encode(to_ply).bytes, Format::Ply);
  const std::string stl = ply->encode(to_stl).bytes;
  EXPECT_EQ(stl.size(), 84 + 50 * std::size_t(m.F.rows()));
  EXPECT_EQ(decode(stl, Format::Stl)->surfaces()[0].F, doc->surfaces()[0].F);
  // Several solids in one ASCII file make one surface, in order.
  const std::string two = ascii_stl(grid(1), "a") + ascii_stl(grid(2), "b");
  EXPECT_EQ(decode(two, Format::Stl)->surfaces()[0].F.rows(), 2 + 8);
}

template <class Error>
std::string error_of(const std::string& bytes, const Limits& limits = {}) {
  try {
    decode(bytes, Format::Stl, limits);
  } catch (const Error& e) {
    return e.what();
  } catch (const std::exception& e) {
    return std::string("wrong error type: ") + e.what();
  }
  return "no error";
}

TEST(Stl, BadInputIsATypedErrorNamingTheProblem) {
  const std::string good = binary_stl(grid(2));
  EXPECT_NE(error_of<FormatError>(good.substr(0, good.size() - 7)).find("declares 8 triangles"), std::string::npos);
  EXPECT_NE(error_of<FormatError>(good + "extra").find("truncated or not STL"), std::string::npos);
  EXPECT_NE(error_of<FormatError>(good.substr(0, 40)).find("shorter than"), std::string::npos);
  std::string lying = good;
  const std::uint32_t many = 0xffffffffu;
  std::memcpy(lying.data() + 80, &many, 4);
  EXPECT_NE(error_of<FormatError>(lying).find("4294967295 triangles"), std::string::npos);
  std::string nan_corner = good;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::memcpy(nan_corner.data() + 84 + 50 * 3 + 16, &nan, 4);
  EXPECT_NE(error_of<FormatError>(nan_corner).find("triangle 3 has a non-finite"), std::string::npos);

  const std::string text = ascii_stl(grid(2));
  EXPECT_NE(error_of<FormatError>(text.substr(0, text.size() / 2)).find("STL line"), std::string::npos);
  std::string inf_text = text;
  inf_text.replace(inf_text.find("vertex ") + 7, 1, "inf");
  EXPECT_NE(error_of<FormatError>(inf_text).find("non-finite vertex coordinate"), std::string::npos);
  std::string word = text;
  word.replace(word.find("outer"), 5, "inner");
  EXPECT_NE(error_of<FormatError>(word).find("expected 'outer'"), std::string::npos);
}

TEST(StlLimits, DeclaredAndCountedTrianglesAreCheckedBeforeAllocating) {
  Limits small;
  small.max_faces = 7;
  EXPECT_NE(error_of<LimitError>(binary_stl(grid(2)), small).find("8 triangles"), std::string::npos);
  EXPECT_NE(error_of<LimitError>(ascii_stl(grid(2)), small).find("more than 7 triangles"), std::string::npos);
  Limits bytes;
  bytes.max_decoded_bytes = 1000;
  EXPECT_NE(error_of<LimitError>(binary_stl(grid(2)), bytes).find("decoded size limit"), std::string::npos);
  Limits vertices;
  vertices.max_vertices = 8;  // the welded grid has 9
  EXPECT_NE(error_of<LimitError>(binary_stl(grid(2)), vertices).find("vertices (welded)"), std::string::npos);
}

// Seeded mutants of both encodings: each decodes (and re-encodes) or raises a typed error.
TEST(StlHostile, MutantsDecodeOrRaiseTypedErrors) {
  const TriMesh m = sphere(6, 8);
  const int mutants = test::mutants_per_seed(400);
  for (const bool text : {false, true}) {
    const std::string seed = text ? ascii_stl(m) : binary_stl(m, "solid trap");
    std::mt19937_64 rng(text ? 11 : 12);
    int decoded = 0;
    for (int i = 0; i < mutants; ++i) {
      const std::string bytes = test::mutate(seed, text, rng);
      try {
        auto doc = decode(bytes, Format::Stl);
        const TriMesh& s = doc->surfaces()[0];
        ASSERT_TRUE(s.V.allFinite()) << "mutant " << i;
        ASSERT_TRUE(s.F.size() == 0 || (s.F.minCoeff() >= 0 && s.F.maxCoeff() < s.V.rows())) << "mutant " << i;
        decode(doc->encode({}).bytes, Format::Stl);
        ++decoded;
      } catch (const FormatError&) {
      } catch (const LimitError&) {
      } catch (const UnsupportedError&) {
      }
    }
    EXPECT_GT(decoded, 0);
    EXPECT_LT(decoded, mutants);
  }
}

}  // namespace
}  // namespace mdn::io
