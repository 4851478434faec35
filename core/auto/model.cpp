#include "core/auto/model.h"

#include <algorithm>
#include <array>
#include <stdexcept>

#include "core/auto/descriptors.h"

namespace mdn {

namespace {
#include "core/auto/model_data.inc"

Eigen::MatrixXd matrix(const double* data, int rows, int cols) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(data, rows, cols);
}
Eigen::VectorXd vector(const double* data, int n) { return Eigen::Map<const Eigen::VectorXd>(data, n); }
}  // namespace

ParameterModel::ParameterModel() : version_(model_data::kVersion) {
  using namespace model_data;
  const std::vector<std::string>& expected = descriptor_names();
  if (static_cast<int>(expected.size()) != kInputs ||
      !std::equal(expected.begin(), expected.end(), std::begin(kDescriptorNames)))
    throw std::logic_error("the compiled-in parameter model (" + version_ +
                           ") was trained on other descriptors than core/auto/descriptors.cpp computes; retrain it "
                           "(tools/train/README.md)");
  for (int k = 0; k < kSetCount; ++k) {
    names_.emplace_back(kSetNames[k]);
    sets_.push_back({kSetValues[k][0], kSetValues[k][1], kSetValues[k][2], kSetValues[k][3], kSetValues[k][4], kSetValues[k][5]});
    identity_.push_back(names_.back() == "identity");
  }
  mean_ = vector(kMean, kInputs);
  scale_ = vector(kScale, kInputs);
  for (int m = 0; m < kMembers; ++m) {
    members_.push_back({{matrix(kW0 + m * kHidden * kInputs, kHidden, kInputs), matrix(kW1 + m * kHidden * kHidden, kHidden, kHidden),
                         matrix(kW2 + m * kSetCount * kHidden, kSetCount, kHidden)},
                        {vector(kB0 + m * kHidden, kHidden), vector(kB1 + m * kHidden, kHidden), vector(kB2 + m * kSetCount, kSetCount)}});
  }
}

const std::vector<ModelProbe>& model_probes() {
  static const std::vector<ModelProbe> probes = [] {
    using namespace model_data;
    std::vector<ModelProbe> out;
    for (int i = 0; i < kProbeCount; ++i)
      out.push_back({kProbeNames[i], std::vector<double>(kProbeInputs[i], kProbeInputs[i] + kInputs),
                     std::vector<double>(kProbeOutputs[i], kProbeOutputs[i] + kSetCount)});
    return out;
  }();
  return probes;
}

const ParameterModel& ParameterModel::shipped() {
  static const ParameterModel model;
  return model;
}

DenoiseParams fill_unpinned(const DenoiseParams& requested, const std::array<double, 6>& values) {
  DenoiseParams p = requested;
  p.mode = ParamMode::Manual;
  if (!requested.is_pinned(AutoField::Alpha)) p.alpha = values[0];
  if (!requested.is_pinned(AutoField::SigmaTheta)) p.sigma_theta = values[1];
  if (!requested.is_pinned(AutoField::NAniso)) p.n_aniso = static_cast<int>(values[2]);
  if (!requested.is_pinned(AutoField::SigmaGamma)) p.sigma_gamma = values[3];
  if (!requested.is_pinned(AutoField::NNormal)) p.n_normal = static_cast<int>(values[4]);
  if (!requested.is_pinned(AutoField::NVertex)) p.n_vertex = static_cast<int>(values[5]);
  return p;
}

DenoiseParams ParameterModel::set_params(int k, const DenoiseParams& requested) const {
  std::array<double, 6> s = sets_.at(static_cast<std::size_t>(k));
  // identity: no pre-filter (alpha 0), no iterations; the angles keep the caller's values.
  if (is_identity(k)) {
    s[1] = requested.sigma_theta;
    s[3] = requested.sigma_gamma;
  }
  return fill_unpinned(requested, s);
}

Eigen::VectorXd ParameterModel::predict(const std::vector<double>& descriptors) const {
  if (static_cast<Eigen::Index>(descriptors.size()) != mean_.size())
    throw std::invalid_argument("ParameterModel::predict: expected " + std::to_string(mean_.size()) + " descriptors");
  const Eigen::VectorXd z = (Eigen::Map<const Eigen::VectorXd>(descriptors.data(), mean_.size()) - mean_).cwiseQuotient(scale_);
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(members_.front().biases.back().size());
  for (const Network& net : members_) {
    Eigen::VectorXd x = z;
    for (std::size_t l = 0; l < net.weights.size(); ++l) {
      x = net.weights[l] * x + net.biases[l];
      if (l + 1 < net.weights.size()) x = x.cwiseMax(0.0);  // ReLU on the hidden layers
    }
    sum += x;
  }
  return sum / static_cast<double>(members_.size());
}

}  // namespace mdn
