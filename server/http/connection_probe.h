// Tells whether the client of a request still holds its connection, so a synchronous
// POST /v1/denoise whose client went away cancels its job.
//
// cpp-httplib 0.11.4 gives handlers no access to their socket (later versions added
// Request::is_connection_closed). The handler's thread owns the accepted socket for as long
// as the handler runs, and the (local port, peer address, peer port) triple identifies it
// among the process's descriptors, so we find it once by that triple and then only poll it.
#pragma once

#include <optional>
#include <string>

namespace mdn::http {

class ConnectionProbe {
 public:
  // The accepted socket with this local port and peer; nullopt if none matches (then the
  // caller cannot detect a vanished client and simply waits for the job).
  static std::optional<ConnectionProbe> find(int local_port, const std::string& remote_addr, int remote_port);
  // True once the peer closed or reset the connection. Never blocks, never consumes bytes.
  bool peer_gone() const;
  // Closes the connection after a response that left the request body unread (a "lingering
  // close", as Apache does): sends FIN after the response, discards what the client still sends
  // until it closes or `max_wait` passes, then ends reading so cpp-httplib's keep-alive loop sees
  // end-of-stream. Needed because 0.11.4 keeps a connection open even when the response says
  // "Connection: close" and would parse the unread body as the next request; closing at once
  // would reset the connection and could destroy the response before the client reads it.
  void linger_close(int max_wait_ms) const;

 private:
  explicit ConnectionProbe(int fd) : fd_(fd) {}
  int fd_;
};

}  // namespace mdn::http
