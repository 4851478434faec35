// One job from bytes to bytes. Both executables go through here, so a mesh denoised by the
// CLI and by the HTTP server with the same parameters gives identical bytes.
#include "server/job_runner.h"

#include <chrono>
#include <memory>
#include <utility>

namespace mdn::service {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

void add_timings(StageTimings& sum, const StageTimings& t) {
  sum.setup_ms += t.setup_ms;
  sum.measure_ms += t.measure_ms;
  sum.initial_ms += t.initial_ms;
  sum.region_ms += t.region_ms;
  sum.anisotropic_ms += t.anisotropic_ms;
  sum.normal_ms += t.normal_ms;
  sum.vertex_ms += t.vertex_ms;
  sum.total_ms += t.total_ms;
}

}  // namespace

JobOutput run_job(const JobInput& input, const io::Limits& limits, ProgressObserver* progress) {
  // Parameters first: a bad request is refused before any decoding work.
  validate(input.params);

  JobOutput out;
  out.effective = input.params;

  auto start = Clock::now();
  std::unique_ptr<io::MeshDocument> document = io::decode(input.bytes, input.format, limits);
  out.decode_ms = ms_since(start);

  const RunOptions options{.threads = input.threads < 1 ? 1 : input.threads, .progress = progress};
  start = Clock::now();
  for (TriMesh& surface : document->surfaces()) {
    DenoiseResult result = denoise(surface, input.params.denoise, options);
    // denoise() keeps the connectivity; only positions go back into the document.
    surface.V = std::move(result.mesh.V);
    out.vertices += surface.num_vertices();
    out.faces += surface.num_faces();
    add_timings(out.stages, result.report.timings);
    out.reports.push_back(result.report);
  }
  out.denoise_ms = ms_since(start);

  io::EncodeOptions encode = input.params.output;
  if (!encode.format) encode.format = document->format();
  out.format = *encode.format;
  out.media_type = std::string(io::media_type(out.format));
  out.effective.output.format = out.format;  // echo what was actually produced

  start = Clock::now();
  out.bytes = document->encode(encode);
  out.encode_ms = ms_since(start);
  out.notes = document->notes();
  out.surfaces = std::move(document->surfaces());  // the document is done with them
  return out;
}

nlohmann::json report_to_json(const DenoiseReport& report) {
  nlohmann::json j = {
      {"fold_ratio", report.fold_ratio},
      {"cluster_area_ratio", report.cluster_area_ratio},
      {"region_prefilter_applied", report.region_prefilter_applied},
      {"region_vertices", report.region_vertices},
      {"mode", std::string(to_string(report.mode))},
      {"params", method_params_json(report.params)},
  };
  if (report.measures) {
    const InputMeasures& m = *report.measures;
    j["measures"] = {{"noise", m.noise},
                     {"tail", m.tail},
                     {"feature_share", m.feature_share},
                     {"smooth_residual", m.smooth_residual},
                     {"smooth_tail", m.smooth_tail},
                     {"cluster_area_ratio", m.cluster_area_ratio}};
  }
  if (report.selection) {
    const Selection& sel = *report.selection;
    nlohmann::json candidates = nlohmann::json::array();
    for (const ScoredCandidate& c : sel.candidates)
      candidates.push_back({{"name", c.name}, {"score", c.score}, {"params", method_params_json(c.params)}});
    j["selection"] = {{"noise",
                       {{"sigma_edges", sel.noise.sigma_edges},
                        {"sigma", sel.noise.sigma},
                        {"gaussian_sigma", sel.noise.gaussian_sigma},
                        {"edge_length", sel.noise.edge_length}}},
                      {"sample_faces", sel.sample_faces},
                      {"scored_faces", sel.scored_faces},
                      {"candidates", std::move(candidates)},
                      {"chosen", sel.candidates[static_cast<std::size_t>(sel.chosen)].name},
                      {"evaluations", sel.evaluations}};
  }
  return j;
}

nlohmann::json job_summary_json(const JobOutput& output) {
  nlohmann::json surfaces = nlohmann::json::array();
  for (const auto& report : output.reports) surfaces.push_back(report_to_json(report));
  const StageTimings& s = output.stages;
  return {
      {"format", std::string(io::to_string(output.format))},
      {"media_type", output.media_type},
      {"bytes", output.bytes.size()},
      {"vertices", output.vertices},
      {"faces", output.faces},
      {"params", to_json(output.effective)},
      {"timings_ms",
       {
           {"decode", output.decode_ms},
           {"denoise", output.denoise_ms},
           {"encode", output.encode_ms},
           {"setup", s.setup_ms},
           {"measure", s.measure_ms},
           {"initial", s.initial_ms},
           {"region", s.region_ms},
           {"anisotropic", s.anisotropic_ms},
           {"normal", s.normal_ms},
           {"vertex", s.vertex_ms},
           {"prefilter", s.prefilter_ms()},
           {"total", s.total_ms},
       }},
      {"surfaces", std::move(surfaces)},
      {"notes", output.notes},
  };
}

}  // namespace mdn::service
