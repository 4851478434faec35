// What the job routes answer: a job's JSON resource (GET /v1/jobs/{id}), a finished job's
// result with its headers (GET /v1/jobs/{id}/result, POST /v1/denoise), the per-surface reports
// and the Server-Timing header, all over the one JSON view of the output (service/job_json.h).
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "server/http/jobs/job.h"
#include "server/http/routes/http_support.h"

namespace mdn::http {

// One report per surface: what ran (auto mode: the chosen parameters and the measurements).
nlohmann::json reports_json(const JobSnapshot& s);
// The job's output without its bytes; "bytes" is the result's size.
nlohmann::json output_summary(const JobSnapshot& s);
// Server-Timing (W3C): queue wait, the job's steps grouped as kTimingFields says, total.
std::string server_timing(const JobSnapshot& s);
// The job resource; `request_id` goes into an error's problem.
nlohmann::json job_json(const JobSnapshot& s, const std::string& request_id);
// A succeeded job's bytes and X-Denoise-* / Server-Timing headers; a single byte range is
// honoured (206), an unsatisfiable one throws HttpError 416.
void write_result(Context& ctx, const JobSnapshot& s);

}  // namespace mdn::http
