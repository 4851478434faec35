// What the per-face prior (issue 48, item 2; decision 87) reads around each face of a noisy
// surface: scale-free, rotation-free readings of the face's noisy normal and of filtered normals
// around it, all expressed in a frame of the face's own (z: the twice ring-mean-filtered normal;
// x: the noisy normal's tilt away from it). core/auto/face_prior.h evaluates the regressor on
// them; tools/train's `train_corpus faces` writes them, with the clean normal in the same frame,
// as the regressor's rows. The same code runs in both, so training and run time read alike.
#pragma once

#include <array>
#include <cstdint>
#include <vector>

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;

// The number of features per face, and their names (decision 87).
constexpr int kFaceFeatures = 41;
const std::vector<const char*>& face_feature_names();

// Area-weighted mean of the normals N of the faces sharing a vertex with f, f included, unit
// (zero when they cancel): the ring-mean filter that the descriptors and the features share.
Vec3 ring_mean(const Topology& topo, const Vertices& N, const Eigen::VectorXd& A, std::int64_t f);

// Per-face readings of a surface, #F rows each.
struct FaceFeatures {
  // #F by kFaceFeatures, row-major: the regressor's inputs.
  Eigen::Matrix<double, Eigen::Dynamic, kFaceFeatures, Eigen::RowMajor> X;
  // #F by 9, row-major: each face's frame, rows x, y, z (unit, right-handed) in world axes.
  Eigen::Matrix<double, Eigen::Dynamic, 9, Eigen::RowMajor> frame;
  Vertices noisy;     // #F by 3 face normals of the input (zero rows for degenerate faces)
  Vertices smoothed;  // #F by 3 the frame's z: the ring-mean filter applied twice
  // Per face: true where the face reads plainly flat (every face of its ring within
  // kFlatDegrees of its smoothed normal): the prior keeps the smoothed normal there and does not
  // run the network (decision 87).
  std::vector<std::uint8_t> flat;
};
constexpr double kFlatDegrees = 1.0;

// Reads every face of (P, F). Deterministic: each face's readings depend on the mesh alone,
// the executor only splits the faces into blocks.
FaceFeatures face_features(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor);

// The whole-surface passes of face_features (ring means, per-vertex readings, edge neighbours),
// once; then any face's readings on demand, so that the prior reads them block by block without
// a #F by kFaceFeatures table. Borrows P, F and topo for its lifetime. read() and flat() are
// const and may run on many threads at once.
class FaceReader {
 public:
  FaceReader(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor);
  // Face f's kFaceFeatures readings into row[0 .. kFaceFeatures) and its frame (rows x, y, z,
  // world axes) into frame: face_features' row f, bit for bit.
  void read(std::int64_t f, double* row, Eigen::Matrix3d& frame) const;
  bool flat(std::int64_t f) const;  // FaceFeatures::flat of f
  const Vertices& noisy() const { return N0_; }
  const Vertices& smoothed() const { return M2_; }

 private:
  Vec3 axis(std::int64_t f) const;  // the frame's z
  const Vertices& P_;
  const Triangles& F_;
  const Topology& topo_;
  Vertices N0_, M1_, M2_, M4_, C_;
  Eigen::VectorXd A_;
  std::vector<double> vdist_, spike_, inconsistency_;
  std::vector<std::array<std::int32_t, 3>> across_;
};

// v (frame axes) in world axes, for a frame whose rows are x, y, z: from_frame's arithmetic.
Vec3 frame_to_world(const Eigen::Matrix3d& frame, const Vec3& v);

// v (world axes) in face f's frame, and back.
Vec3 to_frame(const FaceFeatures& ff, std::int64_t f, const Vec3& v);
Vec3 from_frame(const FaceFeatures& ff, std::int64_t f, const Vec3& v);

}  // namespace mdn

namespace mdn {

// The class of each face of a clean surface (decision 88), by the largest angle between its
// normal and those of its ring: flat (under 2 degrees), curved (under 20), else a crease, or a
// corner where the ring's normal tensor has a third direction (its smallest eigenvalue over the
// trace above 0.01). Training balances its rows by it; the benchmarks report errors per class.
enum class FaceClass : std::uint8_t { Flat = 0, Curved = 1, Crease = 2, Corner = 3 };
constexpr int kFaceClasses = 4;
const char* face_class_name(FaceClass c);
std::vector<FaceClass> face_classes(const Vertices& V, const Triangles& F, const Topology& topo, Executor& executor);

}  // namespace mdn
