// The job routes: POST /v1/denoise (synchronous: the answer is the result), POST /v1/jobs
// (asynchronous, with Idempotency-Key), GET and DELETE /v1/jobs/{id} (GET with ?wait=: a long
// poll), GET /v1/jobs/{id}/result. The handlers of http_server.cpp's route table; the server
// inherits them (its table names them as its own).
//
// Thread-safety contract: the handlers run on the HTTP threads, any number at once; the queue,
// the store and the body reader are thread-safe, and the count of long polls waiting is an atomic.
#pragma once

#include <atomic>
#include <memory>
#include <string>

// job_queue.h (Eigen, through the core) before httplib.h: see request_body.h.
#include "server/http/job_store.h"
#include "server/http/config.h"
#include "server/http/log.h"
#include "server/http/metrics.h"
#include "server/http/request_body.h"
#include "server/http/http_support.h"

namespace mdn::http {

class JobRoutes {
 public:
  JobRoutes(const ServerConfig& config, std::shared_ptr<const EventLog> log, Metrics& metrics, JobQueue& queue,
            JobStore& store);

  void denoise(Context& ctx);
  void create_job(Context& ctx);
  void get_job(Context& ctx);
  void get_result(Context& ctx);
  void delete_job(Context& ctx);

  int waiting() const { return waiting_; }  // long polls waiting now

 private:
  JobSnapshot find_job(Context& ctx, bool with_result);
  JobSnapshot wait_job(Context& ctx);

  const std::shared_ptr<const EventLog> log_;
  JobQueue& queue_;
  JobStore& store_;
  BodyReader bodies_;
  const int max_waiting_;  // long polls at once: half the HTTP threads
  std::atomic<int> waiting_{0};
};

}  // namespace mdn::http
