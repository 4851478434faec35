// The job routes: POST /v1/denoise (synchronous: the answer is the result), POST /v1/jobs
// (asynchronous, with Idempotency-Key), GET and DELETE /v1/jobs/{id} (GET with ?wait=: a long
// poll), GET /v1/jobs/{id}/result. The handlers of http_server.cpp's route table; the server
// holds them as one of its parts (composition: its table names which part answers).
//
// Thread-safety contract: the handlers run on the HTTP threads, any number at once; the queue,
// the store and the body reader are thread-safe, and the count of long polls waiting is an atomic.
#pragma once

#include <atomic>
#include <memory>
#include <string>

#include "server/http/jobs/job_store.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/routes/api_keys.h"
#include "server/http/config.h"
#include "server/http/log.h"
#include "server/http/metrics.h"
#include "server/http/routes/request_body.h"
#include "server/http/routes/http_support.h"

namespace mdn::http {

class JobRoutes {
 public:
  JobRoutes(const ServerConfig& config, std::shared_ptr<const EventLog> log, Metrics& metrics, WorkerPool& pool,
            JobStore& store);

  void denoise(Context& ctx);
  void create_job(Context& ctx);
  void get_job(Context& ctx);
  void get_result(Context& ctx);
  void delete_job(Context& ctx);

  int waiting() const { return waiting_; }  // long polls waiting now
  const QueuedBytes& queued_bytes() const { return queued_bytes_; }
  const ClientKeys& client_keys() const { return keys_; }

 private:
  JobSnapshot find_job(Context& ctx, bool with_result);
  JobSnapshot wait_job(Context& ctx);
  // --api-keys: the store's id behind the path's job id if the job is the caller's (else 404),
  // and the id the caller sees for a store id. Without keys both are the identity.
  std::string store_id_of(const Context& ctx) const;
  std::string public_id(const Context& ctx, const std::string& store_id) const;
  const ApiKey* client_of(const Context& ctx) const;
  // Whose share a request counts against (decision 78): "key:<name>" of its --api-keys client,
  // else "addr:<client address>" (the peer, or from a --trusted-proxies peer its X-Forwarded-For).
  std::string share_of(const Context& ctx) const;
  // The job body of this request, counted in the queued bytes of `share` (decision 79): a
  // declared length over a share is refused (429 or 503, and the connection closed) before the
  // body is read, the body read is counted once it has arrived.
  std::pair<service::JobInput, QueuedBytes::Hold> read_counted_input(Context& ctx, const std::string& share);

  const std::shared_ptr<const EventLog> log_;
  WorkerPool& pool_;
  JobStore& store_;
  const ClientKeys keys_;
  const TrustedProxies proxies_;
  const double sync_start_timeout_s_;  // POST /v1/denoise: longest wait for a worker, then 503
  BodyReader bodies_;
  QueuedBytes queued_bytes_;
  const int max_waiting_;  // long polls at once: half the HTTP threads
  std::atomic<int> waiting_{0};
};

}  // namespace mdn::http
