// meshdenoise-server: parses the configuration (flags, then MDN_* variables), builds the
// metrics, the worker pool and the job store (service_parts.h: memory or Redis), runs the HTTP service over them,
// and drains on SIGTERM/SIGINT: /readyz turns 503, new jobs get 503, accepted jobs finish
// within --drain-grace seconds, then the process exits 0 as soon as the last one ends and the
// results that clients are still polling for are fetched (decision 67; results nobody asks for
// do not hold it, the log counts them); a drain that runs out of grace logs
// every job it abandons and exits 1. A second signal stops at once. Either way the process
// ends within kStopBound of the drain's end: a worker stuck in a step that cannot be
// interrupted is not joined (the stuck jobs are logged, then std::_Exit(1)).
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <thread>

#include <pthread.h>

#include "server/http/config.h"
#include "server/exit_watchdog.h"
#include "server/http/http_server.h"
#include "server/http/log.h"
#include "server/service_parts.h"

namespace {

// After the drain (or a forced stop): time for the store, the listener and the workers to
// stop before the process exits without joining them. Cancelled jobs stop within one poll
// (a few milliseconds); only a step that polls no cancellation (Draco) takes longer.
constexpr std::chrono::seconds kStopBound{5};

// Exit codes (help_text() lists them): 0 stopped after a clean drain, 1 the drain ran out of
// grace or a fatal error, 2 bad configuration, 3 the address cannot be listened on (a port in
// use: a second server on it is refused rather than sharing it through SO_REUSEPORT).
constexpr int kExitCannotListen = 3;

// Writes the port atomically (write then rename) so a reader never sees a partial file.
void write_port_file(const std::string& path, int port) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::trunc);
    out << port << "\n";
    if (!out) throw std::runtime_error("cannot write " + tmp);
  }
  std::filesystem::rename(tmp, path);
}

// Waits for SIGTERM or SIGINT for at most `timeout_s` (negative: forever). True if one came.
bool wait_for_signal(const sigset_t& set, double timeout_s) {
  for (;;) {
    int rc;
    if (timeout_s < 0) {
      int sig = 0;
      rc = sigwait(&set, &sig) == 0 ? sig : -1;
    } else {
      timespec ts{time_t(timeout_s), long((timeout_s - double(time_t(timeout_s))) * 1e9)};
      rc = sigtimedwait(&set, nullptr, &ts);
    }
    if (rc > 0) return true;
    if (rc < 0 && errno == EINTR) continue;
    return false;
  }
}

using namespace mdn::http;

void log_listening(const EventLog& log, const ServerConfig& config, int port) {
  log.info("listening", {{"host", config.host},
                         {"port", port},
                         {"workers", config.effective_workers()},
                         {"threads_per_job", config.threads_per_job},
                         {"queue_capacity", config.queue_capacity},
                         {"job_store", config.queue ? "redis" : "memory"},
                         {"io_threads", config.effective_io_threads()},
                         {"max_body", config.max_body_bytes},
                         {"auth", !config.auth_token.empty()}});
}

// The ids of the jobs a drain waits for (queued and running).
nlohmann::json unfinished_ids(HttpService& service) {
  nlohmann::json ids = nlohmann::json::array();
  for (const auto& job : service.unfinished()) ids.push_back(job.id);
  return ids;
}

// Every job the drain gives up on is named (with the Redis store, unfinished jobs stay in Redis
// for another replica).
void log_abandoned(const EventLog& log, HttpService& service) {
  const auto abandoned = service.unfinished();
  log.warn("drain_incomplete", {{"queued", service.pool().queued()},
                                {"running", service.pool().running()},
                                {"abandoned", abandoned.size()},
                                {"still_running", unfinished_ids(service)}});
  for (const auto& job : abandoned)
    log.warn("job_abandoned", {{"job_id", job.id}, {"state", std::string(to_string(job.state))}, {"async", job.asynchronous}});
}

// The drain after the first signal: within --drain-grace; a second signal cuts it short (the
// watchdog then bounds the stop). True if every accepted job ended.
bool drain(HttpService& service, const ServerConfig& config, const EventLog& log, const sigset_t& signals,
           ExitWatchdog& watchdog) {
  // What the drain waits for, and what it does not: finished results nobody downloaded yet
  // (with the memory store they go with the process).
  log.info("draining", {{"grace_s", config.drain_grace_s},
                        {"queued", service.pool().queued()},
                        {"running", service.pool().running()},
                        {"waiting_for", unfinished_ids(service)},
                        {"results_not_downloaded", service.unfetched_results()}});
  service.begin_drain();
  // Drain on a helper thread so a second signal can still cut the grace period short.
  std::atomic<bool> drained_done{false};
  bool drained = false;
  std::thread drainer([&] {
    drained = service.wait_drained(Clock::now() + std::chrono::milliseconds(std::int64_t(config.drain_grace_s * 1000)));
    drained_done = true;
  });
  while (!drained_done) {
    if (wait_for_signal(signals, 0.1)) {
      log.warn("forced_stop", {{"queued", service.pool().queued()}, {"running", service.pool().running()}});
      watchdog.arm(kStopBound);
      service.stop();
    }
  }
  drainer.join();
  if (!drained) log_abandoned(log, service);
  return drained;
}

// Serves until a signal, drains, stops. The exit code: 0 after a clean drain, 1 otherwise.
int serve_until_signal(const ServerConfig& config, const std::shared_ptr<const EventLog>& log, const sigset_t& signals,
                       ExitWatchdog& watchdog) {
  HttpService service(config, log, make_service_parts(config, log));
  const int port = service.bind();
  if (!config.port_file.empty()) write_port_file(config.port_file, port);
  log_listening(*log, config, port);
  bool serve_ok = true;
  const pthread_t main_thread = pthread_self();
  std::atomic<bool> stopping{false};
  std::thread server([&] {
    serve_ok = service.serve();
    // Listening failed on its own: wake the main thread as a signal would.
    if (!stopping) pthread_kill(main_thread, SIGTERM);
  });
  wait_for_signal(signals, -1);
  stopping = true;
  const bool drained = drain(service, config, *log, signals, watchdog);
  watchdog.arm(kStopBound);
  service.stop();
  server.join();
  log->info("stopped", {{"drained", drained}});
  return serve_ok && drained ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  ParsedCommandLine parsed;
  try {
    parsed = parse_command_line(std::vector<std::string>(argv + 1, argv + argc), [](const char* name) {
      return std::getenv(name);
    });
  } catch (const ConfigError& e) {
    std::cerr << "meshdenoise-server: " << e.what() << "\n";
    return 2;
  }
  if (parsed.help) {
    std::cout << help_text();
    return 0;
  }
  if (parsed.version) {
    std::cout << "meshdenoise-server " << MDN_VERSION << "\n";
    return 0;
  }
  const ServerConfig& config = parsed.config;

  // Signals are taken synchronously by this thread (sigwait), so no handler and no global
  // flag: block them before any thread starts so every thread inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  sigaddset(&signals, SIGTERM);
  sigaddset(&signals, SIGINT);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);  // a vanished client must not kill the process

  auto log = std::make_shared<const EventLog>(config);
  // Declared before the service, so destroyed after it: it also bounds the service's destructor.
  ExitWatchdog watchdog([&log] {
    log->error("exit_without_join", {{"bound_s", kStopBound.count()},
                                     {"detail", "workers still running after the drain; exiting without joining them"}});
    std::fflush(stderr);
    std::_Exit(1);
  });
  try {
    return serve_until_signal(config, log, signals, watchdog);
  } catch (const BindError& e) {
    log->error("cannot_listen", {{"host", config.host}, {"port", config.port}, {"detail", e.what()}});
    return kExitCannotListen;
  } catch (const std::exception& e) {
    log->error("fatal", {{"detail", e.what()}});
    return 1;
  }
}
