// The connection gate's stream (connection_gate.h): a gated connection (Conn: its socket, the
// bytes read ahead, its deadlines) and cpp-httplib's Stream over it. Internal to the transport:
// only connection_gate.cpp and gate_stream.cpp include it.
#pragma once

#include <httplib.h>

#include <chrono>
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

#include <sys/socket.h>

#include "server/http/transport/gate_types.h"
#include "server/http/transport/request_framing.h"

namespace mdn::http::gate {

using Clock = std::chrono::steady_clock;

constexpr std::size_t kReadChunk = 16384;
// The most a parked connection buffers: a head longer than this is refused (request_framing.h).
constexpr std::size_t kMaxHeadBytes = framing::kMaxHeadBytes + 1;

inline Clock::duration seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// One client connection. Owned by the gate while parked, by one lane thread while served.
struct Conn {
  int fd = -1;
  std::string ip;
  int port = 0;
  std::string buf;  // bytes received and not yet consumed, from `off`
  std::size_t off = 0;
  Clock::time_point deadline;       // parked: when the gate gives up on it
  bool idle = true;                 // parked with nothing of the next request yet (keep-alive)
  int served = 0;                   // requests answered
  bool probe = false;               // its next request is a probe (its own lane)
  Clock::time_point queued_at;
  Clock::time_point parked_at;
  // While served:
  std::optional<Clock::time_point> body_deadline;
  BodyReadTimeout timeout = BodyReadTimeout::None;
  bool close_after = false, linger = false;
  std::size_t head_left = 0;            // bytes of the current request's head not read yet
  bool chunked = false;                 // its body is chunked: checked by `framing` as it is read
  framing::ChunkedFraming framing;
  std::optional<Clock::time_point> body_started;  // the first read past the head
  std::uint64_t body_bytes = 0;
  // A refused connection (a head over the limits, a cap): its answer is sent and its write side
  // shut; the gate reads and drops what the client still sends until it closes or kLinger ends,
  // so the client reads the answer instead of a reset (decision 64).
  bool lingering = false;
  bool counted = true;  // in the open / per-client counts (a refusal at a cap is not)

  std::size_t available() const { return buf.size() - off; }
  void compact() {
    buf.erase(0, off);
    off = 0;
  }
  std::string_view pending() const { return std::string_view(buf).substr(off); }
  // The buffered head as far as it has arrived: complete, refused, or not yet either.
  framing::HeadState head() const { return framing::inspect_head(pending()); }
  bool starts_with_probe() const {
    const std::string_view head = std::string_view(buf).substr(off);
    for (std::string_view path : {"GET /healthz", "GET /readyz", "GET /metrics"})
      if (head.size() > path.size() && head.substr(0, path.size()) == path &&
          (head[path.size()] == ' ' || head[path.size()] == '?'))
        return true;
    return false;
  }
};

// The text address and port of an IPv4 or IPv6 socket address; false for another family.
bool address_text(const sockaddr_storage& addr, std::string& ip, int& port);
// A duration as poll(2)'s timeout in milliseconds (clamped to [0, 2^30]).
int poll_ms(Clock::duration d);

// cpp-httplib's Stream over a gated connection: reads go through the connection's buffer (so
// pipelined bytes stay for the next request), with the read timeout between bytes and the
// head or body deadline over all.
class GateStream final : public httplib::Stream {
 public:
  GateStream(Conn& c, const GateOptions& o, Clock::time_point head_deadline)
      : c_(c), o_(o), head_deadline_(head_deadline) {}

  bool is_readable() const override;
  bool is_writable() const override;
  ssize_t read(char* ptr, size_t size) override;
  // Writes what the socket takes now (cpp-httplib calls again for the rest); waits for room up
  // to the write timeout.
  ssize_t write(const char* ptr, size_t size) override;
  void get_remote_ip_and_port(std::string& ip, int& port) const override;
  void get_local_ip_and_port(std::string& ip, int& port) const override;
  socket_t socket() const override { return c_.fd; }

 private:
  bool wait(short events, Clock::duration d) const;

  Conn& c_;
  const GateOptions& o_;
  Clock::time_point head_deadline_;
};

}  // namespace mdn::http::gate
