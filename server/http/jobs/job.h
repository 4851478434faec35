// A job as everyone outside the worker pool sees it: its state and a consistent snapshot of
// it (what the job resource renders, what a store keeps and hands back). The pool's own run
// handle, Job, is in worker_pool.h; a store's interface in job_store.h.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "server/http/problem.h"
#include "service/job_runner.h"

namespace mdn::http {

using Clock = std::chrono::steady_clock;

enum class JobState { Queued, Running, Succeeded, Failed, Cancelled };
std::string_view to_string(JobState state);  // "queued", "running", ...
inline bool is_terminal(JobState s) { return s == JobState::Succeeded || s == JobState::Failed || s == JobState::Cancelled; }

// A consistent copy of a job's public state.
struct JobSnapshot {
  std::string id;
  JobState state = JobState::Queued;
  std::string stage = "queued";  // "queued", "decode", a core Stage name, "done"
  double fraction = 0;           // of the stage, [0, 1]
  bool cancel_requested = false;
  bool asynchronous = false;
  std::int64_t input_bytes = 0;
  std::chrono::system_clock::time_point created_wall;
  double queue_wait_s = 0;  // so far, or until it started
  double run_s = 0;         // so far, or until it finished
  std::optional<Problem> error;                          // Failed (and Cancelled: why)
  // Succeeded. The shared job store (Redis) fills `output` without its bytes unless the result
  // itself was asked for; output_bytes is the result's size either way.
  std::shared_ptr<const service::JobOutput> output;
  std::int64_t output_bytes = 0;
  // The shared store: each surface's report as the worker rendered it (service::report_to_json);
  // `output` then has no reports of its own. Unset: render output->reports.
  std::optional<nlohmann::json> reports;
  int attempts = 0;  // runs started (Redis: more than 1 after a takeover); 0 while queued
  std::optional<int> jobs_ahead;  // Queued, where the store knows it (memory): jobs to start first
};

}  // namespace mdn::http
