// Connections one client cannot exhaust (issue 32): cpp-httplib 0.11.4 serves a connection on
// one pool thread from its accept to its close, so 1,000 idle connections, or 20 that send one
// header byte every 3 s, held every thread and /healthz went unanswered. The gate changes who
// waits:
//
//   accept -> admit(): at --max-connections-per-client (per source address) or
//             --max-connections, the oldest connection still waiting for bytes is closed to
//             make room; if every one is busy with a request -> "503, Retry-After" and close.
//          -> parked in the gate's epoll until a whole request head ("\r\n\r\n") has arrived,
//             read into the connection's own buffer; a head not complete --header-timeout after
//             the connection started (or after its previous response) -> 408 and close. Parked
//             connections cost a descriptor and a buffer, no thread.
//          -> ready: queued for a thread of its lane (probes GET /healthz, /readyz, /metrics
//             have a lane of their own, so they answer while every HTTP thread is busy; one
//             address holds at most threads_per_client threads of the main lane); a
//             connection that waits in the queue longer than kMaxQueueWait -> 503 and close.
//          -> a thread serves the request (cpp-httplib's own parser and routes, through
//             process_request over GateStream); pipelined requests already buffered are served
//             next, in order; then the connection goes back to the gate to wait for its next
//             request (keep-alive, --keep-alive-timeout) or is closed.
//
// GateStream reads through the connection's buffer, so bytes that arrive with one request and
// belong to the next are kept for it (0.11.4 made a new stream per request and dropped them:
// of 3 pipelined GETs only 1 was answered). A request body must arrive within --body-timeout in
// all and with no gap longer than the read timeout (the handler then answers 408).
//
// Thread-safety: admit() runs on cpp-httplib's accepting thread, the gate on its own, requests
// on the lanes' threads; the connections' bookkeeping is under one mutex, a connection's buffer
// belongs to whoever holds the connection (the gate while parked, one lane thread while served).
#pragma once

#include <httplib.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "server/http/transport/gate_types.h"

namespace mdn::http {

// Serves one request on a stream: the server's process_request. `close_connection` asks it to
// answer "Connection: close"; it sets `connection_closed` when the request asked for that.
using ServeRequest = std::function<bool(httplib::Stream& stream, bool close_connection, bool& connection_closed)>;

class ConnectionGate {
 public:
  ConnectionGate(GateOptions options, ServeRequest serve);
  ~ConnectionGate();
  ConnectionGate(const ConnectionGate&) = delete;
  ConnectionGate& operator=(const ConnectionGate&) = delete;

  // Takes an accepted socket (the gate closes it). Never blocks.
  void admit(int fd);
  // Closes every waiting connection and stops the threads once they finish their request.
  void shutdown();

  using Counts = ConnectionCounts;  // gate_types.h
  Counts counts() const;

  // For the request being served on this thread (null outside one): the route handlers and the
  // access log talk to its connection through these.
  // The request head was parsed: its body, if any, must now arrive within body_timeout_s.
  static void request_head_parsed();
  // Why the last read of this thread's request failed: a gap longer than the read timeout, or
  // the body's total deadline.
  using ReadTimeout = BodyReadTimeout;  // gate_types.h (last_body_read_timeout)
  static ReadTimeout last_read_timeout();
  // Close the connection after this response (with a lingering close when bytes stay unread).
  static void close_after_this_response(bool bytes_left_unread);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// cpp-httplib's server with its connections handed to a ConnectionGate instead of a thread per
// connection: process_and_close_socket (called for each accepted socket through the task
// queue, which runs it at once on the accepting thread) passes the socket to the gate, whose
// threads call back serve_request.
class GatedServer final : public httplib::Server {
 public:
  // Must be called before listening; the gate lives as long as the server.
  void set_gate_options(const GateOptions& options);
  // Called with each parsed request before routing (cpp-httplib's setup_request: after the
  // head and the Range header are parsed): the one place a request may be changed.
  void set_request_setup(std::function<void(httplib::Request&)> setup) { request_setup_ = std::move(setup); }
  ConnectionGate& gate() { return *gate_; }

 private:
  bool process_and_close_socket(socket_t sock) override;
  std::unique_ptr<ConnectionGate> gate_;
  std::function<void(httplib::Request&)> request_setup_;
};

}  // namespace mdn::http
