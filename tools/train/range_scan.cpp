#include "range_scan.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>
#include <optional>
#include <stdexcept>

namespace mdn::train {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kHalfPi = std::numbers::pi / 2;

// --- Seeded draws, one per (pixel, stream): independent of the order pixels are visited. ---

std::uint64_t mix(std::uint64_t x) {  // splitmix64's finaliser
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}
double uniform(std::uint64_t seed, std::uint64_t index, std::uint64_t stream) {
  const std::uint64_t h = mix(mix(seed ^ mix(index)) ^ (stream * 0x632be59bd9b4e019ull));
  return (static_cast<double>(h >> 11) + 0.5) * 0x1.0p-53;  // in (0, 1)
}
// Box-Muller from two draws of the same stream pair (std::normal_distribution's algorithm is
// the library's own; this one is the same on every platform).
double gauss(std::uint64_t seed, std::uint64_t index, std::uint64_t stream) {
  const double u = uniform(seed, index, 2 * stream), v = uniform(seed, index, 2 * stream + 1);
  return std::sqrt(-2 * std::log(u)) * std::cos(2 * std::numbers::pi * v);
}

// --- A bounding volume hierarchy over the triangles, exact ray-triangle intersection. ---

class Bvh {
 public:
  explicit Bvh(const TriMesh& mesh) : mesh_(mesh) {
    const auto n = static_cast<std::int32_t>(mesh.F.rows());
    order_.resize(static_cast<std::size_t>(n));
    std::iota(order_.begin(), order_.end(), 0);
    centroid_.resize(static_cast<std::size_t>(n));
    for (std::int32_t f = 0; f < n; ++f)
      centroid_[static_cast<std::size_t>(f)] = (corner(f, 0) + corner(f, 1) + corner(f, 2)) / 3;
    if (n > 0) build_root(0, n);
  }

  struct Hit {
    double t;
    std::int32_t face;
  };
  // The nearest hit of origin + t dir with t in (t_min, t_max).
  std::optional<Hit> first_hit(const Vec3& origin, const Vec3& dir, double t_min, double t_max) const {
    if (nodes_.empty()) return std::nullopt;
    const Vec3 inv(1 / dir.x(), 1 / dir.y(), 1 / dir.z());
    std::optional<Hit> best;
    std::array<std::int32_t, 128> stack{};
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
      if (!slab(node, origin, inv, t_min, t_max)) continue;
      if (node.count > 0) {
        for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
          const std::int32_t f = order_[static_cast<std::size_t>(k)];
          const double t = intersect(f, origin, dir);
          if (t > t_min && t < t_max) {
            t_max = t;
            best = Hit{t, f};
          }
        }
      } else {
        stack[top++] = node.left;
        stack[top++] = node.left + 1;
      }
    }
    return best;
  }

  // The point of the mesh nearest to p (the surface's, not only the vertices').
  Vec3 closest_point(const Vec3& p) const {
    Vec3 best = p;
    double best_d2 = std::numeric_limits<double>::infinity();
    std::array<std::int32_t, 128> stack{};
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& node = nodes_[static_cast<std::size_t>(stack[--top])];
      if (box_distance2(node, p) >= best_d2) continue;
      if (node.count > 0) {
        for (std::int32_t k = node.first; k < node.first + node.count; ++k) {
          const std::int32_t f = order_[static_cast<std::size_t>(k)];
          const Vec3 q = closest_on_triangle(p, corner(f, 0), corner(f, 1), corner(f, 2));
          const double d2 = (q - p).squaredNorm();
          if (d2 < best_d2) best_d2 = d2, best = q;
        }
      } else {  // the nearer child on top of the stack
        const bool left_first = box_distance2(nodes_[static_cast<std::size_t>(node.left)], p) <=
                                box_distance2(nodes_[static_cast<std::size_t>(node.left + 1)], p);
        stack[top++] = left_first ? node.left + 1 : node.left;
        stack[top++] = left_first ? node.left : node.left + 1;
      }
    }
    return best;
  }

  Vec3 corner(std::int32_t f, int k) const { return mesh_.V.row(mesh_.F(f, k)).transpose(); }
  Vec3 normal(std::int32_t f) const {
    return (corner(f, 1) - corner(f, 0)).cross(corner(f, 2) - corner(f, 0)).normalized();
  }

 private:
  struct Node {
    Vec3 lo, hi;
    std::int32_t left = 0;              // children at left, left + 1 (inner nodes)
    std::int32_t first = 0, count = 0;  // triangles order_[first, first + count) (leaves)
  };

  // Median split along the longest axis of the centroids' box; leaves of at most 4 triangles.
  // The two children of a node sit side by side (left, left + 1).
  void build_root(std::int32_t first, std::int32_t last) {
    nodes_.resize(1);
    build(0, first, last);
  }
  void build(std::size_t index, std::int32_t first, std::int32_t last) {
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    Vec3 clo = lo, chi = hi;
    for (std::int32_t k = first; k < last; ++k) {
      const std::int32_t f = order_[static_cast<std::size_t>(k)];
      for (int c = 0; c < 3; ++c) {
        lo = lo.cwiseMin(corner(f, c));
        hi = hi.cwiseMax(corner(f, c));
      }
      clo = clo.cwiseMin(centroid_[static_cast<std::size_t>(f)]);
      chi = chi.cwiseMax(centroid_[static_cast<std::size_t>(f)]);
    }
    nodes_[index].lo = lo;
    nodes_[index].hi = hi;
    if (last - first <= 4) {
      nodes_[index].first = first;
      nodes_[index].count = last - first;
      return;
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const std::int32_t mid = first + (last - first) / 2;
    std::nth_element(order_.begin() + first, order_.begin() + mid, order_.begin() + last,
                     [&](std::int32_t a, std::int32_t b) {
                       const double ca = centroid_[static_cast<std::size_t>(a)][axis],
                                    cb = centroid_[static_cast<std::size_t>(b)][axis];
                       return ca < cb || (ca == cb && a < b);  // a strict total order: the same tree everywhere
                     });
    const std::size_t left = nodes_.size();
    nodes_.resize(left + 2);
    nodes_[index].left = static_cast<std::int32_t>(left);
    build(left, first, mid);
    build(left + 1, mid, last);
  }

  static double box_distance2(const Node& node, const Vec3& p) {
    return (node.lo - p).cwiseMax(p - node.hi).cwiseMax(0.0).squaredNorm();
  }

  // Ericson, Real-Time Collision Detection, 5.1.5: the Voronoi regions of the triangle's
  // vertices, edges and face in turn.
  static Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return a;
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return b;
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return c;
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && d4 - d3 >= 0 && d5 - d6 >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
    const double denom = 1 / (va + vb + vc);
    return a + vb * denom * ab + vc * denom * ac;
  }

  static bool slab(const Node& node, const Vec3& o, const Vec3& inv, double t_min, double t_max) {
    for (int a = 0; a < 3; ++a) {
      double t0 = (node.lo[a] - o[a]) * inv[a], t1 = (node.hi[a] - o[a]) * inv[a];
      if (t0 > t1) std::swap(t0, t1);
      if (std::isnan(t0) || std::isnan(t1)) continue;  // ray parallel to and on the slab's plane
      t_min = std::max(t_min, t0);
      t_max = std::min(t_max, t1);
      if (t_min > t_max) return false;
    }
    return true;
  }

  // Moller-Trumbore: the ray parameter of the hit, or NaN.
  double intersect(std::int32_t f, const Vec3& o, const Vec3& d) const {
    const Vec3 a = corner(f, 0), e1 = corner(f, 1) - a, e2 = corner(f, 2) - a;
    const Vec3 p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-300) return kNaN;
    const double inv = 1 / det;
    const Vec3 s = o - a;
    const double u = s.dot(p) * inv;
    if (u < 0 || u > 1) return kNaN;
    const Vec3 q = s.cross(e1);
    const double v = d.dot(q) * inv;
    if (v < 0 || u + v > 1) return kNaN;
    return e2.dot(q) * inv;
  }

  const TriMesh& mesh_;
  std::vector<std::int32_t> order_;
  std::vector<Vec3> centroid_;
  std::vector<Node> nodes_;
};

// What a ray from the camera meets first: the object, the wall behind it, or nothing.
struct Sample {
  double z = kNaN;  // depth (the ray parameter; rays have d.z = 1)
  double cos_incidence = 0;
  Vec3 normal = Vec3::Zero();  // of the object's face hit
  bool object = false;
};

class Scene {
 public:
  Scene(const TriMesh& mesh, double wall) : bvh_(mesh), wall_(wall) {}
  Sample trace(const Vec3& dir) const {
    Sample s;
    if (const auto hit = bvh_.first_hit(Vec3::Zero(), dir, 0, std::numeric_limits<double>::infinity())) {
      s.z = hit->t;
      s.cos_incidence = std::abs(bvh_.normal(hit->face).dot(dir.normalized()));
      s.normal = bvh_.normal(hit->face);
      s.object = true;
    } else if (wall_ > 0) {
      s.z = wall_;
      s.cos_incidence = 1 / dir.norm();
    }
    return s;
  }
  // Whether the segment from p to q crosses the object (p's own face excluded by a margin).
  bool blocked(const Vec3& p, const Vec3& q) const { return bvh_.first_hit(p, q - p, 1e-6, 1 - 1e-6).has_value(); }
  // The first object hit within `reach` from p along unit `dir`, as a distance.
  std::optional<double> reach(const Vec3& p, const Vec3& dir, double reach) const {
    const auto hit = bvh_.first_hit(p, dir, 1e-6, reach);
    return hit ? std::optional<double>(hit->t) : std::nullopt;
  }

 private:
  Bvh bvh_;
  double wall_;
};

// The image's ray through sampled pixel coordinates (col, row), possibly fractional.
Vec3 ray(const RangeImage& im, double col, double row) {
  return {(col - im.cx) / im.focal, (row - im.cy) / im.focal, 1};
}

// Time-of-flight multipath (decision 58): light that reaches the surface point after a
// bounce off the object's own nearby surface travels further, so the measured phase is late
// and the depth too long in concave corners (Fuchs 2010, "Multipath interference compensation
// in time-of-flight camera images"; Freedman et al. 2014, "SRA: fast removal of general
// multipath for ToF sensors"). Stand-in: eight rays into the hemisphere above the point at
// 45 degrees from its normal, each meeting the surface within 30 cm adding (1 - distance /
// 30 cm) / 8 of the largest bias, 15 mm (a point at the bottom of a deep corner). It varies
// smoothly over the surface, like the real bias.
constexpr double kMultipathReach = 0.30, kMultipathMax = 0.015;
double multipath_bias(const Scene& scene, const Vec3& p, Vec3 n, const Vec3& view) {
  if (n.dot(view) > 0) n = -n;  // the side the camera sees
  const Vec3 a = std::abs(n.x()) < 0.6 ? Vec3::UnitX() : Vec3::UnitY();
  const Vec3 t1 = n.cross(a).normalized(), t2 = n.cross(t1);
  const Vec3 origin = p + 1e-5 * n;
  double sum = 0;
  for (int k = 0; k < 8; ++k) {
    const double phi = k * std::numbers::pi / 4;
    const Vec3 dir = (std::sqrt(0.5) * n + std::sqrt(0.5) * (std::cos(phi) * t1 + std::sin(phi) * t2)).normalized();
    if (const auto t = scene.reach(origin, dir, kMultipathReach)) sum += 1 - *t / kMultipathReach;
  }
  return kMultipathMax * sum / 8;
}

// The noise that, added before the quantisation, gives the published standard deviation of
// the reported depth: the published figures were measured on the sensors' quantised output,
// and rounding adds step^2 / 12 to the variance when the noise spans a step or more.
double sigma_before_quantisation(const RangeSensor& sensor, double z, double theta) {
  const double s = axial_sigma(sensor, z, theta), q = depth_step(sensor, z);
  return std::sqrt(std::max(0.25 * s * s, s * s - q * q / 12));
}

// Structured light's disparity error (decision 84): the sensor finds each pixel's disparity by
// matching a 9x9 window of the speckle pattern, so the windows of neighbouring pixels share most
// of their pixels and their errors most of their cause. Modelled as white noise on the native
// grid summed over the 9x9 window around each pixel and divided by 9: unit variance, a
// correlation of (9 - d) / 9 per axis at d native pixels, none beyond 8. Each native pixel's draw
// is a hash of (seed, native pixel, stream) and each sum runs in a fixed order, so a value does
// not depend on which part of the image is computed: the same bits on every platform.
class WindowNoise {
 public:
  static constexpr int kHalf = 4;  // the window is 2 kHalf + 1 = 9 native pixels wide

  // The field at the sampled pixels [col0, col1] x [row0, row1] of `sensor`'s image.
  WindowNoise(const RangeSensor& sensor, std::uint64_t seed, std::uint64_t stream, int col0, int row0, int col1, int row1)
      : col0_(col0), row0_(row0), cols_(col1 - col0 + 1) {
    const int s = sensor.stride;
    const int x0 = col0 * s - kHalf, x1 = col1 * s + kHalf, y0 = row0 * s - kHalf, y1 = row1 * s + kHalf;
    const auto stride_x = static_cast<std::uint64_t>(sensor.width + 2 * kHalf);
    // Row sums: across[(y - y0) * cols_ + (c - col0)] = the 9 draws of native row y around column c s.
    std::vector<double> white(static_cast<std::size_t>(x1 - x0 + 1));
    std::vector<double> across(static_cast<std::size_t>(y1 - y0 + 1) * static_cast<std::size_t>(cols_));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x)  // native pixel (x, y); x, y >= -kHalf
        white[static_cast<std::size_t>(x - x0)] =
            gauss(seed, static_cast<std::uint64_t>(y + kHalf) * stride_x + static_cast<std::uint64_t>(x + kHalf), stream);
      for (int c = col0; c <= col1; ++c) {
        double sum = 0;
        for (int k = 0; k <= 2 * kHalf; ++k) sum += white[static_cast<std::size_t>(c * s - kHalf + k - x0)];
        across[static_cast<std::size_t>(y - y0) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(c - col0)] = sum;
      }
    }
    field_.resize(static_cast<std::size_t>(row1 - row0 + 1) * static_cast<std::size_t>(cols_));
    for (int r = row0; r <= row1; ++r)
      for (int c = col0; c <= col1; ++c) {
        double sum = 0;
        for (int k = 0; k <= 2 * kHalf; ++k)
          sum += across[static_cast<std::size_t>(r * s - kHalf + k - y0) * static_cast<std::size_t>(cols_) +
                        static_cast<std::size_t>(c - col0)];
        field_[index(c, r)] = sum / (2 * kHalf + 1);
      }
  }
  double at(int col, int row) const { return field_[index(col, row)]; }

 private:
  std::size_t index(int col, int row) const {
    return static_cast<std::size_t>(row - row0_) * static_cast<std::size_t>(cols_) + static_cast<std::size_t>(col - col0_);
  }
  int col0_, row0_, cols_;
  std::vector<double> field_;
};

// Components through shared vertices; the small ones (islands of flying pixels, specks at
// silhouettes, fused crumbs) dropped as scanner software does (decision 59).
std::vector<std::array<int, 3>> drop_small_components(const std::vector<std::array<int, 3>>& tris,
                                                      std::size_t vertices) {
  std::vector<int> parent(vertices);
  std::iota(parent.begin(), parent.end(), 0);
  const auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x)
      x = parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  };
  for (const auto& t : tris)
    for (int k = 1; k < 3; ++k) {
      const int x = find(t[0]), y = find(t[static_cast<std::size_t>(k)]);
      if (x != y) parent[static_cast<std::size_t>(std::max(x, y))] = std::min(x, y);
    }
  std::vector<int> faces_of(vertices, 0);
  for (const auto& t : tris) ++faces_of[static_cast<std::size_t>(find(t[0]))];
  const int keep = std::max(20, static_cast<int>(0.02 * static_cast<double>(tris.size())));
  std::vector<std::array<int, 3>> kept;
  for (const auto& t : tris)
    if (faces_of[static_cast<std::size_t>(find(t[0]))] >= keep) kept.push_back(t);
  return kept;
}

}  // namespace

RangeSensor kinect_v1() { return {}; }

RangeSensor kinect_v2() {
  RangeSensor s;
  s.kind = SensorKind::TimeOfFlight;
  s.width = 512;
  s.height = 424;
  s.focal_px = 365;
  s.stride = 1;
  s.baseline_m = 0;
  return s;
}

double axial_sigma(const RangeSensor& sensor, double z, double theta) {
  const double grazing = theta * theta / ((kHalfPi - theta) * (kHalfPi - theta));
  if (sensor.kind == SensorKind::StructuredLight)  // Nguyen, Izadi, Lovell 2012: the grazing term beyond 60 degrees
    return 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4) + (theta > kHalfPi / 1.5 ? 0.0001 / std::sqrt(z) * grazing : 0.0);
  // Fankhauser, Bloesch, Rodriguez, Kaestner, Hutter, Siegwart 2015, "Kinect v2 for mobile
  // robot navigation: evaluation and modeling", the axial model fitted to their measurements.
  return 0.0015 - 0.0005 * z + 0.0003 * z * z + 0.0001 * std::pow(z, 1.5) * grazing;
}

double depth_step(const RangeSensor& sensor, double z) {
  if (sensor.kind == SensorKind::StructuredLight) return z * z / (8 * sensor.baseline_m * sensor.focal_px);
  return 0.001;
}

double quantise_depth(const RangeSensor& sensor, double z) {
  if (sensor.kind == SensorKind::StructuredLight) {
    // The disparity of depth z is b f / z pixels (Khoshelham and Elberink 2012); the sensor
    // reports it in steps of 1/8 pixel.
    const double bf = sensor.baseline_m * sensor.focal_px;
    const double eighths = std::max(1.0, std::round(8 * bf / z));
    return bf / (eighths / 8);
  }
  return std::round(z * 1000) / 1000;  // Kinect v2 reports whole millimetres
}

Vec3 RangeImage::point(int col, int row, double z) const { return z * ray(*this, col, row); }

RangeImage capture(const TriMesh& scene_mesh, const RangeSensor& sensor, const CaptureOptions& options) {
  if (sensor.stride < 1 || sensor.stride > 4) throw std::invalid_argument("capture: stride must be 1..4");
  RangeImage im;
  im.cols = sensor.width / sensor.stride;
  im.rows = sensor.height / sensor.stride;
  im.focal = sensor.focal_px / sensor.stride;
  im.cx = 0.5 * (im.cols - 1);
  im.cy = 0.5 * (im.rows - 1);
  const std::size_t n = static_cast<std::size_t>(im.cols) * static_cast<std::size_t>(im.rows);
  im.clean_depth.assign(n, kNaN);
  im.depth.assign(n, kNaN);
  im.incidence.assign(n, kNaN);
  const Scene scene(scene_mesh, options.wall_depth_m);
  const double max_theta = sensor.max_incidence_deg * std::numbers::pi / 180;

  // The noise-free image: every pixel's ray on the object (or the wall, for mixing only).
  std::vector<Sample> centre(n);
  for (int r = 0; r < im.rows; ++r)
    for (int c = 0; c < im.cols; ++c) {
      const std::size_t i =
          static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c);
      centre[i] = scene.trace(ray(im, c, r));
      if (!centre[i].object) continue;
      im.clean_depth[i] = centre[i].z;
      im.incidence[i] = std::acos(std::clamp(centre[i].cos_incidence, 0.0, 1.0));
    }

  // Structured light's three correlated draws (decision 84), over the object's pixels: the
  // window's position across and down the image (lateral noise) and the disparity itself.
  std::optional<std::array<WindowNoise, 3>> window;
  if (sensor.kind == SensorKind::StructuredLight) {
    int col0 = im.cols, row0 = im.rows, col1 = -1, row1 = -1;
    for (int r = 0; r < im.rows; ++r)
      for (int c = 0; c < im.cols; ++c)
        if (centre[static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c)].object) {
          col0 = std::min(col0, c), col1 = std::max(col1, c);
          row0 = std::min(row0, r), row1 = std::max(row1, r);
        }
    if (col1 >= 0)
      window.emplace(std::array<WindowNoise, 3>{WindowNoise(sensor, options.seed, 3, col0, row0, col1, row1),
                                                WindowNoise(sensor, options.seed, 4, col0, row0, col1, row1),
                                                WindowNoise(sensor, options.seed, 5, col0, row0, col1, row1)});
  }

  for (int r = 0; r < im.rows; ++r)
    for (int c = 0; c < im.cols; ++c) {
      const std::size_t i =
          static_cast<std::size_t>(r) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(c);
      if (!centre[i].object) continue;  // background: cut away
      const double theta = im.incidence[i];
      // Beyond about 75 degrees too little of the pattern or the modulated light comes back
      // to be measured (issue 48's figure; both models' noise diverges towards 90 degrees).
      if (theta > max_theta) continue;
      const Vec3 dir = ray(im, c, r);
      const Vec3 p = centre[i].z * dir;
      double z = centre[i].z;
      if (sensor.kind == SensorKind::StructuredLight) {
        // The projector sits one baseline to the camera's side: a point it cannot light
        // returns no pattern (the shadows beside every near edge of a Kinect v1 image).
        if (scene.blocked(p, Vec3(sensor.baseline_m, 0, 0))) continue;
        // Lateral noise: the correlation window's position is uncertain by about a pixel,
        // sigma_L = 0.8 + 0.035 theta / (pi/2 - theta) native pixels (Nguyen et al. 2012), so the depth is that of a
        // nearby point of the surface, reported on this pixel's ray. On a slope or at an edge that reads as depth noise
        // and ragged edges. Neighbouring windows overlap, so the shift is correlated (decision 84).
        const double sigma_l = (0.8 + 0.035 * theta / (kHalfPi - theta)) / sensor.stride;
        const Sample moved = scene.trace(ray(im, c + sigma_l * (*window)[0].at(c, r), r + sigma_l * (*window)[1].at(c, r)));
        if (std::isnan(moved.z)) continue;  // the window slid off the object into nothing
        z = moved.z;
      } else {
        // Mixed ("flying") pixels: where the pixel's footprint straddles a depth edge, the
        // returns of both surfaces add up and the phase, so the depth, lands between them
        // (Lindner and Kolb 2010; Sarbolandi, Lefloch, Kolb 2015). Four rays across the
        // footprint, each return weighted by its brightness, Lambertian over distance squared.
        bool edge = false;
        for (const auto& [dc, dr] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const int cc = c + dc, rr = r + dr;
          if (cc < 0 || rr < 0 || cc >= im.cols || rr >= im.rows) continue;
          const double zn =
              centre[static_cast<std::size_t>(rr) * static_cast<std::size_t>(im.cols) + static_cast<std::size_t>(cc)].z;
          if (!std::isnan(zn) && std::abs(zn - z) > jump_threshold(sensor, 0.5 * (z + zn))) edge = true;
        }
        if (edge) {
          double weighted = 0, weight = 0;
          for (const auto& [dc, dr] : {std::pair{-0.25, -0.25}, {0.25, -0.25}, {-0.25, 0.25}, {0.25, 0.25}}) {
            const Sample s = scene.trace(ray(im, c + dc, r + dr));
            if (std::isnan(s.z)) continue;
            const double a = s.cos_incidence / (s.z * s.z);
            weighted += a * s.z;
            weight += a;
          }
          if (weight > 0) z = weighted / weight;
        }
        z += multipath_bias(scene, p, centre[i].normal, dir);
      }
      // Time of flight measures each pixel on its own: independent draws. Structured light's
      // disparity error is the window's (decision 84): smooth bumps about 9 native pixels wide,
      // which the quantisation below turns into terraces on a plane.
      const double draw =
          sensor.kind == SensorKind::StructuredLight ? (*window)[2].at(c, r) : gauss(options.seed, i, 2);
      const double noisy = z + sigma_before_quantisation(sensor, z, theta) * draw;
      im.depth[i] = quantise_depth(sensor, noisy);
    }
  return im;
}

double jump_threshold(const RangeSensor& sensor, double z) {
  const double footprint = z * sensor.stride / sensor.focal_px;
  return 4 * footprint + 4 * axial_sigma(sensor, z, 0) + depth_step(sensor, z);
}

RangeScan mesh_range_image(const RangeImage& im, const RangeSensor& sensor) {
  const auto at = [&](int c, int r) { return r * im.cols + c; };
  const auto valid = [&](int i) {
    return !std::isnan(im.depth[static_cast<std::size_t>(i)]) &&
           !std::isnan(im.clean_depth[static_cast<std::size_t>(i)]);
  };
  const auto joined = [&](int a, int b) {
    for (const std::vector<double>* d : {&im.depth, &im.clean_depth}) {
      const double za = (*d)[static_cast<std::size_t>(a)], zb = (*d)[static_cast<std::size_t>(b)];
      if (std::abs(za - zb) > jump_threshold(sensor, 0.5 * (za + zb))) return false;
    }
    return true;
  };
  std::vector<std::array<int, 3>> tris;  // pixel indices, counter-clockwise seen from the camera
  const auto add = [&](int a, int b, int c) {
    if (valid(a) && valid(b) && valid(c) && joined(a, b) && joined(b, c) && joined(c, a)) tris.push_back({a, b, c});
  };
  for (int r = 0; r + 1 < im.rows; ++r)
    for (int c = 0; c + 1 < im.cols; ++c) {
      const int a = at(c, r), b = at(c + 1, r), cc = at(c, r + 1), d = at(c + 1, r + 1);
      // x right, y down: (a, cc, b) faces the camera. The diagonal of smaller depth
      // difference, where both are there (on the reported depths, as a scanner sees them).
      const auto gap = [&](int p, int q) {
        return valid(p) && valid(q)
                   ? std::abs(im.depth[static_cast<std::size_t>(p)] - im.depth[static_cast<std::size_t>(q)])
                   : std::numeric_limits<double>::infinity();
      };
      if (gap(a, d) <= gap(b, cc) && std::isfinite(gap(a, d))) {
        add(a, cc, d);
        add(a, d, b);
      } else {
        add(a, cc, b);
        add(b, cc, d);
      }
    }
  const std::vector<std::array<int, 3>> kept = drop_small_components(tris, im.depth.size());
  std::vector<std::int32_t> vertex(im.depth.size(), -1);
  std::vector<char> used(im.depth.size(), 0);
  for (const auto& t : kept)
    for (const int p : t) used[static_cast<std::size_t>(p)] = 1;
  RangeScan out;
  std::int32_t count = 0;
  for (std::size_t p = 0; p < used.size(); ++p)
    if (used[p]) {
      vertex[p] = count++;
      out.pixel.push_back(static_cast<std::int32_t>(p));
    }
  out.clean.V.resize(count, 3);
  out.noisy.resize(count, 3);
  for (std::int32_t v = 0; v < count; ++v) {
    const int p = out.pixel[static_cast<std::size_t>(v)];
    const int c = p % im.cols, r = p / im.cols;
    out.clean.V.row(v) = im.point(c, r, im.clean_depth[static_cast<std::size_t>(p)]).transpose();
    out.noisy.row(v) = im.point(c, r, im.depth[static_cast<std::size_t>(p)]).transpose();
  }
  out.clean.F.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t f = 0; f < kept.size(); ++f)
    for (int k = 0; k < 3; ++k)
      out.clean.F(static_cast<Eigen::Index>(f), k) =
          vertex[static_cast<std::size_t>(kept[f][static_cast<std::size_t>(k)])];
  return out;
}

namespace {
// The shape scaled to the pose's size, turned by the pose's seeded rotation, centred at the
// origin (metres).
TriMesh place(const TriMesh& shape, const ScanPose& pose) {
  const Vec3 lo = shape.V.colwise().minCoeff().transpose(), hi = shape.V.colwise().maxCoeff().transpose();
  const double scale = pose.object_size_m / (hi - lo).maxCoeff();
  const Vec3 mid = 0.5 * (lo + hi);
  // A uniformly random rotation: a normalised quaternion of four Gaussian draws.
  Eigen::Quaterniond q(gauss(pose.seed, 0, 10), gauss(pose.seed, 0, 11), gauss(pose.seed, 0, 12),
                       gauss(pose.seed, 0, 13));
  q.normalize();
  const Eigen::Matrix3d R = q.toRotationMatrix();
  TriMesh placed = shape;
  for (Eigen::Index v = 0; v < placed.V.rows(); ++v)
    placed.V.row(v) = (R * (scale * (shape.V.row(v).transpose() - mid))).transpose();
  return placed;
}

// A mesh moved by x -> R x + t.
TriMesh moved(const TriMesh& m, const Eigen::Matrix3d& R, const Vec3& t) {
  TriMesh out = m;
  for (Eigen::Index v = 0; v < m.V.rows(); ++v) out.V.row(v) = (R * m.V.row(v).transpose() + t).transpose();
  return out;
}

CaptureOptions booth(const ScanPose& pose, std::uint64_t seed) {
  CaptureOptions options;
  options.seed = seed;
  options.wall_depth_m = pose.distance_m + pose.object_size_m + 0.2;  // behind the bounding sphere
  return options;
}
}  // namespace

RangeScan scan_shape(const TriMesh& shape, const RangeSensor& sensor, const ScanPose& pose) {
  const TriMesh placed = moved(place(shape, pose), Eigen::Matrix3d::Identity(), Vec3(0, 0, pose.distance_m));
  RangeScan s = mesh_range_image(capture(placed, sensor, booth(pose, mix(pose.seed ^ 0x5ca11))), sensor);
  if (s.clean.F.rows() < 100)
    throw std::runtime_error("scan_shape: " + std::to_string(s.clean.F.rows()) + " faces in view, fewer than 100");
  return s;
}

RangeScan fuse_scans(const TriMesh& shape, const RangeSensor& sensor, const ScanPose& pose,
                     const FusedOptions& options) {
  if (options.views < 1 || options.voxels_across < 8)
    throw std::invalid_argument("fuse_scans: views >= 1, voxels_across >= 8");
  const TriMesh object = place(shape, pose);
  const double d = pose.distance_m;
  // Decision 58: voxels of the object's size over voxels_across, never below the footprint;
  // truncation at four voxels or the noise's reach, whichever is larger.
  const double voxel = std::max(pose.object_size_m / options.voxels_across, d * sensor.stride / sensor.focal_px);
  const double trunc = std::max(4 * voxel, 4 * axial_sigma(sensor, d, 0) + depth_step(sensor, d));
  const Vec3 lo = object.V.colwise().minCoeff().transpose() - Vec3::Constant(2 * trunc);
  const Vec3 span = object.V.colwise().maxCoeff().transpose() + Vec3::Constant(2 * trunc) - lo;
  const int nx = static_cast<int>(std::ceil(span.x() / voxel)) + 1,
            ny = static_cast<int>(std::ceil(span.y() / voxel)) + 1,
            nz = static_cast<int>(std::ceil(span.z() / voxel)) + 1;
  const auto at = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(ny) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(nx) +
           static_cast<std::size_t>(i);
  };
  const auto centre = [&](int i, int j, int k) { return Vec3(lo + voxel * Vec3(i, j, k)); };
  std::vector<double> sdf(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny) * static_cast<std::size_t>(nz),
                          0);
  std::vector<double> weight(sdf.size(), 0);
  // The same fusion of the noise-free depths of the same pixels: the ground truth (decision 58).
  std::vector<double> clean_sdf(sdf.size(), 0), clean_weight(sdf.size(), 0);

  // The turntable: the object turns about the camera's vertical (y) axis in equal steps from a
  // seeded start, seen from `elevation_deg` above; each view a capture with its own draws.
  const double elevation = options.elevation_deg * std::numbers::pi / 180;
  const Eigen::Matrix3d tilt = Eigen::AngleAxisd(-elevation, Vec3::UnitX()).toRotationMatrix();
  for (int view = 0; view < options.views; ++view) {
    const double phi = 2 * std::numbers::pi * (view / static_cast<double>(options.views) + uniform(pose.seed, 0, 20));
    const Eigen::Matrix3d R = tilt * Eigen::AngleAxisd(phi, Vec3::UnitY()).toRotationMatrix();
    const Vec3 t(0, 0, d);
    const RangeImage im = capture(moved(object, R, t), sensor,
                                  booth(pose, mix(pose.seed ^ (0xf05edull + static_cast<std::uint64_t>(view)))));
    // Curless and Levoy 1996 (KinectFusion's fusion, Newcombe et al. 2011): each voxel's
    // projective signed distance to the reported surface, truncated, averaged over views;
    // voxels further behind the surface than the truncation are left as they are (unseen).
    for (int k = 0; k < nz; ++k)
      for (int j = 0; j < ny; ++j)
        for (int i = 0; i < nx; ++i) {
          const Vec3 q = R * centre(i, j, k) + t;
          if (q.z() <= 0) continue;
          const long c = std::lround(im.focal * q.x() / q.z() + im.cx),
                     r = std::lround(im.focal * q.y() / q.z() + im.cy);
          if (c < 0 || r < 0 || c >= im.cols || r >= im.rows) continue;
          const std::size_t pixel = static_cast<std::size_t>(r * im.cols + c);
          const double z = im.depth[pixel], zc = im.clean_depth[pixel];
          if (std::isnan(z)) continue;
          const std::size_t v = at(i, j, k);
          if (z - q.z() >= -trunc) {
            sdf[v] = (sdf[v] * weight[v] + std::min(1.0, (z - q.z()) / trunc)) / (weight[v] + 1);
            weight[v] += 1;
          }
          if (zc - q.z() >= -trunc) {
            clean_sdf[v] =
                (clean_sdf[v] * clean_weight[v] + std::min(1.0, (zc - q.z()) / trunc)) / (clean_weight[v] + 1);
            clean_weight[v] += 1;
          }
        }
  }

  // Surface nets (Gibson 1998): one vertex per cell whose eight corners are all seen and
  // change sign, at the mean of its edges' zero crossings; one quad per voxel edge that
  // changes sign between four such cells. Negative is inside.
  const auto cell = [&](int i, int j, int k) {
    return (static_cast<std::size_t>(k) * static_cast<std::size_t>(ny - 1) + static_cast<std::size_t>(j)) *
               static_cast<std::size_t>(nx - 1) +
           static_cast<std::size_t>(i);
  };
  std::vector<std::int32_t> cell_vertex(
      static_cast<std::size_t>(nx - 1) * static_cast<std::size_t>(ny - 1) * static_cast<std::size_t>(nz - 1), -1);
  // The cell's vertex in a volume: the mean of its edges' zero crossings, if its eight
  // corners were seen and change sign.
  const auto cell_point = [&](const std::vector<double>& f, const std::vector<double>& w, int i, int j,
                              int k) -> std::optional<Vec3> {
    bool inside = false, outside = false;
    for (int c = 0; c < 8; ++c) {
      const std::size_t v = at(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
      if (w[v] <= 0) return std::nullopt;
      (f[v] < 0 ? inside : outside) = true;
    }
    if (!inside || !outside) return std::nullopt;
    Vec3 sum = Vec3::Zero();
    int crossings = 0;
    for (int a = 0; a < 8; ++a)
      for (const int b : {a | 1, a | 2, a | 4}) {  // the cell's 12 edges, each once
        if (b == a) continue;
        const int ia = i + (a & 1), ja = j + ((a >> 1) & 1), ka = k + (a >> 2);
        const int ib = i + (b & 1), jb = j + ((b >> 1) & 1), kb = k + (b >> 2);
        const double sa = f[at(ia, ja, ka)], sb = f[at(ib, jb, kb)];
        if ((sa < 0) == (sb < 0)) continue;
        sum += centre(ia, ja, ka) + sa / (sa - sb) * (centre(ib, jb, kb) - centre(ia, ja, ka));
        ++crossings;
      }
    return sum / crossings;
  };
  std::vector<Vec3> positions;
  for (int k = 0; k + 1 < nz; ++k)
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i)
        if (const auto p = cell_point(sdf, weight, i, j, k)) {
          cell_vertex[cell(i, j, k)] = static_cast<std::int32_t>(positions.size());
          positions.push_back(*p);
        }
  std::vector<std::array<int, 3>> tris;
  const int n[3] = {nx, ny, nz};
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i)
        for (int axis = 0; axis < 3; ++axis) {
          int p[3] = {i, j, k};
          if (p[axis] + 1 >= n[axis]) continue;
          const std::size_t va = at(i, j, k);
          int q[3] = {i, j, k};
          ++q[axis];
          const std::size_t vb = at(q[0], q[1], q[2]);
          if (weight[va] <= 0 || weight[vb] <= 0 || (sdf[va] < 0) == (sdf[vb] < 0)) continue;
          // The four cells around the edge, counter-clockwise about +axis (u, w = the next two
          // axes in cyclic order): (-,-), (0,-), (0,0), (-,0).
          const int u = (axis + 1) % 3, w = (axis + 2) % 3;
          if (p[u] < 1 || p[w] < 1 || p[u] >= n[u] - 1 || p[w] >= n[w] - 1) continue;
          std::array<int, 4> quad{};
          bool complete = true;
          const int du[4] = {-1, 0, 0, -1}, dw[4] = {-1, -1, 0, 0};
          for (int c = 0; c < 4 && complete; ++c) {
            int x[3] = {i, j, k};
            x[u] += du[c];
            x[w] += dw[c];
            quad[static_cast<std::size_t>(c)] = cell_vertex[cell(x[0], x[1], x[2])];
            complete = quad[static_cast<std::size_t>(c)] >= 0;
          }
          if (!complete) continue;
          if (sdf[va] >= 0) std::swap(quad[1], quad[3]);  // outside at the start: the normal is -axis
          const auto P = [&](int c) { return positions[static_cast<std::size_t>(quad[static_cast<std::size_t>(c)])]; };
          if ((P(0) - P(2)).squaredNorm() <= (P(1) - P(3)).squaredNorm()) {
            tris.push_back({quad[0], quad[1], quad[2]});
            tris.push_back({quad[0], quad[2], quad[3]});
          } else {
            tris.push_back({quad[0], quad[1], quad[3]});
            tris.push_back({quad[1], quad[2], quad[3]});
          }
        }
  const std::vector<std::array<int, 3>> kept = drop_small_components(tris, positions.size());
  std::vector<std::int32_t> index(positions.size(), -1);
  std::int32_t count = 0;
  for (const auto& t : kept)
    for (const int v : t)
      if (index[static_cast<std::size_t>(v)] < 0) index[static_cast<std::size_t>(v)] = 0;
  for (std::size_t v = 0; v < positions.size(); ++v)
    if (index[v] == 0)
      index[v] = count++;
    else
      index[v] = -1;
  // Decision 99: a fused vertex has no pixel to follow; its ground truth is where it meets the
  // fusion of the noise-free depths of the same pixels (the zero set of that volume's trilinear
  // interpolation), moving along its smoothed normal: neighbours stay neighbours, none folds
  // over another, no two share a point. Where that volume was not seen along the way or has no
  // zero within two voxels, the nearest point of the clean surface.
  const Bvh bvh(object);
  // The noise-free volume at x (trilinear), if the eight corners of x's cell were seen.
  const auto clean_field = [&](const Vec3& x) -> std::optional<double> {
    const Vec3 g = (x - lo) / voxel;
    const int i = static_cast<int>(std::floor(g.x())), j = static_cast<int>(std::floor(g.y())),
              k = static_cast<int>(std::floor(g.z()));
    if (i < 0 || j < 0 || k < 0 || i + 1 >= nx || j + 1 >= ny || k + 1 >= nz) return std::nullopt;
    const double u = g.x() - i, w = g.y() - j, s = g.z() - k;
    double f = 0;
    for (int c = 0; c < 8; ++c) {
      const int a = c & 1, b = (c >> 1) & 1, e = c >> 2;
      const std::size_t v = at(i + a, j + b, k + e);
      if (clean_weight[v] <= 0) return std::nullopt;
      f += clean_sdf[v] * (a ? u : 1 - u) * (b ? w : 1 - w) * (e ? s : 1 - s);
    }
    return f;
  };
  // Each vertex moves along its normal on the fused surface, smoothed over its neighbours so
  // that neighbouring vertices move along nearly parallel lines and none crosses another: the
  // area-weighted normals of its faces, then four passes of the mean over the faces' corners.
  std::vector<Vec3> along(positions.size(), Vec3::Zero());
  for (const auto& t : kept) {
    const Vec3 n = (positions[static_cast<std::size_t>(t[1])] - positions[static_cast<std::size_t>(t[0])])
                       .cross(positions[static_cast<std::size_t>(t[2])] - positions[static_cast<std::size_t>(t[0])]);
    for (const int v : t) along[static_cast<std::size_t>(v)] += n;
  }
  for (int pass = 0; pass < 4; ++pass) {
    std::vector<Vec3> next(positions.size(), Vec3::Zero());
    for (const auto& t : kept) {
      const Vec3 sum = along[static_cast<std::size_t>(t[0])].normalized() + along[static_cast<std::size_t>(t[1])].normalized() +
                       along[static_cast<std::size_t>(t[2])].normalized();
      for (const int v : t) next[static_cast<std::size_t>(v)] += sum;
    }
    along.swap(next);
  }
  // The zero of the noise-free volume on the line start + t n nearest to t = 0, |t| up to two
  // voxels: the first sign change in steps of a tenth of a voxel, alternately ahead and behind,
  // then bisection.
  const auto onto_clean_fusion = [&](const Vec3& start, const Vec3& n) -> std::optional<Vec3> {
    const std::optional<double> f0 = clean_field(start);
    if (!f0 || n.squaredNorm() == 0) return std::nullopt;
    const double h = 0.1 * voxel;
    std::optional<double> last[2] = {f0, f0};  // the value at the previous step, ahead and behind
    for (int k = 1; k <= 20; ++k)
      for (int side = 0; side < 2; ++side) {
        const double dir = side == 0 ? 1.0 : -1.0;
        double ta = dir * (k - 1) * h, tb = dir * k * h;
        const std::optional<double> fa = last[side], fb = clean_field(start + tb * n);
        last[side] = fb;
        if (!fa || !fb || (*fa < 0) == (*fb < 0)) continue;
        const bool a_inside = *fa < 0;
        for (int it = 0; it < 40; ++it) {
          const double tm = 0.5 * (ta + tb);
          const std::optional<double> fm = clean_field(start + tm * n);
          if (!fm) return std::nullopt;
          (((*fm < 0) == a_inside) ? ta : tb) = tm;
        }
        return start + 0.5 * (ta + tb) * n;
      }
    return std::nullopt;
  };
  RangeScan out;
  out.noisy.resize(count, 3);
  out.clean.V.resize(count, 3);
  for (std::size_t v = 0; v < positions.size(); ++v) {
    if (index[v] < 0) continue;
    const std::optional<Vec3> truth = onto_clean_fusion(positions[v], along[v].normalized());
    out.noisy.row(index[v]) = positions[v].transpose();
    out.clean.V.row(index[v]) = (truth ? *truth : bvh.closest_point(positions[v])).transpose();
  }
  out.clean.F.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (std::size_t f = 0; f < kept.size(); ++f)
    for (int c = 0; c < 3; ++c)
      out.clean.F(static_cast<Eigen::Index>(f), c) =
          index[static_cast<std::size_t>(kept[f][static_cast<std::size_t>(c)])];
  if (out.clean.F.rows() < 100)
    throw std::runtime_error("fuse_scans: " + std::to_string(out.clean.F.rows()) + " faces fused, fewer than 100");
  return out;
}

}  // namespace mdn::train
