#include "server/service_parts.h"

#include <string>
#include <utility>

#include "server/http/jobs/redis/store.h"

namespace mdn::http {

WorkerPoolOptions make_pool_options(const ServerConfig& c) {
  WorkerPoolOptions o;
  o.workers = c.effective_workers();
  o.threads_per_job = c.threads_per_job;
  o.capacity = c.queue_capacity;
  o.time_limit = std::chrono::milliseconds(std::int64_t(c.job_time_limit_s * 1000));
  o.limits = decode_limits(c);
  return o;
}

MemoryJobStoreOptions make_memory_store_options(const ServerConfig& c) {
  MemoryJobStoreOptions o;
  o.result_ttl = std::chrono::milliseconds(std::int64_t(c.result_ttl_s * 1000));
  o.max_stored = c.max_stored_jobs;
  o.max_stored_per_client = c.effective_client_max_stored_jobs();
  return o;
}

ServiceParts make_service_parts(const ServerConfig& config, std::shared_ptr<const EventLog> log) {
  ServiceParts parts;
  parts.metrics = std::make_unique<Metrics>();
  Metrics* metrics = parts.metrics.get();
  parts.pool = std::make_unique<WorkerPool>(make_pool_options(config), [metrics, log](const JobSnapshot& s) {
    metrics->job_finished(std::string(to_string(s.state)), s.queue_wait_s, s.run_s);
    if (!log) return;
    nlohmann::json fields = {{"job_id", s.id}, {"state", to_string(s.state)}, {"queue_wait_s", s.queue_wait_s},
                             {"run_s", s.run_s}, {"async", s.asynchronous}};
    if (s.error) fields["error"] = s.error->type, fields["detail"] = s.error->detail;
    log->info("job_finished", fields);
  });
  if (config.queue)
    parts.store = make_redis_job_store(config, *parts.pool, std::move(log));
  else
    parts.store = std::make_unique<MemoryJobStore>(*parts.pool, make_memory_store_options(config));
  return parts;
}

}  // namespace mdn::http
