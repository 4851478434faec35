#include "server/http/connection_probe.h"

#include <fcntl.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdlib>

namespace mdn::http {
namespace {

thread_local int t_connection_fd = -1;  // set by ConnectionTaskQueue for the task's duration

int port_of(int fd, bool peer) {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  const int rc = peer ? getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len)
                      : getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len);
  if (rc != 0) return -1;
  if (addr.ss_family == AF_INET) return ntohs(reinterpret_cast<sockaddr_in*>(&addr)->sin_port);
  if (addr.ss_family == AF_INET6) return ntohs(reinterpret_cast<sockaddr_in6*>(&addr)->sin6_port);
  return -1;
}

}  // namespace

ConnectionTaskQueue::ConnectionTaskQueue(std::size_t threads, int listen_fd)
    : pool_(threads), listen_fd_(listen_fd), listen_port_(listen_fd >= 0 ? port_of(listen_fd, false) : -1) {}

// Whether fd is a connection on the listening port that no task serves yet; `open` tells
// whether fd is a descriptor at all.
bool ConnectionTaskQueue::unserved_connection(int fd, ino_t& inode, bool& open) const {
  struct stat st {};
  open = fstat(fd, &st) == 0;
  if (!open || !S_ISSOCK(st.st_mode) || serving_.count(st.st_ino)) return false;
  if (port_of(fd, false) != listen_port_ || port_of(fd, true) < 0) return false;
  inode = st.st_ino;
  return true;
}

int ConnectionTaskQueue::accepted_socket(ino_t& inode) const {
  if (listen_port_ <= 0) return -1;
  // accept() gave the lowest free descriptor, so the new socket lies just below the lowest one
  // free now, or above it if another thread closed a lower one since: search outwards from it,
  // down to 0 and up until 64 descriptors in a row are closed.
  const int lowest_free = fcntl(listen_fd_, F_DUPFD_CLOEXEC, 0);
  if (lowest_free < 0) return -1;
  close(lowest_free);
  bool open = false;
  for (int d = 1, closed_above = 0; lowest_free - d >= 0 || closed_above < 64; ++d) {
    if (lowest_free - d >= 0 && unserved_connection(lowest_free - d, inode, open)) return lowest_free - d;
    if (closed_above < 64) {
      if (unserved_connection(lowest_free + d, inode, open)) return lowest_free + d;
      closed_above = open ? 0 : closed_above + 1;
    }
  }
  return -1;
}

void ConnectionTaskQueue::enqueue(std::function<void()> fn) {
  int fd = -1;
  ino_t inode = 0;
  {
    std::lock_guard lock(mutex_);
    fd = accepted_socket(inode);
    if (fd >= 0) serving_.insert(inode);
  }
  pool_.enqueue([this, fn = std::move(fn), fd, inode] {
    t_connection_fd = fd;
    fn();  // cpp-httplib's process_and_close_socket: serves the connection, then closes it
    t_connection_fd = -1;
    if (fd >= 0) {
      std::lock_guard lock(mutex_);
      serving_.erase(inode);
    }
  });
}

std::optional<ConnectionProbe> ConnectionProbe::current(int peer_port) {
  if (t_connection_fd < 0 || (peer_port > 0 && port_of(t_connection_fd, true) != peer_port)) return std::nullopt;
  return ConnectionProbe(t_connection_fd);
}

void ConnectionProbe::linger_close(int max_wait_ms) const {
  shutdown(fd_, SHUT_WR);
  char sink[16384];
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(max_wait_ms);
  for (;;) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) break;
    pollfd p{fd_, POLLIN, 0};
    if (poll(&p, 1, int(left.count())) <= 0) break;
    const ssize_t n = recv(fd_, sink, sizeof sink, MSG_DONTWAIT);
    if (n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR)) break;
  }
  shutdown(fd_, SHUT_RD);
}

bool ConnectionProbe::peer_gone() const {
  pollfd p{fd_, POLLIN | POLLRDHUP, 0};
  if (poll(&p, 1, 0) <= 0) return false;
  if (p.revents & (POLLHUP | POLLERR | POLLRDHUP | POLLNVAL)) return true;
  if (p.revents & POLLIN) {
    char byte;
    const ssize_t n = recv(fd_, &byte, 1, MSG_PEEK | MSG_DONTWAIT);
    return n == 0 || (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR);
  }
  return false;
}

}  // namespace mdn::http
