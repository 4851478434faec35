// Vertex pre-filtering, Sec. 4 of Lu, Chen, Schaefer. All positions are #V by 3 in the
// unit-box frame; the topology is that of the mesh being filtered.
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include "core/mesh.h"
#include "core/params.h"
#include "core/topology.h"

namespace mdn {

class Executor;
class ProgressObserver;

// Solves the systems (I + alpha D^T W D) P~ = P of Eq. 1 (W = I) and Eq. 3 (W = diag(w_e)),
// with D the #E by #V shaping operator, one row per interior manifold edge. All systems
// share one sparsity pattern, so the symbolic analysis is done once (LDLT); CG is matrix-free
// and starts from the anchor P, i.e. the previous iterate for Eq. 3. Not thread-safe; one per
// pipeline run.
class ShapingSolver {
 public:
  // executor: optional threads for the CG solver (results do not depend on the count).
  ShapingSolver(const Topology& topo, LinearSolver kind, double cg_tolerance, Executor* executor = nullptr);
  ~ShapingSolver();
  // Returns the solution P~ (#V by 3). weights: #E edge weights, or empty for W = I. start:
  // CG's first iterate (#V by 3; none: P itself), taken over as its iterate; LDLT ignores it.
  Vertices solve(const Vertices& P, double alpha, const Eigen::VectorXd& weights,
                 std::optional<Vertices> start = std::nullopt);
  // CG iterations of the last solve: single-precision and double ones together (decision 37;
  // 0 for LDLT).
  int last_iterations() const;
  // The threads given at construction (nullptr: serial).
  Executor* executor() const;
  // Frees the CG work vectors kept between solves (decision 29); the next solve allocates them
  // again. The pipeline calls it before Eq. 2, whose factorisation would otherwise hold its
  // peak on top of them.
  void release_buffers();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// Eq. 1: initial isotropic pre-filter.
Vertices initial_prefilter(const Vertices& P, const Topology& topo, double alpha,
                           LinearSolver kind = LinearSolver::Ldlt);

// Eq. 4: w_e = b^-((1 - cos theta) / (1 - cos sigma_theta)), theta the angle between the
// normals of the edge's two faces. Returns #E weights.
Eigen::VectorXd anisotropic_edge_weights(const Vertices& P, const Triangles& F, const Topology& topo,
                                         double sigma_theta_deg, double b);

// Eq. 3, iterated `iterations` times, each anchored to the previous output with w_e
// recomputed; from the second pass on, CG starts from the last pass's step repeated
// (decision 42). `solver` is reused across calls if given. Checks `progress` for
// cancellation before every iteration (throws CancelledError).
Vertices anisotropic_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                               const DenoiseParams& params, ShapingSolver* solver = nullptr,
                               ProgressObserver* progress = nullptr, const IterationHook& on_iteration = {});

// Sec. 4.2: fraction of interior manifold edges whose two face normals make an angle
// greater than fold_angle_deg.
double fold_ratio(const Vertices& P, const Triangles& F, const Topology& topo, double fold_angle_deg,
                  Executor* executor = nullptr);

struct FaceClusters {
  std::vector<std::int32_t> label;   // #F cluster index in [0, K)
  std::vector<double> mean_area;     // K mean face area per cluster
  std::int32_t smallest = 0;         // cluster with the smallest mean area
  double area_ratio = 1;             // max mean area / min mean area over non-empty clusters
};
// Sec. 4.2: K-means over faces in (centroid, area) space, seeded with k-means++. Features:
// centroids scaled to unit total variance, log(area) standardised (see core/README.md).
FaceClusters cluster_faces(const Vertices& P, const Triangles& F, int k, std::uint64_t seed,
                           int max_iterations = 100, Executor* executor = nullptr);
// cluster_faces' area ratio on every ceil(#F / max_faces)-th face (all of them up to
// max_faces); 1 where the sample has fewer than k faces. A quick reading of Sec. 4.2's
// irregularity test (measure_input, decision 48).
double sampled_area_ratio(const Vertices& P, const Triangles& F, int k, std::uint64_t seed, std::int64_t max_faces,
                          Executor* executor = nullptr);

namespace detail {
// Rows of (centroid, log area) features, scaled as cluster_faces describes.
using ClusterFeatures = Eigen::Matrix<double, Eigen::Dynamic, 4, Eigen::RowMajor>;
// Lloyd's iterations from `centers` (k rows) until no label changes, at most max_iterations;
// the labels into `label` (one per row of X, all 0 on entry), the final centres into
// `centers`. The same labels and centres as plain Lloyd for any thread count (decisions 39, 49).
void lloyd_iterations(const ClusterFeatures& X, ClusterFeatures& centers, int max_iterations, Executor* executor,
                      std::vector<std::int32_t>& label);
}  // namespace detail

// Eq. 2 on one set of faces: their vertices are unknowns, every other vertex is fixed.
// Minimises ||P~ - P||^2 + beta ||L P~||^2 over the unknowns, L the uniform Laplacian of
// the whole mesh restricted to the unknown rows. Returns the new positions of all vertices.
// Solved matrix-free by Jacobi-preconditioned CG to a relative residual of 1e-10 per column
// (decision 38), over the executor's threads if given (the result does not depend on them).
Vertices region_prefilter(const Vertices& P, const Triangles& F, const Topology& topo,
                          const std::vector<std::int32_t>& faces, double beta,
                          std::int64_t* num_unknowns = nullptr, Executor* executor = nullptr);

}  // namespace mdn
