#include "server/http/jobs/redis/job_codec.h"

#include <algorithm>

#include "service/job_json.h"

namespace mdn::http::redis {

using nlohmann::json;

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string problem_text(const Problem& p) {
  return json{{"status", p.status}, {"type", p.type}, {"title", p.title}, {"detail", p.detail},
              {"extensions", p.extensions}}
      .dump();
}

std::optional<Problem> problem_from_text(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const json j = json::parse(text, nullptr, false);
  if (!j.is_object()) return make_problem(ProblemType::Internal, "unreadable stored error");
  Problem p = make_problem(j.value("status", 500), j.value("type", "internal"), j.value("title", ""),
                           j.value("detail", ""));
  if (j.contains("extensions") && j["extensions"].is_object()) p.extensions = j["extensions"];
  return p;
}

// The summary of a result that every replica needs to answer for it (all but the bytes): the
// job's JSON view (service/job_json.h), reports as rendered, exactly what the memory store shows.
std::string output_text(const service::JobOutput& o) { return service::output_to_json(o).dump(); }

// The output (without bytes) and the rendered reports of a stored summary.
std::shared_ptr<service::JobOutput> output_from_text(const std::string& text, json& reports) {
  std::int64_t bytes = 0;
  return std::make_shared<service::JobOutput>(service::output_from_json(json::parse(text), reports, bytes));
}

std::optional<JobState> state_from_string(std::string_view s) {
  for (JobState st : {JobState::Queued, JobState::Running, JobState::Succeeded, JobState::Failed, JobState::Cancelled})
    if (to_string(st) == s) return st;
  return std::nullopt;
}

std::int64_t to_int(const std::string& s, std::int64_t fallback) {
  try {
    return s.empty() ? fallback : std::stoll(s);
  } catch (...) {
    return fallback;
  }
}

double to_double(const std::string& s) {
  try {
    return s.empty() ? 0.0 : std::stod(s);
  } catch (...) {
    return 0.0;
  }
}

JobSnapshot snapshot_from_hash(const std::string& id, std::map<std::string, std::string> h,
                               const std::optional<std::string>& result) {
  JobSnapshot s;
  s.id = id;
  s.asynchronous = true;
  s.state = state_from_string(h["state"]).value_or(JobState::Failed);
  s.stage = h["stage"].empty() ? "queued" : h["stage"];
  s.fraction = std::clamp(to_double(h["fraction"]), 0.0, 1.0);
  s.cancel_requested = h["cancel"] == "1";
  s.input_bytes = to_int(h["input_bytes"]);
  s.attempts = int(to_int(h["attempts"]));
  const std::int64_t created = to_int(h["created_ms"]), now = now_ms();
  const std::int64_t started = to_int(h["started_ms"], -1), finished = to_int(h["finished_ms"], -1);
  s.created_wall = std::chrono::system_clock::time_point(std::chrono::milliseconds(created));
  const std::int64_t end = finished >= 0 ? finished : now;
  s.queue_wait_s = double(std::max<std::int64_t>(0, (started >= 0 ? started : end) - created)) / 1000;
  s.run_s = started >= 0 ? double(std::max<std::int64_t>(0, end - started)) / 1000 : 0.0;
  s.error = problem_from_text(h["error"]);
  if (s.state == JobState::Succeeded && !h["output"].empty()) {
    json reports;
    auto out = output_from_text(h["output"], reports);
    if (result) out->bytes = *result;
    s.output = std::move(out);
    s.reports = std::move(reports);
    s.output_bytes = to_int(h["output_bytes"]);
  }
  return s;
}

}  // namespace mdn::http::redis
