// What the connection gate (connection_gate.h) shares with those that do not include it: its
// options, its counts (for /metrics) and why the body read of this thread's request failed (for
// the body reader's 408). The gate owns these types; no cpp-httplib here.
#pragma once

#include <chrono>
#include <cstdint>

namespace mdn::http {

struct GateOptions {
  int io_threads = 8;               // threads serving requests (the main lane)
  int probe_threads = 2;            // threads serving GET /healthz, /readyz, /metrics only
  double header_timeout_s = 10;     // a request head must be complete this long after it may start
  double keep_alive_timeout_s = 2;  // an idle connection between requests is closed after this
  int keep_alive_max = 100;         // requests on one connection
  double read_timeout_s = 10;       // largest gap between bytes of a body
  double body_timeout_s = 300;      // a whole body
  // The body's minimum rate (decision 63, in the manner of mod_reqtimeout's MinRate): after
  // body_rate_grace_s, a body must have sent body_min_rate bytes per second since it began,
  // however steadily it trickles; then 408 and close. 0: no floor. Flags --body-min-rate and
  // --body-rate-grace (config.h).
  double body_min_rate = 500;
  double body_rate_grace_s = 10;
  double write_timeout_s = 30;
  int max_connections_per_client = 64;
  int max_connections = 2048;
  // Main-lane threads one address may hold at once; its other ready requests wait (and past
  // kMaxQueueWait are answered 503), so one client's slow bodies or long synchronous jobs
  // cannot take every thread. io_threads: no cap (behind a proxy, every client is one address).
  int threads_per_client = 4;
};

// The longest a request whose head has arrived waits for a thread before it is answered 503.
inline constexpr std::chrono::seconds kMaxQueueWait{10};

// Why the last read of this thread's request body failed (the gate's stream sets it): a gap
// longer than the read timeout, the body's total deadline, a body slower than the minimum rate,
// or chunked framing that breaks RFC 9112 7.1 or the line limits (request_framing.h).
enum class BodyReadTimeout { None, Stall, BodyDeadline, TooSlow, BadFraming };
BodyReadTimeout last_body_read_timeout();  // the gate's (ConnectionGate::last_read_timeout)

// The connection gate's counts (ConnectionGate::counts(), for /metrics).
struct ConnectionCounts {
  std::int64_t open = 0, parked = 0, queued = 0;
  std::int64_t refused_client = 0, refused_total = 0, evicted = 0, head_timeouts = 0, queue_timeouts = 0;
  std::int64_t head_refusals = 0;  // heads over the line / head limits or that cannot be framed
};

}  // namespace mdn::http
