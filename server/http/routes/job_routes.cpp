#include "server/http/routes/job_routes.h"

#include <algorithm>
#include <charconv>
#include <chrono>
#include <cmath>
#include <functional>
#include <optional>
#include <string_view>

#include "server/http/transport/connection_probe.h"
#include "server/http/routes/job_resource.h"
#include "server/http/problem.h"
#include "server/http/secure_random.h"
#include "service/params_json.h"

namespace mdn::http {
namespace {

constexpr double kMaxWaitS = 60;  // the longest ?wait= of a long poll

JobSnapshot found(const std::string& id, std::optional<JobSnapshot> job) {
  if (!job)
    throw HttpError(job_not_found(id));
  return std::move(*job);
}

}  // namespace

JobRoutes::JobRoutes(const ServerConfig& config, std::shared_ptr<const EventLog> log, Metrics& metrics, WorkerPool& pool,
                     JobStore& store)
    : log_(std::move(log)),
      pool_(pool),
      store_(store),
      keys_(config.api_keys),
      proxies_(config.trusted_proxies),
      sync_start_timeout_s_(config.sync_start_timeout_s),
      bodies_(config.max_body_bytes, std::min(config.read_timeout_s, config.body_stall_timeout_s), config.body_timeout_s, metrics),
      queued_bytes_(config.effective_max_queued_bytes(), config.effective_client_max_queued_bytes()),
      max_waiting_(std::max(1, config.effective_io_threads() / 2)) {}

const ApiKey* JobRoutes::client_of(const Context& ctx) const {
  if (!keys_.enabled()) return nullptr;
  const ApiKey* client = keys_.client(ctx.req.get_header_value("Authorization"));
  // The pre-routing check let only known keys through to /v1.
  if (client == nullptr) throw HttpError(make_problem(ProblemType::Unauthorized, "this server requires an API key"));
  return client;
}

std::string JobRoutes::share_of(const Context& ctx) const {
  if (const ApiKey* client = client_of(ctx)) return "key:" + client->name;
  // Behind a proxy of --trusted-proxies, the address it forwards for (decision 86); behind any
  // other, every client is the proxy's address: one share (docker/README.md).
  return "addr:" + proxies_.client_address_of(ctx.req.remote_addr, ctx.req.headers);
}

std::pair<service::JobInput, QueuedBytes::Hold> JobRoutes::read_counted_input(Context& ctx, const std::string& share) {
  if (const auto declared = BodyReader::declared_length(ctx.req)) {
    try {
      queued_bytes_.check(share, *declared, pool_.retry_after_s());
    } catch (const HttpError&) {
      close_after_response(ctx.res);  // the body stays unread
      throw;
    }
  }
  service::JobInput input = bodies_.read_job_input(ctx);
  QueuedBytes::Hold hold = queued_bytes_.reserve(share, std::int64_t(input.bytes.size()), pool_.retry_after_s());
  return {std::move(input), std::move(hold)};
}

std::string JobRoutes::store_id_of(const Context& ctx) const {
  const std::string id = ctx.req.matches[1];
  const ApiKey* client = client_of(ctx);
  if (client == nullptr) return id;
  // Another client's job, or no job: the same 404.
  const auto own = keys_.store_id(*client, id);
  if (!own) throw HttpError(job_not_found(id));
  return *own;
}

std::string JobRoutes::public_id(const Context& ctx, const std::string& store_id) const {
  const ApiKey* client = client_of(ctx);
  return client == nullptr ? store_id : keys_.public_id(*client, store_id);
}

JobSnapshot JobRoutes::find_job(Context& ctx, bool with_result) {
  const std::string id = store_id_of(ctx);
  JobSnapshot s = found(ctx.req.matches[1], store_.find(id, with_result));
  s.id = public_id(ctx, s.id);
  return s;
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
  const std::string id = store_id_of(ctx);
  JobSnapshot s = found(ctx.req.matches[1], store_.wait_finished(id, Clock::now() + std::chrono::microseconds(std::int64_t(
                                                                                    std::llround(seconds * 1e6)))));
  s.id = public_id(ctx, s.id);
  return s;
}

void JobRoutes::denoise(Context& ctx) {
  auto [input, queued] = read_counted_input(ctx, share_of(ctx));
  std::shared_ptr<Job> job = pool_.submit(new_job_id(), std::move(input), {.asynchronous = false, .queued_bytes = std::move(queued)});
  const auto probe = ConnectionProbe::current(ctx.req.remote_port);
  const auto start_by = Clock::now() + std::chrono::milliseconds(std::int64_t(sync_start_timeout_s_ * 1000));
  while (!job->wait_for(std::chrono::milliseconds(50))) {
    // A synchronous request whose job found no worker in time is answered 503 (never left
    // hanging behind a queue that does not move); the job is withdrawn.
    if (Clock::now() >= start_by && job->snapshot().state == JobState::Queued) {
      pool_.cancel(job);
      Problem p = make_problem(ProblemType::QueueFull, "no worker was free to start this job within " +
                                                           std::to_string(int(sync_start_timeout_s_)) + " s");
      p.retry_after_s = pool_.retry_after_s();
      throw HttpError(std::move(p));
    }
    if (probe && probe->peer_gone()) {
      pool_.cancel(job);
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
  const std::string share = share_of(ctx);
  auto [input, queued] = read_counted_input(ctx, share);
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
  // Idempotency keys are the client's own: another client's same key is another job.
  if (key)
    if (const ApiKey* client = client_of(ctx)) key = client->name + ":" + *key;
  auto submitted = store_.submit(std::move(input), key, fingerprint, {share, std::move(queued)});
  JobSnapshot& s = submitted.job;
  s.id = public_id(ctx, s.id);
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
    store_.result_fetched(store_id_of(ctx));
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
  JobStore::CancelResult r = store_.cancel(store_id_of(ctx));
  r.job.id = public_id(ctx, r.job.id);
  switch (r.outcome) {
    case JobStore::CancelOutcome::NotFound:
      throw HttpError(job_not_found(ctx.req.matches[1]));
    case JobStore::CancelOutcome::CancelledQueued:
      return set_json(ctx.res, job_json(r.job, ctx.request_id), 200);
    case JobStore::CancelOutcome::CancelRequested:
      return set_json(ctx.res, job_json(r.job, ctx.request_id), 202);
    case JobStore::CancelOutcome::Removed:
      ctx.res.status = 204;
      return;
  }
}

}  // namespace mdn::http
