// The one JSON view of a job's output, shared by the CLI's --report, the HTTP job and result
// resources and the Redis store's summary. Its shape is proto/report.schema.json:
//   { "format", "compression", "media_type", "bytes", "vertices", "faces", "params": to_json(effective),
//     "notes": [...], "reports": [ report_to_json(r) per surface ],
//     "timings_ms": { kTimingFields' names } }
// Timings are wall-clock and vary between runs; everything else is deterministic.
#pragma once

#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

#include "service/job_runner.h"

namespace mdn::service {

// One surface: fold_ratio, cluster_area_ratio, region_*, "mode", "params" (what ran: the six
// parameters and region_mode, as a manual-mode params object) and, in auto and search modes,
// "measures" and "choice" (core/auto/choice.h).
nlohmann::json report_to_json(const DenoiseReport& report);
nlohmann::json reports_to_json(const std::vector<DenoiseReport>& reports);

nlohmann::json timings_to_json(const JobTimings& timings);
// Missing keys read as 0; throws nlohmann::json::exception on a non-number.
JobTimings timings_from_json(const nlohmann::json& j);

// The output description. `bytes` is the result's size and `reports` the rendered reports:
// the Redis store keeps both without the result's bytes or the DenoiseReport structs.
nlohmann::json output_to_json(const JobOutput& output, std::int64_t bytes, nlohmann::json reports);
// Of a finished job that still holds its bytes and reports.
nlohmann::json output_to_json(const JobOutput& output);

// The inverse of output_to_json: everything but the bytes and the reports (left empty); the
// rendered reports go to `reports`, the size to `bytes`. Throws nlohmann::json::exception or
// io's errors on a document output_to_json did not write.
JobOutput output_from_json(const nlohmann::json& j, nlohmann::json& reports, std::int64_t& bytes);

}  // namespace mdn::service
