// The per-face prior (issue 48, items 2-3; decisions 87-89): a small network, trained offline
// (tools/train/face_train.py) on the training corpus's shapes, that reads each face's
// neighbourhood (core/auto/face_features.h) and predicts its clean normal and the angle by which
// the noise turned it. The normals are the L1-median filter's guidance (decision 53: the range
// weight of Eq. 7 reads them, fixed for the run); the angles are the per-face noise reading.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/mesh.h"
#include "core/topology.h"

namespace mdn {

class Executor;

// The noise reading's summary (issue 48, item 3): over the faces of the surface, the predicted
// angle between each face's noisy and clean normal.
struct FaceNoiseSummary {
  double median_deg = 0;
  double p90_deg = 0;
  double share_over_2deg = 0;  // the share of faces whose predicted angle is above 2 degrees
};

struct FacePrior {
  Vertices guidance;         // #F by 3 unit normals (zero rows for degenerate faces), input face order
  Eigen::VectorXd noise_deg;  // #F predicted noisy-to-clean angles, degrees
  std::int64_t evaluated = 0;  // faces the network ran on (the others read plainly flat)
  FaceNoiseSummary summary;
  double ms = 0;               // time taken (features and network)
};

// The compiled-in network's version (core/auto/face_model_data.inc), e.g. "face-mlp-295753-h32-1a2b3c".
const std::string& face_prior_version();

// Reads (P, F): features, then the network in fixed blocks of 256 faces over the faces that do
// not read plainly flat (those keep the twice ring-mean-filtered normal, and the angle to it as
// their noise reading). Scale-free and rotation-free; bit for bit the same for any thread count.
FacePrior face_prior(const Vertices& P, const Triangles& F, const Topology& topo, Executor& executor);

// The network on raw feature rows (it standardises them), for the probes: #rows by kFaceFeatures in,
// #rows by 4 out (the clean normal in the face's frame, unnormalised; the noise angle in radians).
Eigen::MatrixXd face_network(const Eigen::MatrixXd& features);

struct FaceProbe {
  std::vector<double> inputs, outputs;  // as torch computed them (float32), tools/train/face_train.py
};
const std::vector<FaceProbe>& face_prior_probes();

}  // namespace mdn
