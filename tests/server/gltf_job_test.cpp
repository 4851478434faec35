// A noisy glTF scene through the whole job (decode -> denoise -> encode), read back:
// the geometry is really denoised, seam copies stay together, UVs come back bit for bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "core/io/document.h"
#include "core/metrics.h"
#include "io/gltf_fixtures.h"
#include "server/job_runner.h"

namespace mdn::service {
namespace {

using test_io::Json;

Json glb_json(const std::string& glb) {
  std::uint32_t length = 0;
  std::memcpy(&length, glb.data() + 12, 4);
  return Json::parse(glb.substr(20, length));
}

// Float data of an accessor in an uncompressed GLB (tightly packed VEC2/VEC3 floats).
std::vector<float> accessor_floats(const std::string& glb, int accessor, int components) {
  const Json j = glb_json(glb);
  const Json& acc = j["accessors"][accessor];
  const Json& view = j["bufferViews"][acc["bufferView"].get<int>()];
  std::uint32_t json_len = 0;
  std::memcpy(&json_len, glb.data() + 12, 4);
  const std::size_t start = 20 + json_len + 8 + view.value("byteOffset", 0) + acc.value("byteOffset", 0);
  const std::size_t count = acc["count"].get<std::size_t>() * static_cast<std::size_t>(components);
  std::vector<float> out(count);
  EXPECT_LE(start + count * 4, glb.size());
  std::memcpy(out.data(), glb.data() + start, count * 4);
  return out;
}

JobOutput run(const std::string& glb, bool draco) {
  JobInput in;
  in.bytes = glb;
  in.format = io::Format::Glb;
  in.params.output.draco = draco;
  return run_job(in, {});
}

TEST(GltfJob, NoisySceneIsDenoisedAndReadsBack) {
  const auto noisy = test_io::make_sphere(0.03);
  const auto clean = test_io::make_sphere(0.0);
  const TriMesh truth = io::decode(test_io::sphere_scene_glb(clean), io::Format::Glb)->surfaces()[0];
  const TriMesh before = io::decode(test_io::sphere_scene_glb(noisy), io::Format::Glb)->surfaces()[0];
  ASSERT_EQ(truth.F, before.F);  // same welding on both

  const TriMesh plain = io::decode(run(test_io::sphere_scene_glb(noisy), false).bytes, io::Format::Glb)->surfaces()[0];
  // Uncompressed, the surface comes back in the input's welded order.
  ASSERT_EQ(plain.F, truth.F);
  EXPECT_LT(msae(plain, truth), msae(before, truth) / 3);
  // Still the unit sphere: the pre-filter's shrinkage stays small on this coarse mesh.
  EXPECT_NEAR(plain.V.rowwise().norm().mean(), 1.0, 0.02);

  // Draco reorders vertices: every decoded vertex must be one of the denoised ones, within
  // the 16-bit position quantisation, and none may be missing (no seam opened).
  const JobOutput out = run(test_io::sphere_scene_glb(noisy), true);
  const TriMesh draco = io::decode(out.bytes, io::Format::Glb)->surfaces()[0];
  ASSERT_EQ(draco.V.rows(), plain.V.rows());
  ASSERT_EQ(draco.F.rows(), plain.F.rows());
  for (Eigen::Index i = 0; i < draco.V.rows(); ++i) {
    double nearest = 1e9;
    for (Eigen::Index j = 0; j < plain.V.rows(); ++j) nearest = std::min(nearest, (draco.V.row(i) - plain.V.row(j)).norm());
    EXPECT_LT(nearest, 1e-4) << "vertex " << i;
  }
}

TEST(GltfJob, UncompressedOutputKeepsUvsAndSeamCopiesTogether) {
  const auto f = test_io::make_sphere(0.03);
  const JobOutput out = run(test_io::sphere_scene_glb(f), /*draco=*/false);
  const Json j = glb_json(out.bytes);
  const Json& attributes = j["meshes"][0]["primitives"][0]["attributes"];
  const auto uv = accessor_floats(out.bytes, attributes["TEXCOORD_0"].get<int>(), 2);
  ASSERT_EQ(uv.size(), f.uv.size());
  EXPECT_EQ(std::memcmp(uv.data(), f.uv.data(), uv.size() * 4), 0) << "UVs changed";
  // Column s = segments duplicates s = 0 (different UVs): after denoising both copies must
  // hold the very same position, or the seam cracks.
  const auto pos = accessor_floats(out.bytes, attributes["POSITION"].get<int>(), 3);
  const int cols = f.segments + 1;
  int compared = 0;
  for (int r = 1; r < f.rings; ++r) {
    const int a = r * cols, b = r * cols + f.segments;
    if (3 * b + 2 >= static_cast<int>(pos.size())) continue;  // this primitive holds other rows
    for (int k = 0; k < 3; ++k) EXPECT_EQ(pos[3 * a + k], pos[3 * b + k]) << "row " << r;
    EXPECT_NE(pos[3 * a], f.noisy[3 * a]) << "row " << r << " was not denoised";
    ++compared;
  }
  EXPECT_GT(compared, 0);
}

}  // namespace
}  // namespace mdn::service
