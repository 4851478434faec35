#include "server/http/routes/service_routes.h"

#include <algorithm>
#include <string>
#include <utility>

#include "core/params.h"
#include "server/http/embedded.h"
#include "server/http/problem.h"
#include "server/http/routes/web_routes.h"
#include "service/params_json.h"

namespace mdn::http {

using nlohmann::json;

ServiceRoutes::ServiceRoutes(const ServerConfig& config, Metrics& metrics, WorkerPool& pool, JobStore& store,
                             const JobRoutes& jobs, std::function<ConnectionCounts()> connections)
    : config_(config), metrics_(metrics), pool_(pool), store_(store), jobs_(jobs), connections_(std::move(connections)) {}

void ServiceRoutes::healthz(Context& ctx) { set_json(ctx.res, {{"status", "ok"}}); }

void ServiceRoutes::readyz(Context& ctx) {
  if (pool_.draining()) {
    Problem p = make_problem(ProblemType::Draining, "the server is shutting down");
    p.retry_after_s = 5;
    throw HttpError(p);
  }
  if (pool_.saturated()) {
    Problem p = make_problem(ProblemType::QueueFull, "the job queue is full");
    p.retry_after_s = pool_.retry_after_s();
    throw HttpError(p);
  }
  if (auto p = store_.unavailable()) throw HttpError(*p);
  set_json(ctx.res, {{"status", "ready"},
                     {"job_store", store_.kind()},
                     {"queued", pool_.queued()},
                     {"running", pool_.running()},
                     {"capacity", pool_.capacity()},
                     {"workers", pool_.workers()}});
}

void ServiceRoutes::metrics_route(Context& ctx) {
  ctx.res.status = 200;
  std::string text = metrics_.render({pool_.queued(), pool_.capacity(), pool_.running(), pool_.workers(),
                                     pool_.draining(), std::max(0, jobs_.waiting()), jobs_.queued_bytes().total(),
                                     jobs_.queued_bytes().total_limit()});
  store_.render_metrics(text);
  render_connection_metrics(text);
  ctx.res.set_content(text, "text/plain; version=0.0.4; charset=utf-8");
}

// The connection gate's state and the connections it closed to protect the service.
void ServiceRoutes::render_connection_metrics(std::string& out) const {
  const ConnectionCounts c = connections_();
  out += "# HELP mdn_http_connections Client connections: open, waiting for a request (no thread), queued for a thread.\n"
         "# TYPE mdn_http_connections gauge\n";
  out += "mdn_http_connections{state=\"open\"} " + std::to_string(c.open) + "\n";
  out += "mdn_http_connections{state=\"waiting\"} " + std::to_string(c.parked) + "\n";
  out += "mdn_http_connections{state=\"queued\"} " + std::to_string(c.queued) + "\n";
  out += "# HELP mdn_http_connections_closed_total Connections closed by the gate: refused at a per-client or total cap, "
         "evicted while waiting, head not complete in time, head over the framing limits, no thread in time.\n"
         "# TYPE mdn_http_connections_closed_total counter\n";
  const std::pair<const char*, std::int64_t> reasons[] = {{"client_limit", c.refused_client}, {"total_limit", c.refused_total},
                                                          {"evicted", c.evicted},           {"head_timeout", c.head_timeouts},
                                                          {"head_refused", c.head_refusals}, {"queue_timeout", c.queue_timeouts}};
  for (const auto& [reason, n] : reasons)
    out += std::string("mdn_http_connections_closed_total{reason=\"") + reason + "\"} " + std::to_string(n) + "\n";
}

void ServiceRoutes::openapi(Context& ctx) {
  ctx.res.status = 200;
  const auto doc = embedded::openapi_yaml();
  ctx.res.set_content(doc.data(), doc.size(), "application/yaml");
}

void ServiceRoutes::params(Context& ctx) {
  json specs = json::array();
  for (const ParamSpec& s : param_specs()) {
    specs.push_back({{"name", s.name},
                     {"type", s.integer ? "integer" : "number"},
                     {"default", s.default_value()},
                     {"minimum", s.min},
                     {"maximum", s.max},
                     {"paper_minimum", s.paper_min},
                     {"paper_maximum", s.paper_max},
                     {"unit", s.unit},
                     {"equation", s.equation},
                     {"description", s.description}});
  }
  set_json(ctx.res, {{"defaults", service::to_json(service::JobParams{})},
                     {"parameters", specs},
                     {"schema", json::parse(embedded::params_schema_json())}});
}

void ServiceRoutes::params_schema(Context& ctx) {
  ctx.res.status = 200;
  const auto doc = embedded::params_schema_json();
  ctx.res.set_content(doc.data(), doc.size(), "application/schema+json");
}

void ServiceRoutes::report_schema(Context& ctx) {
  ctx.res.status = 200;
  const auto doc = embedded::report_schema_json();
  ctx.res.set_content(doc.data(), doc.size(), "application/schema+json");
}

// GET / and GET /web/{path}: the web page (web_routes.h), unless --web off.
void ServiceRoutes::web_page(Context& ctx) {
  if (!config_.web)
    throw HttpError(make_problem(ProblemType::NotFound, "no route GET " + ctx.req.path + " (--web off)"));
  serve_web_file(ctx.req, ctx.res, ctx.req.matches.size() > 1 ? ctx.req.matches[1] : "index.html");
}

}  // namespace mdn::http
