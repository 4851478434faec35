#include "core/auto/face_prior.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "core/auto/face_features.h"
#include "core/parallel.h"

namespace mdn {

namespace {
#include "core/auto/face_model_data.inc"

constexpr std::int64_t kBlock = 256;  // faces per block of the network (fixed: thread-free results)

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

struct Network {
  Eigen::VectorXd mean, scale, b0, b1, b2;
  Eigen::MatrixXd W0, W1, W2;
  Network() {
    using namespace face_model_data;
    static_assert(kInputs == kFaceFeatures, "face_model_data.inc was trained on other features: retrain it");
    mean = Eigen::Map<const Eigen::VectorXd>(kMean, kInputs);
    scale = Eigen::Map<const Eigen::VectorXd>(kScale, kInputs);
    W0 = Eigen::Map<const RowMajor>(kW0, kHidden, kInputs);
    W1 = Eigen::Map<const RowMajor>(kW1, kHidden, kHidden);
    W2 = Eigen::Map<const RowMajor>(kW2, 4, kHidden);
    b0 = Eigen::Map<const Eigen::VectorXd>(kB0, kHidden);
    b1 = Eigen::Map<const Eigen::VectorXd>(kB1, kHidden);
    b2 = Eigen::Map<const Eigen::VectorXd>(kB2, 4);
  }
  // X: kInputs by n raw features (columns); returns 4 by n.
  Eigen::MatrixXd operator()(const Eigen::MatrixXd& X) const {
    const Eigen::MatrixXd Z = (X.colwise() - mean).array().colwise() / scale.array();
    const Eigen::MatrixXd H0 = ((W0 * Z).colwise() + b0).cwiseMax(0.0);
    const Eigen::MatrixXd H1 = ((W1 * H0).colwise() + b1).cwiseMax(0.0);
    return (W2 * H1).colwise() + b2;
  }
  static const Network& shipped() {
    static const Network net;
    return net;
  }
};

double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0;
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1) + 0.5);
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

}  // namespace

const std::string& face_prior_version() {
  static const std::string version = face_model_data::kVersion;
  return version;
}

Eigen::MatrixXd face_network(const Eigen::MatrixXd& features) { return Network::shipped()(features.transpose()).transpose(); }

const std::vector<FaceProbe>& face_prior_probes() {
  static const std::vector<FaceProbe> probes = [] {
    using namespace face_model_data;
    std::vector<FaceProbe> out;
    for (int i = 0; i < kProbeCount; ++i)
      out.push_back({std::vector<double>(kProbeInputs + i * kInputs, kProbeInputs + (i + 1) * kInputs),
                     std::vector<double>(kProbeOutputs + i * 4, kProbeOutputs + (i + 1) * 4)});
    return out;
  }();
  return probes;
}

FacePrior face_prior(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor) {
  const auto t0 = std::chrono::steady_clock::now();
  // The surface's passes once; each block of 256 non-flat faces then reads its faces and runs
  // the network on them, so no #F by kFaceFeatures table is built (it cost more page faults
  // than arithmetic).
  const FaceReader reader(P, F, topo, executor);
  const std::int64_t nf = F.rows();
  FacePrior out;
  out.guidance.resize(nf, 3);
  out.noise_deg.resize(nf);
  std::vector<std::uint8_t> flat(static_cast<std::size_t>(nf));
  executor.parallel_for(nf, 2048, [&](std::int64_t b, std::int64_t e) {
    for (std::int64_t f = b; f < e; ++f) flat[static_cast<std::size_t>(f)] = reader.flat(f);
  });
  std::vector<std::int32_t> faces;  // where the network runs, in face order
  for (std::int64_t f = 0; f < nf; ++f) {
    const Vec3 n0 = reader.noisy().row(f).transpose(), s = reader.smoothed().row(f).transpose();
    if (n0.squaredNorm() == 0) {  // degenerate: no normal to guide by
      out.guidance.row(f).setZero();
      out.noise_deg(f) = 0;
    } else if (flat[static_cast<std::size_t>(f)]) {
      out.guidance.row(f) = s.transpose();
      out.noise_deg(f) = std::atan2(n0.cross(s).norm(), n0.dot(s)) * 180 / M_PI;
    } else {
      faces.push_back(static_cast<std::int32_t>(f));
    }
  }
  out.evaluated = static_cast<std::int64_t>(faces.size());
  const Network& net = Network::shipped();
  const std::int64_t blocks = (out.evaluated + kBlock - 1) / kBlock;
  executor.parallel_for(blocks, 1, [&](std::int64_t b, std::int64_t e) {
    Eigen::MatrixXd X(kFaceFeatures, kBlock);
    std::vector<Eigen::Matrix3d> frames(static_cast<std::size_t>(kBlock));
    for (std::int64_t block = b; block < e; ++block) {
      const std::int64_t first = block * kBlock, n = std::min(kBlock, out.evaluated - first);
      if (n != X.cols()) X.resize(kFaceFeatures, n);
      for (std::int64_t k = 0; k < n; ++k)
        reader.read(faces[static_cast<std::size_t>(first + k)], X.col(k).data(), frames[static_cast<std::size_t>(k)]);
      const Eigen::MatrixXd Y = net(X);
      for (std::int64_t k = 0; k < n; ++k) {
        const std::int64_t f = faces[static_cast<std::size_t>(first + k)];
        Vec3 local = Y.col(k).head<3>();
        const double norm = local.norm();
        out.guidance.row(f) =
            (norm > 0 ? frame_to_world(frames[static_cast<std::size_t>(k)], local / norm) : Vec3(reader.smoothed().row(f).transpose()))
                .transpose();
        out.noise_deg(f) = std::max(0.0, Y(3, k)) * 180 / M_PI;
      }
    }
  });
  std::vector<double> noise(out.noise_deg.data(), out.noise_deg.data() + nf);
  out.summary.median_deg = quantile(noise, 0.5);
  out.summary.p90_deg = quantile(noise, 0.9);
  out.summary.share_over_2deg =
      nf ? static_cast<double>(std::count_if(noise.begin(), noise.end(), [](double x) { return x > 2; })) / static_cast<double>(nf) : 0;
  out.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace mdn
