// The service's own routes: GET /healthz, /readyz, /metrics, /openapi.yaml, /v1/params,
// /v1/params/schema, /v1/report/schema and the web page (GET /, /web/{path}). The handlers of
// http_server.cpp's route table, a part the server holds beside the job routes (job_routes.h).
//
// Thread-safety contract: the handlers run on the HTTP threads, any number at once; what they
// read (queue, store, metrics, the connection gate's counts) is thread-safe.
#pragma once

#include <functional>
#include <string>

#include "server/http/jobs/job_store.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/config.h"
#include "server/http/transport/gate_types.h"
#include "server/http/routes/http_support.h"
#include "server/http/routes/job_routes.h"
#include "server/http/metrics.h"

namespace mdn::http {

class ServiceRoutes {
 public:
  // `connections` reads the connection gate's counts for /metrics.
  ServiceRoutes(const ServerConfig& config, Metrics& metrics, WorkerPool& pool, JobStore& store, const JobRoutes& jobs,
                std::function<ConnectionCounts()> connections);

  void healthz(Context& ctx);
  void readyz(Context& ctx);
  void metrics_route(Context& ctx);
  void openapi(Context& ctx);
  void params(Context& ctx);
  void params_schema(Context& ctx);
  void report_schema(Context& ctx);
  void web_page(Context& ctx);

 private:
  // The connection gate's state and the connections it closed to protect the service.
  void render_connection_metrics(std::string& out) const;

  const ServerConfig& config_;
  Metrics& metrics_;
  WorkerPool& pool_;
  JobStore& store_;
  const JobRoutes& jobs_;
  const std::function<ConnectionCounts()> connections_;
};

}  // namespace mdn::http
