// MSAE and E_v of Sec. 7, and the exact point-to-surface distance behind E_v.
//
// SurfaceDistance is a bounding-volume hierarchy over the triangles: nodes in one flat
// array (depth-first order, left child right after its parent), triangles copied into leaf
// order so a leaf's triangles are contiguous. The split is the median of the triangle
// centroids along the longest axis of their bounds, which keeps the depth at about
// log2(#F / leaf size) whatever the sampling, so the query stack has a fixed bound.
// Queries are branch and bound: visit the nearer child first, skip any box whose distance
// is not below the best distance found so far. The point-triangle closest point is
// Ericson's Voronoi-region method (Real-Time Collision Detection, Sec. 5.1.5), with
// degenerate triangles handled as their three edges.
#include "core/metrics.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/errors.h"
#include "core/parallel.h"

namespace mdn {

namespace {

// Squared distance from p to the segment [a, b]; a zero-length segment is the point a.
double segment_distance2(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double len2 = ab.squaredNorm();
  double t = 0;
  if (len2 > 0) t = std::clamp((p - a).dot(ab) / len2, 0.0, 1.0);
  return (p - (a + t * ab)).squaredNorm();
}

// Squared distance from p to the triangle (a, b, c). Ericson's region tests: the vertex
// regions, then the edge regions, then the face. Every division there is by a squared
// edge length or by |ab x ac|^2, so only a degenerate triangle (collinear or coincident
// corners) could divide by zero; those are measured as the union of their edges, which is
// exactly the point set they cover.
double triangle_distance2(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 ab = b - a;
  const Vec3 ac = c - a;
  const double cross2 = ab.cross(ac).squaredNorm();
  // Relative test: sin^2 of the corner angle at a below ~1e-28 is rounding noise.
  if (!(cross2 > 1e-28 * ab.squaredNorm() * ac.squaredNorm())) {
    return std::min({segment_distance2(p, a, b), segment_distance2(p, b, c), segment_distance2(p, c, a)});
  }
  const Vec3 ap = p - a;
  const double d1 = ab.dot(ap);
  const double d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return ap.squaredNorm();  // vertex region a

  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp);
  const double d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return bp.squaredNorm();  // vertex region b

  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {  // edge region ab; d1 - d3 = |ab|^2 > 0
    const double v = d1 / (d1 - d3);
    return (p - (a + v * ab)).squaredNorm();
  }

  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp);
  const double d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return cp.squaredNorm();  // vertex region c

  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {  // edge region ac; d2 - d6 = |ac|^2 > 0
    const double w = d2 / (d2 - d6);
    return (p - (a + w * ac)).squaredNorm();
  }

  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {  // edge region bc; sum = |bc|^2 > 0
    const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return (p - (b + w * (c - b))).squaredNorm();
  }

  // Face region: va + vb + vc = |ab x ac|^2 > 0 (checked above).
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom;
  const double w = vc * denom;
  return (p - (a + ab * v + ac * w)).squaredNorm();
}

constexpr int kLeafSize = 4;
constexpr int kStackSize = 96;  // > 2 x depth bound of a median-split tree over 2^31 faces

}  // namespace

struct SurfaceDistance::Impl {
  // A node's box; leaves hold triangles [first, first + count) of `tris`, inner nodes have
  // count == 0, their left child at index + 1 and their right child at `first`.
  struct Node {
    std::array<double, 3> lo, hi;
    std::int32_t first;
    std::int32_t count;
  };
  std::vector<Node> nodes;
  std::vector<Vec3> tris;  // 3 corners per triangle, in leaf order

  // Squared distance from p to the box (0 inside).
  static double box_distance2(const Node& node, const Vec3& p) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double below = node.lo[k] - p[k];
      const double above = p[k] - node.hi[k];
      const double d = std::max({below, above, 0.0});
      d2 += d * d;
    }
    return d2;
  }

  // Builds the subtree over order[begin, end) and returns its node index.
  std::int32_t build(std::vector<std::int32_t>& order, const Vertices& centroids, const std::vector<Vec3>& corners,
                     std::int32_t begin, std::int32_t end) {
    const auto index = static_cast<std::int32_t>(nodes.size());
    nodes.push_back({});
    Node node{};
    node.lo = {std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity(),
               std::numeric_limits<double>::infinity()};
    node.hi = {-node.lo[0], -node.lo[1], -node.lo[2]};
    Vec3 clo = Vec3::Constant(std::numeric_limits<double>::infinity());
    Vec3 chi = -clo;
    for (std::int32_t i = begin; i < end; ++i) {
      const std::int32_t f = order[i];
      for (int j = 0; j < 3; ++j) {
        const Vec3& q = corners[3 * static_cast<std::size_t>(f) + j];
        for (int k = 0; k < 3; ++k) {
          node.lo[k] = std::min(node.lo[k], q[k]);
          node.hi[k] = std::max(node.hi[k], q[k]);
        }
      }
      clo = clo.cwiseMin(centroids.row(f).transpose());
      chi = chi.cwiseMax(centroids.row(f).transpose());
    }
    if (end - begin <= kLeafSize) {
      node.first = begin;
      node.count = end - begin;
      nodes[index] = node;
      return index;
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const std::int32_t mid = begin + (end - begin) / 2;
    std::nth_element(order.begin() + begin, order.begin() + mid, order.begin() + end,
                     [&](std::int32_t x, std::int32_t y) {
                       // Ties broken by index so the tree does not depend on the library's nth_element.
                       const double cx = centroids(x, axis), cy = centroids(y, axis);
                       return cx < cy || (cx == cy && x < y);
                     });
    build(order, centroids, corners, begin, mid);
    node.first = build(order, centroids, corners, mid, end);
    node.count = 0;
    nodes[index] = node;
    return index;
  }

  double distance2(const Vec3& p) const {
    double best = std::numeric_limits<double>::infinity();
    std::array<std::int32_t, kStackSize> stack;
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const std::int32_t ni = stack[--top];
      const Node& node = nodes[ni];
      if (box_distance2(node, p) >= best) continue;
      if (node.count > 0) {
        for (std::int32_t t = node.first; t < node.first + node.count; ++t) {
          const std::size_t k = 3 * static_cast<std::size_t>(t);
          best = std::min(best, triangle_distance2(p, tris[k], tris[k + 1], tris[k + 2]));
        }
        continue;
      }
      const std::int32_t left = ni + 1;
      const std::int32_t right = node.first;
      const double dl = box_distance2(nodes[left], p);
      const double dr = box_distance2(nodes[right], p);
      // Push the farther child first so the nearer one is searched first and tightens `best`.
      if (dl <= dr) {
        if (dr < best) stack[top++] = right;
        if (dl < best) stack[top++] = left;
      } else {
        if (dl < best) stack[top++] = left;
        if (dr < best) stack[top++] = right;
      }
    }
    return best;
  }
};

SurfaceDistance::SurfaceDistance(const TriMesh& surface) : impl_(std::make_unique<Impl>()) {
  validate_mesh(surface);
  if (surface.num_faces() > std::numeric_limits<std::int32_t>::max() / 3)
    throw InvalidMeshError("SurfaceDistance: too many faces for 32-bit node indices");
  const auto nf = static_cast<std::int32_t>(surface.num_faces());
  std::vector<Vec3> corners(3 * static_cast<std::size_t>(nf));
  Vertices centroids(nf, 3);
  for (std::int32_t f = 0; f < nf; ++f) {
    for (int j = 0; j < 3; ++j) corners[3 * static_cast<std::size_t>(f) + j] = surface.V.row(surface.F(f, j)).transpose();
    centroids.row(f) = (corners[3 * f] + corners[3 * f + 1] + corners[3 * f + 2]).transpose() / 3.0;
  }
  std::vector<std::int32_t> order(nf);
  std::iota(order.begin(), order.end(), 0);
  impl_->nodes.reserve(2 * static_cast<std::size_t>(nf) / kLeafSize + 2);
  impl_->build(order, centroids, corners, 0, nf);
  impl_->tris.resize(corners.size());
  for (std::int32_t i = 0; i < nf; ++i)
    for (int j = 0; j < 3; ++j) impl_->tris[3 * static_cast<std::size_t>(i) + j] = corners[3 * static_cast<std::size_t>(order[i]) + j];
}

SurfaceDistance::~SurfaceDistance() = default;
SurfaceDistance::SurfaceDistance(SurfaceDistance&&) noexcept = default;

double SurfaceDistance::distance(const Vec3& p) const {
  if (!p.allFinite()) throw InvalidMeshError("SurfaceDistance: query point has a non-finite coordinate");
  return std::sqrt(impl_->distance2(p));
}

double msae(const TriMesh& result, const TriMesh& truth) {
  validate_mesh(result);
  validate_mesh(truth);
  if (result.num_faces() != truth.num_faces() || result.F != truth.F)
    throw InvalidMeshError("msae: the result and the ground truth must have the same faces");
  return msae_of_normals(face_normals(result.V, result.F), face_normals(truth.V, truth.F));
}

double msae_of_normals(const Vertices& nr, const Vertices& nt) {
  if (nr.rows() != nt.rows()) throw InvalidMeshError("msae: the result and the ground truth must have the same faces");
  double sum = 0;
  std::int64_t counted = 0;
  for (std::int64_t f = 0; f < nr.rows(); ++f) {
    const Vec3 a = nr.row(f).transpose();
    const Vec3 b = nt.row(f).transpose();
    if (a.squaredNorm() == 0 || b.squaredNorm() == 0) continue;  // degenerate face: no normal
    // atan2 keeps full precision for small angles, where acos(dot) loses half the digits.
    const double angle = std::atan2(a.cross(b).norm(), a.dot(b));
    sum += angle * angle;
    ++counted;
  }
  if (counted == 0) throw InvalidMeshError("msae: every face is degenerate in the result or the ground truth");
  return sum / static_cast<double>(counted);
}

double vertex_error(const TriMesh& result, const TriMesh& truth, Executor* executor) {
  validate_mesh(result);
  validate_mesh(truth);
  const UnitBox box = UnitBox::of(truth.V);
  const TriMesh truth_box{box.apply(truth.V), truth.F};
  const Vertices P = box.apply(result.V);
  const Eigen::VectorXd areas = face_areas(P, result.F);

  // Vertex weights sum_{j in F(i)} A_j, accumulated serially (deterministic).
  Eigen::VectorXd weight = Eigen::VectorXd::Zero(P.rows());
  double total_area = 0;
  for (std::int64_t f = 0; f < result.num_faces(); ++f) {
    for (int j = 0; j < 3; ++j) weight[result.F(f, j)] += areas[f];
    total_area += areas[f];
  }
  if (!(total_area > 0)) throw InvalidMeshError("vertex_error: the result has zero total area");

  const SurfaceDistance surface(truth_box);
  Eigen::VectorXd d2 = Eigen::VectorXd::Zero(P.rows());
  const auto body = [&](std::int64_t begin, std::int64_t end) {
    for (std::int64_t i = begin; i < end; ++i) {
      if (weight[i] == 0) continue;  // unreferenced vertex: weight 0, contributes nothing
      const double d = surface.distance(P.row(i).transpose());
      d2[i] = d * d;
    }
  };
  if (executor != nullptr) {
    executor->parallel_for(P.rows(), body);
  } else {
    body(0, P.rows());
  }
  double sum = 0;  // serial sum: identical whatever the thread count
  for (std::int64_t i = 0; i < P.rows(); ++i) sum += weight[i] * d2[i];
  return std::sqrt(sum / (3.0 * total_area));
}

}  // namespace mdn
