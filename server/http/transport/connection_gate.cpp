#include "server/http/transport/connection_gate.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/epoll.h>
#include <sys/eventfd.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <condition_variable>
#include <cstring>
#include <deque>
#include <map>
#include <mutex>
#include <thread>
#include <unordered_map>
#include <vector>

#include "server/http/transport/connection_probe.h"
#include "server/http/transport/gate_stream.h"
#include "server/http/transport/request_framing.h"
#include "server/http/problem.h"

namespace mdn::http {
namespace {

using namespace gate;

constexpr int kTickMs = 50;  // the gate's deadline checks
// Decision 64: how long a refused connection is drained before it is closed, and how many may
// linger at once (past that a refusal closes at once, as before).
constexpr auto kLinger = std::chrono::seconds(1);  // as ConnectionProbe::linger_close
constexpr std::int64_t kMaxLingering = 256;

thread_local Conn* t_conn = nullptr;             // the connection this lane thread serves now
thread_local const GateOptions* t_options = nullptr;  // and its gate's options

// A raw response for the gate's own refusals (no request was parsed, or none is served yet).
std::string raw_problem(ProblemType type, const std::string& detail, std::optional<int> retry_after_s) {
  Problem p = make_problem(type, detail);
  const std::string body = p.to_json("", "").dump();
  std::string out = "HTTP/1.1 " + std::to_string(p.status) + " " + p.title + "\r\n";
  out += "Content-Type: " + std::string(kProblemMediaType) + "\r\nContent-Length: " + std::to_string(body.size()) + "\r\n";
  if (retry_after_s) out += "Retry-After: " + std::to_string(*retry_after_s) + "\r\n";
  out += "Connection: close\r\n\r\n" + body;
  return out;
}

// Best effort, never blocks: the answer fits the socket's send buffer of a fresh connection.
void send_now(int fd, const std::string& bytes) { (void)::send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL | MSG_DONTWAIT); }

// Reads what is there without blocking (a lingering connection's bytes are dropped). False
// when the peer closed or the socket failed.
bool read_available(Conn& c) {
  char chunk[kReadChunk];
  while (c.lingering || c.available() < kMaxHeadBytes) {
    const ssize_t n = ::recv(c.fd, chunk, sizeof chunk, MSG_DONTWAIT);
    if (n > 0) {
      if (!c.lingering) c.buf.append(chunk, std::size_t(n));
      continue;
    }
    if (n == 0) return false;
    return errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR;
  }
  return true;
}

bool peer_address(int fd, std::string& ip, int& port) {
  sockaddr_storage addr{};
  socklen_t len = sizeof addr;
  if (getpeername(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) return false;
  return address_text(addr, ip, port);
}

// The task queue cpp-httplib asks for: its task (process_and_close_socket) is run at once, on
// the accepting thread: it only hands the socket to the gate.
class InlineTaskQueue final : public httplib::TaskQueue {
 public:
  explicit InlineTaskQueue(ConnectionGate& gate) : gate_(gate) {}
  void enqueue(std::function<void()> fn) override { fn(); }
  void shutdown() override { gate_.shutdown(); }

 private:
  ConnectionGate& gate_;
};

}  // namespace

struct ConnectionGate::Impl {
  struct Lane {
    std::deque<std::unique_ptr<Conn>> ready;
    std::condition_variable cv;
    std::vector<std::thread> threads;
  };

  GateOptions options;
  ServeRequest serve;
  int epoll_fd = -1;
  int wake_fd = -1;
  int max_open = 0;

  mutable std::mutex mutex;  // everything below
  std::unordered_map<int, std::unique_ptr<Conn>> parked;
  std::map<std::string, int> per_client;
  std::map<std::string, int> busy;  // main-lane threads serving each address now
  Counts counts;
  Lane main_lane, probe_lane;
  std::int64_t lingering = 0;  // refused connections being drained (decision 64)
  bool stopping = false;
  std::thread gate_thread;
  std::once_flag stopped;

  Impl(GateOptions o, ServeRequest s) : options(std::move(o)), serve(std::move(s)) {
    epoll_fd = epoll_create1(EPOLL_CLOEXEC);
    wake_fd = eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    if (epoll_fd < 0 || wake_fd < 0) throw std::runtime_error("cannot create the connection gate's epoll");
    epoll_event ev{};
    ev.events = EPOLLIN;
    ev.data.fd = wake_fd;
    epoll_ctl(epoll_fd, EPOLL_CTL_ADD, wake_fd, &ev);
    // Each connection is a descriptor: stay within half the process's limit (the rest is for
    // Redis, files and the workers).
    rlimit nofile{};
    max_open = options.max_connections;
    if (getrlimit(RLIMIT_NOFILE, &nofile) == 0 && nofile.rlim_cur != RLIM_INFINITY)
      max_open = std::max(16, std::min(max_open, int(std::min<rlim_t>(nofile.rlim_cur / 2, 1 << 30))));
    gate_thread = std::thread([this] { gate_loop(); });
    for (int i = 0; i < std::max(1, options.io_threads); ++i)
      main_lane.threads.emplace_back([this] { lane_loop(main_lane); });
    for (int i = 0; i < std::max(1, options.probe_threads); ++i)
      probe_lane.threads.emplace_back([this] { lane_loop(probe_lane); });
  }

  ~Impl() {
    stop();
    ::close(epoll_fd);
    ::close(wake_fd);
  }

  // Idempotent; a second caller waits until the first has stopped everything.
  void stop() { std::call_once(stopped, [this] { stop_once(); }); }

  void stop_once() {
    {
      std::lock_guard lock(mutex);
      stopping = true;
    }
    const std::uint64_t one = 1;
    (void)!::write(wake_fd, &one, sizeof one);
    main_lane.cv.notify_all();
    probe_lane.cv.notify_all();
    if (gate_thread.joinable()) gate_thread.join();
    for (Lane* lane : {&main_lane, &probe_lane})
      for (auto& t : lane->threads)
        if (t.joinable()) t.join();
    std::lock_guard lock(mutex);
    for (auto& [fd, c] : parked) close_locked(*c);
    parked.clear();
    for (Lane* lane : {&main_lane, &probe_lane}) {
      for (auto& c : lane->ready) close_locked(*c);
      lane->ready.clear();
    }
  }

  // ---- bookkeeping (mutex held)
  void close_locked(Conn& c) {
    if (c.fd < 0) return;
    ::close(c.fd);
    c.fd = -1;
    if (c.lingering) --lingering;
    if (!c.counted) return;
    --counts.open;
    if (auto it = per_client.find(c.ip); it != per_client.end() && --it->second <= 0) per_client.erase(it);
  }

  void admit(int fd) {
    auto c = std::make_unique<Conn>();
    c->fd = fd;
    if (!peer_address(fd, c->ip, c->port)) {
      ::close(fd);
      return;
    }
    std::unique_lock lock(mutex);
    if (stopping) {
      ::close(fd);
      return;
    }
    // At a cap, the oldest connection that waits for bytes (idle, or a head not finished) makes
    // room: a new connection, a health probe among them, is never refused because of idle ones.
    bool client_full = per_client[c->ip] >= options.max_connections_per_client;
    if ((client_full && evict_oldest_locked(&c->ip)) || (!client_full && counts.open >= max_open && evict_oldest_locked(nullptr)))
      client_full = false;
    if (client_full || counts.open >= max_open) {
      if (per_client[c->ip] == 0) per_client.erase(c->ip);
      ++(client_full ? counts.refused_client : counts.refused_total);
      lock.unlock();
      c->counted = false;
      const std::string answer = raw_problem(ProblemType::QueueFull,
                                             client_full ? "too many open connections from " + c->ip + " (at most " +
                                                               std::to_string(options.max_connections_per_client) + ")"
                                                         : "the server has too many open connections",
                                             1);
      refuse_locked(std::move(c), answer);
      return;
    }
    ++per_client[c->ip];
    ++counts.open;
    c->deadline = Clock::now() + seconds(options.header_timeout_s);
    c->idle = false;  // a new connection owes its first request within the head timeout
    park_locked(std::move(c));
  }

  // Decision 64: answers and shuts the write side, then drains what the client still sends (the
  // request it is writing) for up to kLinger before closing, so the client reads the answer
  // rather than a reset. Past kMaxLingering drained at once, it closes at once.
  void refuse_locked(std::unique_ptr<Conn> c, const std::string& answer) {
    send_now(c->fd, answer);
    ::shutdown(c->fd, SHUT_WR);
    if (lingering >= kMaxLingering) {
      close_locked(*c);
      return;
    }
    c->buf.clear();
    c->off = 0;
    c->lingering = true;
    ++lingering;
    c->deadline = Clock::now() + kLinger;
    park_locked(std::move(c));
  }

  // A connection with bytes buffered: its head refused (then lingering), dispatched when whole,
  // or parked for the rest of it.
  void route_locked(std::unique_ptr<Conn> c) {
    const framing::HeadState head = c->head();
    if (head.refusal) {
      ++counts.head_refusals;
      refuse_locked(std::move(c), raw_problem(head.refusal->type, head.refusal->detail, std::nullopt));
    } else if (head.complete) {
      dispatch_locked(std::move(c));
    } else {
      park_locked(std::move(c));
    }
  }

  // Closes the parked connection (of `ip`, or any) parked longest ago; false if there is none.
  bool evict_oldest_locked(const std::string* ip) {
    Conn* oldest = nullptr;
    for (auto& [fd, c] : parked)
      if (!c->lingering && (!ip || c->ip == *ip) && (!oldest || c->parked_at < oldest->parked_at)) oldest = c.get();
    if (!oldest) return false;
    auto c = unpark_locked(oldest->fd);
    ++counts.evicted;
    ::shutdown(c->fd, SHUT_RDWR);
    close_locked(*c);
    return true;
  }

  void park_locked(std::unique_ptr<Conn> c) {
    c->parked_at = Clock::now();
    epoll_event ev{};
    ev.events = EPOLLIN | EPOLLRDHUP;
    ev.data.fd = c->fd;
    if (epoll_ctl(epoll_fd, EPOLL_CTL_ADD, c->fd, &ev) != 0) {
      close_locked(*c);
      return;
    }
    const int fd = c->fd;
    parked[fd] = std::move(c);
  }

  // Takes a parked connection out of the epoll set (mutex held).
  std::unique_ptr<Conn> unpark_locked(int fd) {
    auto it = parked.find(fd);
    if (it == parked.end()) return nullptr;
    auto c = std::move(it->second);
    parked.erase(it);
    epoll_ctl(epoll_fd, EPOLL_CTL_DEL, fd, nullptr);
    return c;
  }

  void dispatch_locked(std::unique_ptr<Conn> c) {
    c->probe = c->starts_with_probe();
    c->queued_at = Clock::now();
    Lane& lane = c->probe ? probe_lane : main_lane;
    lane.ready.push_back(std::move(c));
    lane.cv.notify_one();
  }

  // ---- the gate thread: heads arriving, deadlines, connections waiting too long for a thread
  void gate_loop() {
    std::vector<epoll_event> events(256);
    for (;;) {
      const int n = epoll_wait(epoll_fd, events.data(), int(events.size()), kTickMs);
      std::lock_guard lock(mutex);
      if (stopping) return;
      for (int i = 0; i < n; ++i) {
        const int fd = events[std::size_t(i)].data.fd;
        if (fd == wake_fd) {
          std::uint64_t v;
          (void)!::read(wake_fd, &v, sizeof v);
          continue;
        }
        auto it = parked.find(fd);
        if (it == parked.end()) continue;
        Conn& c = *it->second;
        const bool open = read_available(c);
        if (c.lingering) {
          if (!open) close_locked(*unpark_locked(fd));
          continue;
        }
        if (c.idle && c.available() > 0) {
          // The next request started: its head is due within the head timeout.
          c.idle = false;
          c.deadline = Clock::now() + seconds(options.header_timeout_s);
        }
        const framing::HeadState head = c.head();
        if (head.refusal || head.complete) {
          route_locked(unpark_locked(fd));
        } else if (!open) {
          auto gone = unpark_locked(fd);
          close_locked(*gone);
        }
      }
      expire_locked(Clock::now());
    }
  }

  void expire_locked(Clock::time_point now) {
    std::vector<int> due;
    for (auto& [fd, c] : parked)
      if (now >= c->deadline) due.push_back(fd);
    for (int fd : due) {
      auto c = unpark_locked(fd);
      if (!c->idle && !c->lingering) {
        // A head begun and not finished in time (slowloris), or a new connection that sent
        // nothing: answered 408 when something was sent, closed either way.
        ++counts.head_timeouts;
        if (c->available() > 0)
          send_now(c->fd, raw_problem(ProblemType::RequestTimeout,
                                      "the request head did not arrive within " + format_seconds(options.header_timeout_s),
                                      std::nullopt));
      }
      ::shutdown(c->fd, SHUT_RDWR);
      close_locked(*c);
    }
    for (Lane* lane : {&main_lane, &probe_lane}) {
      while (!lane->ready.empty() && now - lane->ready.front()->queued_at > kMaxQueueWait) {
        auto c = std::move(lane->ready.front());
        lane->ready.pop_front();
        ++counts.queue_timeouts;
        send_now(c->fd, raw_problem(ProblemType::QueueFull, "every HTTP thread stayed busy; retry shortly", 1));
        ::shutdown(c->fd, SHUT_WR);
        close_locked(*c);
      }
    }
  }

  static std::string format_seconds(double s) {
    char text[32];
    std::snprintf(text, sizeof text, "%g s", s);
    return text;
  }

  // ---- the lanes: serve requests while whole heads are buffered, then park or close
  // The first ready connection this lane may serve now: on the main lane, one whose address
  // holds fewer than threads_per_client threads (others wait, and past kMaxQueueWait get 503).
  std::deque<std::unique_ptr<Conn>>::iterator next_locked(Lane& lane) {
    if (&lane == &probe_lane) return lane.ready.begin();
    return std::find_if(lane.ready.begin(), lane.ready.end(), [&](const std::unique_ptr<Conn>& c) {
      const auto it = busy.find(c->ip);
      return it == busy.end() || it->second < options.threads_per_client;
    });
  }

  void lane_loop(Lane& lane) {
    const bool main = &lane == &main_lane;
    for (;;) {
      std::unique_ptr<Conn> c;
      {
        std::unique_lock lock(mutex);
        lane.cv.wait(lock, [&] { return stopping || next_locked(lane) != lane.ready.end(); });
        if (stopping) return;
        const auto it = next_locked(lane);
        c = std::move(*it);
        lane.ready.erase(it);
        if (main) ++busy[c->ip];
      }
      const std::string ip = c->ip;
      serve_connection(std::move(c));
      if (main) {
        std::lock_guard lock(mutex);
        if (auto it = busy.find(ip); it != busy.end() && --it->second <= 0) busy.erase(it);
        lane.cv.notify_all();  // a connection of this address may be served now
      }
    }
  }

  void serve_connection(std::unique_ptr<Conn> c) {
    ConnectionProbe::Scope probe_scope(c->fd);
    t_conn = c.get();
    t_options = &options;
    bool keep = true;
    while (keep) {
      c->body_deadline.reset();
      c->timeout = ReadTimeout::None;
      c->close_after = c->linger = false;
      const framing::HeadState head = c->head();  // whole and within the limits: the gate checked it
      c->head_left = head.head_bytes;
      c->chunked = head.chunked;
      c->framing = framing::ChunkedFraming{};
      c->body_started.reset();
      c->body_bytes = 0;
      const bool last = c->served + 1 >= options.keep_alive_max || is_stopping();
      bool closed = false;
      GateStream stream(*c, options, Clock::now() + seconds(options.header_timeout_s));
      const bool ok = serve(stream, last, closed);
      ++c->served;
      keep = ok && !closed && !last && !c->close_after;
      if (c->linger) {
        if (auto probe = ConnectionProbe::current(-1)) probe->linger_close(1000);
        keep = false;
      }
      // Pipelined: the next request is already here; answered in order, on this thread
      // unless it is a probe request on the main lane (or the reverse): back to the gate.
      if (keep) {
        const framing::HeadState next = c->head();
        if (next.refusal || !next.complete) break;
      }
      if (keep && c->starts_with_probe() != c->probe) break;
    }
    t_conn = nullptr;
    t_options = nullptr;
    std::lock_guard lock(mutex);
    if (!keep || stopping) {
      close_locked(*c);
      return;
    }
    c->compact();
    c->idle = c->available() == 0;
    c->deadline = Clock::now() + seconds(c->idle ? options.keep_alive_timeout_s : options.header_timeout_s);
    route_locked(std::move(c));
  }

  bool is_stopping() const {
    std::lock_guard lock(mutex);
    return stopping;
  }
};

ConnectionGate::ConnectionGate(GateOptions options, ServeRequest serve)
    : impl_(std::make_unique<Impl>(std::move(options), std::move(serve))) {}
ConnectionGate::~ConnectionGate() = default;

void ConnectionGate::admit(int fd) { impl_->admit(fd); }
void ConnectionGate::shutdown() { impl_->stop(); }

ConnectionGate::Counts ConnectionGate::counts() const {
  std::lock_guard lock(impl_->mutex);
  Counts c = impl_->counts;
  c.parked = std::int64_t(impl_->parked.size());
  c.queued = std::int64_t(impl_->main_lane.ready.size() + impl_->probe_lane.ready.size());
  return c;
}

void ConnectionGate::request_head_parsed() {
  // The body clock starts when the head is parsed (pre-routing calls this for every request).
  if (t_conn && t_options) t_conn->body_deadline = Clock::now() + seconds(t_options->body_timeout_s);
}

ConnectionGate::ReadTimeout ConnectionGate::last_read_timeout() { return t_conn ? t_conn->timeout : ReadTimeout::None; }

BodyReadTimeout last_body_read_timeout() { return ConnectionGate::last_read_timeout(); }

void ConnectionGate::close_after_this_response(bool bytes_left_unread) {
  if (!t_conn) return;
  t_conn->close_after = true;
  t_conn->linger = t_conn->linger || bytes_left_unread;
}

void GatedServer::set_gate_options(const GateOptions& options) {
  gate_ = std::make_unique<ConnectionGate>(options, [this](httplib::Stream& stream, bool close_connection, bool& closed) {
    return process_request(stream, close_connection, closed, request_setup_);
  });
  ConnectionGate* gate = gate_.get();
  new_task_queue = [gate] { return new InlineTaskQueue(*gate); };
}

bool GatedServer::process_and_close_socket(socket_t sock) {
  gate_->admit(sock);
  return true;
}

}  // namespace mdn::http
