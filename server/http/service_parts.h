// What the HTTP service runs on: the metrics, this process's worker pool (its workers run every
// job, synchronous or not) and the job store (where asynchronous jobs live: memory or Redis).
// main() builds them with make_service_parts and hands them to HttpService; a test builds its
// own, for instance a fake JobStore, so handlers can be tested without Redis.
#pragma once

#include <memory>

#include "server/http/config.h"
#include "server/http/job_store.h"
#include "server/http/memory_job_store.h"
#include "server/http/worker_pool.h"
#include "server/http/log.h"
#include "server/http/metrics.h"

namespace mdn::http {

// Members are destroyed in reverse order: the store (which runs its jobs on the pool) first,
// then the pool (whose finish hook counts into the metrics), then the metrics.
struct ServiceParts {
  std::unique_ptr<Metrics> metrics;
  std::unique_ptr<WorkerPool> pool;
  std::unique_ptr<JobStore> store;
};

// The pool's options from the configuration (workers, capacity, limits, time limit), and the
// memory store's (result lifetime, stored jobs).
WorkerPoolOptions make_pool_options(const ServerConfig& config);
MemoryJobStoreOptions make_memory_store_options(const ServerConfig& config);

// The metrics, a pool whose finished jobs are counted there and logged to `log` (may be
// null), and the store config.queue names (MemoryJobStore, or the Redis store, which starts
// its worker slots at once). Throws ConfigError as make_redis_job_store does.
ServiceParts make_service_parts(const ServerConfig& config, std::shared_ptr<const EventLog> log);

}  // namespace mdn::http
