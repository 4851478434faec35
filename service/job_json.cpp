#include "service/job_json.h"

#include <string>
#include <utility>

#include "core/auto/choice.h"
#include "service/params_json.h"

namespace mdn::service {

using nlohmann::json;

namespace {

json noise_to_json(const NoiseEstimate& n) {
  return {{"sigma_edges", n.sigma_edges},
          {"sigma", n.sigma},
          {"gaussian_sigma", n.gaussian_sigma},
          {"edge_length", n.edge_length}};
}

// ParamMode::Search's recorrupted scores and descent (core/auto/recorrupted.h).
json search_to_json(const Selection& sel) {
  json candidates = json::array();
  for (const ScoredCandidate& c : sel.candidates)
    candidates.push_back({{"name", c.name},
                          {"score", c.score},
                          {"draws", c.draws},
                          {"removed_edges", sel.noise.edge_length > 0 ? c.residual / sel.noise.edge_length : 0.0},
                          {"eligible", c.eligible},
                          {"params", method_params_json(c.params)}});
  return {{"noise", noise_to_json(sel.noise)},
          {"sample_faces", sel.sample_faces},
          {"scored_faces", sel.scored_faces},
          {"candidates", std::move(candidates)},
          {"chosen", sel.candidates[static_cast<std::size_t>(sel.chosen)].name},
          {"evaluations", sel.evaluations}};
}

json choice_to_json(const ParameterChoice& c) {
  json descriptors = json::object();
  for (const auto& [name, value] : c.descriptors) descriptors[name] = value;
  json sets = json::array();
  for (const PredictedSet& s : c.sets) sets.push_back({{"name", s.name}, {"predicted_ratio", s.predicted}});
  json j = {{"method", c.method},
            {"model_version", c.model_version},
            {"chosen", c.chosen},
            {"predicted_ratio", c.predicted},
            {"noise", noise_to_json(c.noise)},
            {"descriptors", std::move(descriptors)},
            {"sets", std::move(sets)},
            {"notes", c.notes}};
  if (c.search) j["search"] = search_to_json(*c.search);
  return j;
}

}  // namespace

json report_to_json(const DenoiseReport& report) {
  json j = {
      {"fold_ratio", report.fold_ratio},
      {"cluster_area_ratio", report.cluster_area_ratio},
      {"region_prefilter_applied", report.region_prefilter_applied},
      {"region_vertices", report.region_vertices},
      {"mode", std::string(to_string(report.mode))},
      {"params", method_params_json(report.params)},
  };
  if (report.choice) {
    const ParameterChoice& c = *report.choice;
    const InputMeasures& m = c.measures;
    j["measures"] = {{"noise", m.noise},
                     {"tail", m.tail},
                     {"feature_share", m.feature_share},
                     {"smooth_residual", m.smooth_residual},
                     {"smooth_tail", m.smooth_tail},
                     {"cluster_area_ratio", m.cluster_area_ratio}};
    j["choice"] = choice_to_json(c);
  }
  return j;
}

json reports_to_json(const std::vector<DenoiseReport>& reports) {
  json out = json::array();
  for (const DenoiseReport& r : reports) out.push_back(report_to_json(r));
  return out;
}

json timings_to_json(const JobTimings& timings) {
  json j = json::object();
  for (const TimingField& f : kTimingFields) j[std::string(f.name)] = timings.*f.member;
  return j;
}

JobTimings timings_from_json(const json& j) {
  JobTimings t;
  for (const TimingField& f : kTimingFields)
    if (auto it = j.find(f.name); it != j.end()) t.*f.member = it->get<double>();
  return t;
}

json output_to_json(const JobOutput& output, std::int64_t bytes, json reports) {
  return {{"format", std::string(io::to_string(output.format))},
          {"compression", std::string(io::to_string(output.compression))},
          {"media_type", output.media_type},
          {"bytes", bytes},
          {"vertices", output.vertices},
          {"faces", output.faces},
          {"params", to_json(output.effective)},
          {"notes", output.notes},
          {"reports", std::move(reports)},
          {"timings_ms", timings_to_json(output.timings)}};
}

json output_to_json(const JobOutput& output) {
  return output_to_json(output, std::int64_t(output.bytes.size()), reports_to_json(output.reports));
}

JobOutput output_from_json(const json& j, json& reports, std::int64_t& bytes) {
  JobOutput o;
  const std::string format = j.at("format").get<std::string>();
  o.format = io::format_from_string(format).value_or(io::Format::Off);
  // Documents stored before "compression" existed read as None.
  if (const auto it = j.find("compression"); it != j.end())
    o.compression = io::compression_from_string(it->get<std::string>()).value_or(io::Compression::None);
  o.media_type = j.at("media_type").get<std::string>();
  bytes = j.at("bytes").get<std::int64_t>();
  o.vertices = j.at("vertices").get<std::int64_t>();
  o.faces = j.at("faces").get<std::int64_t>();
  o.effective = job_params_from_json(j.at("params"));
  o.notes = j.at("notes").get<std::vector<std::string>>();
  reports = j.at("reports");
  o.timings = timings_from_json(j.at("timings_ms"));
  return o;
}

}  // namespace mdn::service
