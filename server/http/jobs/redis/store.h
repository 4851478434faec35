// The shared job store on Redis (--queue redis://host:port/db): any replica accepts a job, any
// replica's workers run it, any replica answers for it, and a replica that dies takes no
// accepted job with it. Built on Redis Streams with one consumer group, over Debian's hiredis
// (0.14, synchronous API, one connection per thread).
//
// Keys (prefix --queue-prefix, "mdn:" by default):
//   <p>queue               Stream; one entry {id} per job to run; consumer group "workers".
//   <p>job:<id>            Hash: state, stage, fraction, format, params (JSON), created_ms,
//                          started_ms, finished_ms, input_bytes, attempts, owner (consumer),
//                          cancel, error (problem JSON), output (result summary JSON),
//                          output_bytes, idem. Expires --result-ttl after the job finished.
//   <p>job:<id>:input      The request body; deleted when the job finishes.
//   <p>job:<id>:result     The result bytes; expires with the hash.
//   <p>idem:<key>          "<id>|<fingerprint>" of an Idempotency-Key; expires with its job.
//
// Life of a job. POST: one Lua script checks the idempotency key and the capacity, writes the
// hash and input and XADDs the id, so a job is either wholly accepted or not at all. A worker
// slot (one per --workers) waits with XREAD BLOCK (read-only) for a new entry, then one script
// XREADGROUPs it, marks the job running under this replica's consumer name and counts the
// attempt (one write, hence one fsync with appendfsync always), and the local WorkerPool runs it.
// Every 200 ms the slot reads the cancel flag and checks that the job is still its own (a
// read-only script); on each stage change and at least every quarter of the idle threshold it
// sends a heartbeat: the progress, and XCLAIM ... JUSTID, which resets the entry's idle time.
// A final script (run by a finisher thread, so the slot takes its next job meanwhile) stores
// result and state, XACKs and XDELs the entry, guarded
// by "still running and still mine", so a job overtaken by another replica is never stored
// twice. Entries idle longer than --queue-reclaim-idle (their worker died) are taken over with
// XAUTOCLAIM and run again, at most --queue-max-attempts runs in all; then the job fails.
//
// Redis unreachable: /readyz and the job routes answer 503 queue-unavailable with Retry-After,
// connections are re-made on the next use, a monitor pings every second; running jobs go on
// and store their result once Redis is back. Durability of accepted jobs is Redis's own
// (appendonly; see docker/README.md).
#pragma once

#include <memory>

#include "server/http/config.h"
#include "server/http/jobs/job_store.h"
#include "server/http/jobs/worker_pool.h"
#include "server/http/log.h"

namespace mdn::http {

// Starts the worker slots and the monitor; never fails because Redis is down (it keeps trying).
// Throws ConfigError when the URL is malformed or a limit exceeds what Redis can store.
std::unique_ptr<JobStore> make_redis_job_store(const ServerConfig& config, WorkerPool& worker_pool,
                                               std::shared_ptr<const EventLog> log);

}  // namespace mdn::http
