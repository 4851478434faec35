#include "server/http/job_routes.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string_view>

#include "server/http/connection_probe.h"
#include "server/http/job_resource.h"
#include "server/http/problem.h"
#include "server/params_json.h"

namespace mdn::http {
namespace {

constexpr double kMaxWaitS = 60;  // the longest ?wait= of a long poll

JobSnapshot found(const std::string& id, std::optional<JobSnapshot> job) {
  if (!job)
    throw HttpError(job_not_found(id));
  return std::move(*job);
}

}  // namespace

JobRoutes::JobRoutes(const ServerConfig& config, std::shared_ptr<const EventLog> log, Metrics& metrics, JobQueue& queue,
                     JobStore& store)
    : log_(std::move(log)),
      queue_(queue),
      store_(store),
      bodies_(config.max_body_bytes, std::min(config.read_timeout_s, config.body_stall_timeout_s), metrics),
      max_waiting_(std::max(1, config.effective_io_threads() / 2)) {}

JobSnapshot JobRoutes::find_job(Context& ctx, bool with_result) {
  const std::string id = ctx.req.matches[1];
  return found(id, store_.find(id, with_result));
}

// GET /v1/jobs/{id}?wait=S (long poll): answers when the job has finished, or after S seconds
// (0 to kMaxWaitS) with its current state. At most half the HTTP threads wait at once; beyond
// that a request answers at once (a client's next poll waits again).
JobSnapshot JobRoutes::wait_job(Context& ctx) {
  const std::string text = ctx.req.get_param_value("wait");
  double seconds = -1;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), seconds);
  if (ec != std::errc() || end != text.data() + text.size() || !(seconds >= 0 && seconds <= kMaxWaitS)) {
    Problem p = make_problem(ProblemType::InvalidQuery, "wait must be a number of seconds from 0 to " + std::to_string(int(kMaxWaitS)) +
                                 " (got '" + header_safe(text) + "')");
    p.extensions["field"] = "wait";
    p.extensions["minimum"] = 0;
    p.extensions["maximum"] = kMaxWaitS;
    throw HttpError(std::move(p));
  }
  if (seconds == 0) return find_job(ctx, false);
  const int waiting = waiting_.fetch_add(1);
  struct Leave {
    std::atomic<int>& n;
    ~Leave() { --n; }
  } leave{waiting_};
  if (waiting >= max_waiting_) return find_job(ctx, false);
  const std::string id = ctx.req.matches[1];
  return found(id, store_.wait_finished(
                       id, Clock::now() + std::chrono::microseconds(std::int64_t(std::llround(seconds * 1e6)))));
}

void JobRoutes::denoise(Context& ctx) {
  service::JobInput input = bodies_.read_job_input(ctx);
  std::shared_ptr<Job> job = queue_.submit(std::move(input), false).job;
  const auto probe = ConnectionProbe::current(ctx.req.remote_port);
  while (!job->wait_for(std::chrono::milliseconds(50))) {
    if (probe && probe->peer_gone()) {
      queue_.cancel(job);
      if (log_) log_->info("client_gone", {{"request_id", ctx.request_id}, {"job_id", job->id()}});
      ctx.res.status = 499;  // nginx's "client closed request": for the access log only
      return;
    }
  }
  const JobSnapshot s = job->snapshot();
  if (s.state == JobState::Succeeded) return write_result(ctx, s);
  throw HttpError(s.error.value_or(make_problem(ProblemType::Internal, "the job failed")));
}

void JobRoutes::create_job(Context& ctx) {
  std::optional<std::string> key;
  if (ctx.req.has_header("Idempotency-Key")) {
    key = ctx.req.get_header_value("Idempotency-Key");
    if (key->empty() || key->size() > 255 || !std::all_of(key->begin(), key->end(), [](char c) {
          return c > 0x20 && c < 0x7f;
        }))
      throw HttpError(make_problem(ProblemType::BadIdempotencyKey, "Idempotency-Key must be 1 to 255 visible ASCII characters"));
  }
  service::JobInput input = bodies_.read_job_input(ctx);
  // What can be refused at once is refused before the job is accepted (not 202 and a failed
  // job later): parameters that do not validate (400), a body that is not the declared
  // container (415).
  service::validate(input.params);
  if (const auto sniffed = io::sniff_format(input.bytes); sniffed != input.format)
    throw HttpError(unsupported_media_type(
        "the body is not a " + std::string(io::to_string(input.format)) + " file" +
        (sniffed ? " (it looks like " + std::string(io::to_string(*sniffed)) + ")" : std::string(" (no mesh format recognised)"))));
  std::string fingerprint;
  if (key) {
    // Same key and same (body, format, effective parameters) -> same job.
    fingerprint = std::string(io::to_string(input.format)) + "|" + service::to_json(input.params).dump() + "|" +
                  std::to_string(input.bytes.size()) + "|" +
                  std::to_string(std::hash<std::string_view>{}(input.bytes));
  }
  auto submitted = store_.submit(std::move(input), key, fingerprint);
  const JobSnapshot& s = submitted.job;
  if (submitted.replayed) ctx.res.set_header("Idempotent-Replayed", "true");
  ctx.res.set_header("Location", "/v1/jobs/" + s.id);
  ctx.res.set_header("Retry-After", "1");
  set_json(ctx.res, job_json(s, ctx.request_id), 202);
}

void JobRoutes::get_job(Context& ctx) {
  const JobSnapshot s = ctx.req.has_param("wait") ? wait_job(ctx) : find_job(ctx, false);
  if (!is_terminal(s.state)) ctx.res.set_header("Retry-After", "1");
  set_json(ctx.res, job_json(s, ctx.request_id));
}

void JobRoutes::get_result(Context& ctx) {
  const JobSnapshot s = find_job(ctx, true);
  if (s.state == JobState::Succeeded) {
    write_result(ctx, s);
    store_.result_fetched(s.id);
    return;
  }
  Problem p;
  if (!is_terminal(s.state)) {
    p = make_problem(ProblemType::JobNotFinished, "the job is " + std::string(to_string(s.state)));
    p.retry_after_s = 1;
  } else {
    p = make_problem(s.state == JobState::Cancelled ? ProblemType::JobCancelled : ProblemType::JobFailed,
                     "the job " + std::string(to_string(s.state)) + (s.error ? ": " + s.error->detail : ""));
    if (s.error) p.extensions["job_error"] = s.error->to_json("/v1/jobs/" + s.id, ctx.request_id);
  }
  p.extensions["job_state"] = to_string(s.state);
  throw HttpError(p);
}

void JobRoutes::delete_job(Context& ctx) {
  const std::string id = ctx.req.matches[1];
  const JobStore::CancelResult r = store_.cancel(id);
  switch (r.outcome) {
    case JobQueue::CancelOutcome::NotFound:
      throw HttpError(job_not_found(id));
    case JobQueue::CancelOutcome::CancelledQueued:
      return set_json(ctx.res, job_json(r.job, ctx.request_id), 200);
    case JobQueue::CancelOutcome::CancelRequested:
      return set_json(ctx.res, job_json(r.job, ctx.request_id), 202);
    case JobQueue::CancelOutcome::Removed:
      ctx.res.status = 204;
      return;
  }
}

}  // namespace mdn::http
