// The job codec: a job's Redis hash <-> JobSnapshot, and the stored forms of its error (a
// problem as JSON) and of its output summary (service/job_json.h). Pure functions of their
// arguments (but now_ms, the wall clock), no Redis needed: tests/server/http/jobs/redis/job_codec_test.cpp.
//
// Hash fields read: state, stage, fraction, cancel, input_bytes, attempts, created_ms,
// started_ms, finished_ms, error, output, output_bytes (store.h lists every key and field).
#pragma once

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "server/http/jobs/worker_pool.h"
#include "server/http/problem.h"

namespace mdn::http::redis {

std::int64_t now_ms();  // wall clock, ms since the epoch (what created_ms & co. hold)

std::string problem_text(const Problem& p);
// nullopt for ""; an unreadable text becomes a 500 internal problem.
std::optional<Problem> problem_from_text(const std::string& text);

// A finished job's output as stored (all but the bytes): output_to_json's document.
std::string output_text(const service::JobOutput& o);
// Its inverse; the rendered reports go to `reports`. Throws nlohmann::json::exception.
std::shared_ptr<service::JobOutput> output_from_text(const std::string& text, nlohmann::json& reports);

std::optional<JobState> state_from_string(std::string_view s);
// Lenient: "" or garbage give `fallback` / 0.
std::int64_t to_int(const std::string& s, std::int64_t fallback = 0);
double to_double(const std::string& s);

// The snapshot of job `id` from its hash; with `result`, a succeeded job's output carries those
// bytes. Times are measured against now_ms() while the job is unfinished.
JobSnapshot snapshot_from_hash(const std::string& id, std::map<std::string, std::string> h,
                               const std::optional<std::string>& result);

}  // namespace mdn::http::redis
