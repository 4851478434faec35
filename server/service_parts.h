// The composition root's choice of parts (ServiceParts, http_server.h): the metrics, this
// process's worker pool and the job store config.queue names, memory or Redis. main() builds
// them here and hands them to HttpService; a test builds its own, for instance a fake JobStore,
// so handlers can be tested without Redis. The only file that names the Redis store
// (server/http/jobs/redis/) is service_parts.cpp.
#pragma once

#include <memory>

#include "server/http/config.h"
#include "server/http/http_server.h"
#include "server/http/jobs/memory_job_store.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/log.h"

namespace mdn::http {

// The pool's options from the configuration (workers, capacity, limits, time limit), and the
// memory store's (result lifetime, stored jobs).
WorkerPoolOptions make_pool_options(const ServerConfig& config);
MemoryJobStoreOptions make_memory_store_options(const ServerConfig& config);

// The metrics, a pool whose finished jobs are counted there and logged to `log` (may be
// null), and the store config.queue names (MemoryJobStore, or the Redis store, which starts
// its worker slots at once). Throws ConfigError as make_redis_job_store does.
ServiceParts make_service_parts(const ServerConfig& config, std::shared_ptr<const EventLog> log);

}  // namespace mdn::http
