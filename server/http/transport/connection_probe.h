// The client connection a request arrived on: whether its client still holds it (so a
// synchronous POST /v1/denoise whose client went away cancels its job), and how to close it
// after a response that left bytes unread.
//
// cpp-httplib 0.11.4 gives handlers no access to their socket (later versions added
// Request::is_connection_closed). The connection gate (connection_gate.h) serves a request on
// one thread and names its socket there (Scope); ConnectionProbe::current() then reads it.
#pragma once

#include <sys/types.h>

#include <optional>

namespace mdn::http {

class ConnectionProbe {
 public:
  // The connection this thread serves now; nullopt outside a request the gate serves, or if
  // `peer_port` (the request's remote port; not positive when cpp-httplib could not parse the
  // request, and then not checked) differs from the socket's: a check that this is the
  // request's own connection. Callers then fall back: a vanished client goes unnoticed until
  // its job ends.
  static std::optional<ConnectionProbe> current(int peer_port);
  // True once the peer closed or reset the connection. Never blocks, never consumes bytes.
  bool peer_gone() const;
  // Closes the connection after a response that left bytes unread (a body, or what follows an
  // unparseable request): a "lingering close", as Apache does. Sends FIN after the response,
  // discards what the client still sends until it closes or `max_wait` passes, then ends
  // reading; the gate then closes the socket. Closing at once would reset the connection
  // (unread bytes) and could destroy the response before the client reads it.
  void linger_close(int max_wait_ms) const;

  // While alive, `fd` is the connection this thread serves (ConnectionProbe::current).
  class Scope {
   public:
    explicit Scope(int fd);
    ~Scope();
    Scope(const Scope&) = delete;
    Scope& operator=(const Scope&) = delete;
  };

 private:
  explicit ConnectionProbe(int fd) : fd_(fd) {}
  int fd_;
};

}  // namespace mdn::http
