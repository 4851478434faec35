// OFF, OBJ and PLY adapters, format detection and cross-format conversion.
#include <gtest/gtest.h>

#include <cstring>

#include "core/io/document.h"
#include "io_test_support.h"

namespace mdn::io {
namespace {

using test_io::grid;

std::string off_text(const TriMesh& m) {
  std::string s = "OFF\n# a comment\n" + std::to_string(m.V.rows()) + " " + std::to_string(m.F.rows()) + " 0\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    s += std::to_string(m.V(i, 0)) + " " + std::to_string(m.V(i, 1)) + " " + std::to_string(m.V(i, 2)) + "\n";
  for (Eigen::Index f = 0; f < m.F.rows(); ++f)
    s += "3 " + std::to_string(m.F(f, 0)) + " " + std::to_string(m.F(f, 1)) + " " + std::to_string(m.F(f, 2)) + "\n";
  return s;
}

TEST(FormatDetection, NamesExtensionsAndMediaTypes) {
  for (Format f : {Format::Off, Format::Obj, Format::Ply, Format::Drc, Format::Glb, Format::Gltf})
    EXPECT_EQ(format_from_string(to_string(f)), f);
  EXPECT_EQ(format_from_extension("scan/Bunny.GLB"), Format::Glb);
  EXPECT_EQ(format_from_extension("a.b/mesh.off"), Format::Off);
  EXPECT_EQ(format_from_extension("mesh"), std::nullopt);
  EXPECT_EQ(format_from_extension("mesh.3mf"), std::nullopt);
  EXPECT_EQ(media_type(Format::Glb), "model/gltf-binary");
  EXPECT_EQ(media_type(Format::Gltf), "model/gltf+json");
}

TEST(FormatDetection, SniffsContent) {
  EXPECT_EQ(sniff_format(std::string("glTF\x02\0\0\0", 8)), Format::Glb);
  EXPECT_EQ(sniff_format("DRACO\x02\x02"), Format::Drc);
  EXPECT_EQ(sniff_format("ply\nformat ascii 1.0\n"), Format::Ply);
  EXPECT_EQ(sniff_format("# made by hand\nOFF\n3 1 0\n"), Format::Off);
  EXPECT_EQ(sniff_format("COFF 3 1 0\n"), Format::Off);
  EXPECT_EQ(sniff_format("# obj\nmtllib a.mtl\nv 0 0 0\n"), Format::Obj);
  EXPECT_EQ(sniff_format("  {\"asset\":{\"version\":\"2.0\"}}"), Format::Gltf);
  EXPECT_EQ(sniff_format("hello world"), std::nullopt);
  EXPECT_EQ(sniff_format(""), std::nullopt);
}

TEST(Off, RoundTripIsExactAndDeterministic) {
  const TriMesh m = grid(4);
  auto doc = decode(off_text(m), Format::Off);
  ASSERT_EQ(doc->surfaces().size(), 1u);
  EXPECT_EQ(doc->surfaces()[0].F, m.F);
  EXPECT_TRUE(doc->surfaces()[0].V.isApprox(m.V));
  Vertices moved = test_io::jitter(m.V, 0.01);
  doc->surfaces()[0].V = moved;
  const std::string out = doc->encode({}).bytes;
  EXPECT_EQ(out, doc->encode({}).bytes);
  auto back = decode(out, Format::Off);
  EXPECT_EQ(back->surfaces()[0].V, moved);  // shortest round-trip text: bit-exact
  EXPECT_EQ(back->surfaces()[0].F, m.F);
}

TEST(Off, KeepsColoursAndRecomputesNoffNormals) {
  const std::string coff = "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 9 9 9\n";
  auto doc = decode(coff, Format::Off);
  doc->surfaces()[0].V(0, 2) = 0.5;
  const std::string out = doc->encode({}).bytes;
  EXPECT_NE(out.find("COFF\n"), std::string::npos);
  EXPECT_NE(out.find("0 0 0.5 255 0 0 255\n"), std::string::npos);
  EXPECT_NE(out.find("1 0 0 0 255 0 255\n"), std::string::npos);
  EXPECT_NE(out.find("3 0 1 2 9 9 9\n"), std::string::npos);

  const std::string noff = "NOFF 3 1 0\n0 0 0 9 9 9\n1 0 0 9 9 9\n0 1 0 9 9 9\n3 0 1 2\n";
  auto doc2 = decode(noff, Format::Off);
  const std::string out2 = doc2->encode({}).bytes;
  EXPECT_NE(out2.find("0 0 0 0 0 1\n"), std::string::npos) << out2;
  EXPECT_EQ(out2.find('9'), std::string::npos);
  EXPECT_FALSE(doc2->notes().empty());
}

TEST(Off, MalformedInputsGetTypedErrors) {
  EXPECT_THROW(decode("", Format::Off), FormatError);
  EXPECT_THROW(decode("PLY\n", Format::Off), FormatError);
  EXPECT_THROW(decode("OFF\n3 1\n0 0 0\n1 0 0\n", Format::Off), FormatError);            // truncated
  EXPECT_THROW(decode("OFF\n3 1 0\n0 0 x\n1 0 0\n0 1 0\n3 0 1 2\n", Format::Off), FormatError);
  EXPECT_THROW(decode("OFF\n3 1 0\n0 0 nan\n1 0 0\n0 1 0\n3 0 1 2\n", Format::Off), FormatError);
  EXPECT_THROW(decode("OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n", Format::Off), InvalidMeshError);  // quad
  EXPECT_THROW(decode("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n", Format::Off), InvalidMeshError);
  EXPECT_THROW(decode("OFF\n999999999 1 0\n0 0 0\n", Format::Off), LimitError);
  EXPECT_THROW(decode("OFF\n1000 1000 0\n0 0 0\n", Format::Off), FormatError);  // counts exceed the bytes
  EXPECT_THROW(decode("OFF BINARY\n", Format::Off), UnsupportedError);
  Limits small;
  small.max_faces = 1;
  EXPECT_THROW(decode(off_text(grid(2)), Format::Off, small), LimitError);
}

TEST(Obj, KeepsEverythingButPositionsAndNormals) {
  const std::string obj =
      "# test\nmtllib m.mtl\no quad\n"
      "v 0 0 0\nv 1 0 0 0.5 0.25 0.125\nv 1 1 0\nv 0 1 0\n"
      "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
      "vn 0 0 1\nvn 0 0 1\n"
      "usemtl red\ns off\n"
      "f 1/1/1 2/2/1 3/3/1\n"
      "f -4/-4/2 -2/-2/2 -1/-1/2\n";
  auto doc = decode(obj, Format::Obj);
  TriMesh& s = doc->surfaces()[0];
  ASSERT_EQ(s.V.rows(), 4);
  ASSERT_EQ(s.F.rows(), 2);
  EXPECT_EQ(s.F.row(1), Eigen::RowVector3i(0, 2, 3));
  s.V(1, 0) = 2.0;  // tilts nothing (stays in z=0) but moves vertex 2
  s.V(3, 2) = 1.0;  // lifts vertex 4: face 2 tilts
  const std::string out = doc->encode({}).bytes;
  EXPECT_NE(out.find("v 2 0 0 0.5 0.25 0.125\n"), std::string::npos) << out;  // colour kept
  EXPECT_NE(out.find("v 0 1 1\n"), std::string::npos);
  for (const char* kept : {"# test\nmtllib m.mtl\no quad\n", "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n", "usemtl red\ns off\n",
                           "f 1/1/1 2/2/1 3/3/1\nf -4/-4/2 -2/-2/2 -1/-1/2\n"})
    EXPECT_NE(out.find(kept), std::string::npos) << kept;
  EXPECT_NE(out.find("vn 0 0 1\n"), std::string::npos);  // face 1 still flat
  auto back = decode(out, Format::Obj);
  EXPECT_EQ(back->surfaces()[0].V, s.V);
  // The second vn now follows the tilted face (0,0,0) (1,1,0) (0,1,1): normal (1,-1,1)/sqrt(3).
  EXPECT_NE(out.find("vn 0.5773502691896257 -0.5773502691896257 0.5773502691896257\n"), std::string::npos) << out;
}

TEST(Obj, MalformedInputsGetTypedErrors) {
  EXPECT_THROW(decode("# nothing\n", Format::Obj), FormatError);
  EXPECT_THROW(decode("v 0 0\nf 1 1 1\n", Format::Obj), FormatError);
  EXPECT_THROW(decode("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", Format::Obj), FormatError);  // index 0
  EXPECT_THROW(decode("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", Format::Obj), InvalidMeshError);
  EXPECT_THROW(decode("v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 3\n", Format::Obj), InvalidMeshError);  // quad
  EXPECT_THROW(decode("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/5 2/5 3/5\n", Format::Obj), FormatError);  // vt missing
}

// PLY with colours in the three encodings.
std::string ply_text(const std::string& encoding) {
  const TriMesh m = grid(2);
  std::string s = "ply\nformat " + encoding + " 1.0\ncomment made in a test\nelement vertex " + std::to_string(m.V.rows()) +
                  "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\n"
                  "property uchar blue\nelement face " + std::to_string(m.F.rows()) +
                  "\nproperty list uchar int vertex_indices\nproperty ushort quality\nend_header\n";
  const bool ascii = encoding == "ascii";
  const bool big = encoding == "binary_big_endian";
  auto put = [&](const void* p, std::size_t n) {
    std::string bytes(static_cast<const char*>(p), n);
    if (big) std::reverse(bytes.begin(), bytes.end());
    s += bytes;
  };
  for (Eigen::Index i = 0; i < m.V.rows(); ++i) {
    const float xyz[3] = {float(m.V(i, 0)), float(m.V(i, 1)), float(m.V(i, 2))};
    const unsigned char rgb[3] = {static_cast<unsigned char>(i * 10), 7, 200};
    if (ascii) {
      s += std::to_string(xyz[0]) + " " + std::to_string(xyz[1]) + " " + std::to_string(xyz[2]) + " " +
           std::to_string(rgb[0]) + " 7 200\n";
    } else {
      for (float v : xyz) put(&v, 4);
      s.append(reinterpret_cast<const char*>(rgb), 3);
    }
  }
  for (Eigen::Index f = 0; f < m.F.rows(); ++f) {
    const std::uint16_t quality = static_cast<std::uint16_t>(1000 + f);
    if (ascii) {
      s += "3 " + std::to_string(m.F(f, 0)) + " " + std::to_string(m.F(f, 1)) + " " + std::to_string(m.F(f, 2)) + " " +
           std::to_string(quality) + "\n";
    } else {
      s += char(3);
      for (int k = 0; k < 3; ++k) {
        const std::int32_t idx = m.F(f, k);
        put(&idx, 4);
      }
      put(&quality, 2);
    }
  }
  return s;
}

class PlyEncodings : public ::testing::TestWithParam<std::string> {};

TEST_P(PlyEncodings, RoundTripKeepsHeaderAndExtraProperties) {
  const std::string input = ply_text(GetParam());
  auto doc = decode(input, Format::Ply);
  TriMesh& s = doc->surfaces()[0];
  ASSERT_EQ(s.V.rows(), 9);
  ASSERT_EQ(s.F, grid(2).F);
  // Unchanged positions give back the input byte for byte (ascii: same shortest text).
  if (GetParam() != "ascii") {
    EXPECT_EQ(doc->encode({}).bytes, input);
  }
  s.V(4, 2) = 0.25;
  const std::string out = doc->encode({}).bytes;
  EXPECT_EQ(out.substr(0, out.find("end_header")), input.substr(0, input.find("end_header")));
  EXPECT_EQ(out.size(), GetParam() == "ascii" ? out.size() : input.size());
  auto back = decode(out, Format::Ply);
  EXPECT_EQ(back->surfaces()[0].V(4, 2), 0.25);
  EXPECT_EQ(back->surfaces()[0].F, s.F);
  // Round trip of the round trip is a fixed point: colours and face quality survived.
  EXPECT_EQ(back->encode({}).bytes, out);
}

INSTANTIATE_TEST_SUITE_P(All, PlyEncodings,
                         ::testing::Values("ascii", "binary_little_endian", "binary_big_endian"));

TEST(Ply, AsciiColoursSurvive) {
  auto doc = decode(ply_text("ascii"), Format::Ply);
  const std::string out = doc->encode({}).bytes;
  EXPECT_NE(out.find(" 80 7 200\n"), std::string::npos) << out;  // vertex 8's colour
  EXPECT_NE(out.find(" 1007\n"), std::string::npos);             // last face's quality
}

TEST(Ply, MalformedInputsGetTypedErrors) {
  const std::string good = ply_text("binary_little_endian");
  EXPECT_THROW(decode("plx\n", Format::Ply), FormatError);
  EXPECT_THROW(decode("ply\nformat ascii 1.0\nelement vertex 3\n", Format::Ply), FormatError);  // no end_header
  EXPECT_THROW(decode(good.substr(0, good.size() - 5), Format::Ply), FormatError);               // truncated
  EXPECT_THROW(decode("ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\n"
                      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
                      Format::Ply),
               LimitError);
  EXPECT_THROW(decode("ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\n"
                      "property float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
                      Format::Ply),
               FormatError);  // declared rows exceed the data
  EXPECT_THROW(decode("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nend_header\n",
                      Format::Ply),
               FormatError);  // no z
  EXPECT_THROW(decode("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n",
                      Format::Ply),
               InvalidMeshError);  // quad
  EXPECT_THROW(decode("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                      "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n1 1 0\n3 0 1 2.5\n",
                      Format::Ply),
               FormatError);  // non-integer index
}

TEST(Conversion, SurfaceSurvivesEveryTextFormat) {
  const TriMesh m = grid(3);
  auto doc = decode(off_text(m), Format::Off);
  for (Format target : {Format::Off, Format::Obj, Format::Ply}) {
    EncodeOptions options;
    options.format = target;
    const std::string bytes = doc->encode(options).bytes;
    EXPECT_EQ(sniff_format(bytes), target);
    auto back = decode(bytes, target);
    EXPECT_EQ(back->surfaces()[0].F, m.F);
    EXPECT_LT((back->surfaces()[0].V - m.V).cwiseAbs().maxCoeff(), 1e-6);
  }
}

TEST(Conversion, ChangedVertexCountIsRefused) {
  auto doc = decode(off_text(grid(2)), Format::Off);
  doc->surfaces()[0].V.conservativeResize(3, 3);
  EXPECT_THROW(doc->encode({}).bytes, InvalidMeshError);
}

}  // namespace
}  // namespace mdn::io
