// The HTTP service: route table, handlers, CORS, auth, request ids, access logs and metrics,
// over cpp-httplib and the parts main() builds (ServiceParts, below): the metrics, the WorkerPool
// (this process's workers; synchronous jobs) and a JobStore (asynchronous jobs: in memory, or
// shared through Redis with --queue; job_store.h). The service never picks its store itself.
//
// Lifecycle: bind() -> serve() (blocks, on its own thread) ... begin_drain() -> wait_drained()
// -> stop(). Every method except serve() may be called from any thread.
#pragma once

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "server/http/config.h"
#include "server/http/jobs/job_store.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/log.h"
#include "server/http/metrics.h"

namespace mdn::http {

// The listening address cannot be bound (the port is in use, the host is not local, ...): what()
// says which and why. meshdenoise-server exits 3 on it.
class BindError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What the HTTP service runs on: the metrics, this process's worker pool (its workers run every
// job, synchronous or not) and the job store (where asynchronous jobs live). The composition
// root builds them (server/service_parts.h: make_service_parts); a test may build its own.
// Members are destroyed in reverse order: the store (which runs its jobs on the pool) first,
// then the pool (whose finish hook counts into the metrics), then the metrics.
struct ServiceParts {
  std::unique_ptr<Metrics> metrics;
  std::unique_ptr<WorkerPool> pool;
  std::unique_ptr<JobStore> store;
};

// One route: method and path template as in proto/openapi.yaml ("/v1/jobs/{id}").
struct RouteInfo {
  std::string method, path;
};

class HttpService {
 public:
  // Takes the parts (every member set; make_service_parts builds them from the configuration).
  // `log` receives access and job logs; it may be null.
  HttpService(const ServerConfig& config, std::shared_ptr<const EventLog> log, ServiceParts parts);
  ~HttpService();
  HttpService(const HttpService&) = delete;
  HttpService& operator=(const HttpService&) = delete;

  // Binds the listening socket (config.port, or any free port if 0) and returns the port.
  // Throws BindError if the address cannot be bound (a port in use is refused: no SO_REUSEPORT).
  int bind();
  // Accepts connections until stop(). Returns false if listening failed.
  bool serve();
  // SIGTERM: /readyz answers 503 and new jobs get 503; accepted jobs keep running.
  void begin_drain();
  // Waits until accepted jobs finished or the deadline (results not fetched yet do not hold it).
  bool wait_drained(Clock::time_point deadline);
  // Stops accepting connections, lets in-flight requests finish, and cancels what is left.
  void stop();

  WorkerPool& pool();
  // For the drain's log: the jobs queued or running here (queued synchronous ones, the memory
  // store's; not those running synchronously), and the succeeded results nobody fetched.
  std::vector<JobSnapshot> unfinished();
  int unfetched_results();

  // Every route the server answers (besides OPTIONS preflights), for contract tests.
  static std::vector<RouteInfo> route_table();

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace mdn::http
