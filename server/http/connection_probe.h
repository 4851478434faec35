// The client connection a request arrived on: whether its client still holds it (so a
// synchronous POST /v1/denoise whose client went away cancels its job), and how to close it
// after a response that left bytes unread.
//
// cpp-httplib 0.11.4 gives handlers no access to their socket (later versions added
// Request::is_connection_closed), and it parses the peer address only once a request line
// parses. But it serves each connection on one pool thread, from its first byte to its close.
// So ConnectionTaskQueue, the server's thread pool, finds the socket each accepted connection
// runs on and tells that thread; ConnectionProbe::current() then reads it there.
#pragma once

#include <httplib.h>
#include <sys/types.h>

#include <cstddef>
#include <functional>
#include <mutex>
#include <optional>
#include <unordered_set>

namespace mdn::http {

class ConnectionProbe {
 public:
  // The connection this thread serves now; nullopt outside a ConnectionTaskQueue task, if its
  // socket could not be identified, or if `peer_port` (the request's remote port; not positive
  // when cpp-httplib could not parse the request, and then not checked) differs from the
  // socket's: a check that this is the request's own connection. Callers then fall back: a vanished client goes unnoticed
  // until its job ends, and a connection closes without lingering.
  static std::optional<ConnectionProbe> current(int peer_port);
  // True once the peer closed or reset the connection. Never blocks, never consumes bytes.
  bool peer_gone() const;
  // Closes the connection after a response that left bytes unread (a body, or what follows an
  // unparseable request): a "lingering close", as Apache does. Sends FIN after the response,
  // discards what the client still sends until it closes or `max_wait` passes, then ends
  // reading so cpp-httplib's keep-alive loop sees end-of-stream. Needed because 0.11.4 keeps a
  // connection open even when the response says "Connection: close" and would parse the unread
  // bytes as the next request; closing at once would reset the connection and could destroy
  // the response before the client reads it.
  void linger_close(int max_wait_ms) const;

 private:
  explicit ConnectionProbe(int fd) : fd_(fd) {}
  int fd_;
};

// cpp-httplib's ThreadPool, plus: each connection's thread learns its socket. enqueue() runs on
// the accepting thread right after accept(), so the connection's socket is a socket on the
// listening port, with a peer, that no task serves yet (told apart by inode, which a reused
// descriptor number does not share); accept() gives the lowest free descriptor, so it is found
// next to the lowest one free now, most often in a few system calls.
class ConnectionTaskQueue final : public httplib::TaskQueue {
 public:
  ConnectionTaskQueue(std::size_t threads, int listen_fd);
  void enqueue(std::function<void()> fn) override;
  void shutdown() override { pool_.shutdown(); }

 private:
  int accepted_socket(ino_t& inode) const;  // -1 if not found
  bool unserved_connection(int fd, ino_t& inode, bool& open) const;

  httplib::ThreadPool pool_;
  int listen_fd_ = -1;
  int listen_port_ = -1;
  std::mutex mutex_;
  std::unordered_set<ino_t> serving_;  // sockets of the connections queued or being served
};

}  // namespace mdn::http
