#include "server/http/transport/gate_stream.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace mdn::http::gate {

bool address_text(const sockaddr_storage& addr, std::string& ip, int& port) {
  char text[INET6_ADDRSTRLEN] = "";
  if (addr.ss_family == AF_INET) {
    const auto* a = reinterpret_cast<const sockaddr_in*>(&addr);
    inet_ntop(AF_INET, &a->sin_addr, text, sizeof text);
    port = ntohs(a->sin_port);
  } else if (addr.ss_family == AF_INET6) {
    const auto* a = reinterpret_cast<const sockaddr_in6*>(&addr);
    inet_ntop(AF_INET6, &a->sin6_addr, text, sizeof text);
    port = ntohs(a->sin6_port);
  } else {
    return false;
  }
  ip = text;
  return true;
}

int poll_ms(Clock::duration d) {
  const auto ms = std::chrono::duration_cast<std::chrono::milliseconds>(d).count();
  return int(std::clamp<long long>(ms, 0, 1 << 30));
}

bool GateStream::is_readable() const { return c_.available() > 0 || wait(POLLIN, seconds(o_.read_timeout_s)); }

bool GateStream::is_writable() const { return wait(POLLOUT, seconds(o_.write_timeout_s)); }

ssize_t GateStream::read(char* ptr, size_t size) {
  const bool body = c_.head_left == 0;
  // Decision 63: past its grace, a body must keep up with the minimum rate whether or not
  // bytes keep arriving (a trickle of 1 byte/s used to hold a thread for the whole body timeout).
  std::optional<Clock::time_point> rate_deadline;
  if (body && o_.body_min_rate > 0) {
    if (!c_.body_started) c_.body_started = Clock::now();
    rate_deadline = *c_.body_started + seconds(o_.body_rate_grace_s + double(c_.body_bytes) / o_.body_min_rate);
    if (Clock::now() > *rate_deadline) {
      c_.timeout = BodyReadTimeout::TooSlow;
      return -1;
    }
  }
  while (c_.available() == 0) {
    c_.buf.clear();
    c_.off = 0;
    Clock::time_point deadline = c_.body_deadline.value_or(head_deadline_);
    const bool rate_first = rate_deadline && *rate_deadline < deadline;
    if (rate_first) deadline = *rate_deadline;
    const Clock::time_point now = Clock::now();
    const Clock::duration stall = seconds(o_.read_timeout_s);
    const bool deadline_first = deadline - now <= stall;
    if (!wait(POLLIN, deadline_first ? std::max(deadline - now, Clock::duration::zero()) : stall)) {
      c_.timeout = !deadline_first             ? BodyReadTimeout::Stall
                   : rate_first                ? BodyReadTimeout::TooSlow
                   : c_.body_deadline          ? BodyReadTimeout::BodyDeadline
                                               : BodyReadTimeout::Stall;
      return -1;
    }
    char chunk[kReadChunk];
    const ssize_t n = ::recv(c_.fd, chunk, sizeof chunk, MSG_DONTWAIT);
    if (n == 0) return 0;
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) continue;  // a spurious wake-up
      return -1;
    }
    c_.buf.assign(chunk, std::size_t(n));
  }
  // The head is the gate's, already checked; past it, at most what the framing allows: a
  // chunked body stops at the byte that breaks its framing or its line limits.
  std::size_t n = std::min(size, c_.available());
  if (!body) n = std::min(n, c_.head_left);
  if (body && c_.chunked && !c_.framing.done() && !c_.framing.feed(std::string_view(c_.buf).substr(c_.off, n))) {
    c_.timeout = BodyReadTimeout::BadFraming;
    return -1;
  }
  std::memcpy(ptr, c_.buf.data() + c_.off, n);
  c_.off += n;
  if (body) c_.body_bytes += n;
  else c_.head_left -= n;
  return ssize_t(n);
}

ssize_t GateStream::write(const char* ptr, size_t size) {
  const Clock::time_point deadline = Clock::now() + seconds(o_.write_timeout_s);
  for (;;) {
    if (!wait(POLLOUT, std::max(deadline - Clock::now(), Clock::duration::zero()))) return -1;
    const ssize_t n = ::send(c_.fd, ptr, size, MSG_NOSIGNAL | MSG_DONTWAIT);
    if (n >= 0) return n;
    if ((errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) || Clock::now() >= deadline) return -1;
  }
}

void GateStream::get_remote_ip_and_port(std::string& ip, int& port) const {
  ip = c_.ip;
  port = c_.port;
}

void GateStream::get_local_ip_and_port(std::string& ip, int& port) const {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  ip.clear();
  port = 0;
  if (getsockname(c_.fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return;
  address_text(addr, ip, port);
}

bool GateStream::wait(short events, Clock::duration d) const {
  pollfd p{c_.fd, events, 0};
  for (;;) {
    const int rc = ::poll(&p, 1, poll_ms(d));
    if (rc < 0 && errno == EINTR) continue;
    return rc > 0;
  }
}

}  // namespace mdn::http::gate
