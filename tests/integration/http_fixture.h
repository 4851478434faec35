// Test support for the black-box HTTP tests: starts the real meshdenoise-server binary on a
// free loopback port (--port 0 --port-file), talks to it with cpp-httplib's client, and stops
// it with SIGTERM, checking its exit status. Also runs the `meshdenoise` CLI for byte-for-byte
// comparisons and builds noisy test meshes as OFF text.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

// Eigen first: <httplib.h> pulls in <resolv.h>, whose `_res` macro breaks Eigen's headers.
#include "core/noise.h"
#include "support/ports.h"
#include "support/shapes.h"

#include <gtest/gtest.h>
#include <httplib.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <csignal>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>


namespace mdn::test {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

inline double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }

// A client writing a body the server refused (413, 416 ...) may find the connection closed:
// that must be an error return, not SIGPIPE killing the test (cpp-httplib 0.11.4 sends
// without MSG_NOSIGNAL). Real clients (curl, browsers) ignore SIGPIPE the same way.
inline const bool kSigpipeIgnored = [] {
  std::signal(SIGPIPE, SIG_IGN);
  return true;
}();

// The environment wins (ctest sets MDN_BUILD_DIR); the build's own paths are the fallback.
inline std::string build_dir() {
  const char* dir = std::getenv("MDN_BUILD_DIR");
  return dir ? dir : MDN_DEFAULT_BUILD_DIR;
}
inline std::string source_dir() {
  const char* dir = std::getenv("MDN_SOURCE_DIR");
  return dir ? dir : MDN_DEFAULT_SOURCE_DIR;
}
inline std::string server_binary() { return build_dir() + "/server/meshdenoise-server"; }
inline std::string cli_binary() { return build_dir() + "/cli/meshdenoise"; }

inline std::string read_file(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_file(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

// `mesh` with seeded noise of `sigma` mean edge lengths (along the normal), as OFF text.
inline std::string noisy_off(TriMesh mesh, double sigma, std::uint64_t seed) {
  NoiseSpec spec;
  spec.sigma = sigma;
  spec.seed = seed;
  mesh.V = add_noise(mesh, spec);
  return off_text(mesh);
}

// A noisy sphere (seeded): `levels` subdivisions of an icosahedron (20 * 4^levels faces).
inline std::string noisy_sphere_off(int levels, std::uint64_t seed = 1) { return noisy_off(sphere(levels), 0.2, seed); }

inline std::string temp_dir(const std::string& name) {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  fs::path dir = fs::temp_directory_path() /
                 ("mdn_" + name + "_" + std::string(info ? info->name() : "x") + "_" + std::to_string(getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir.string();
}

// Runs a shell command; returns its exit status and stdout.
inline std::pair<int, std::string> run_command(const std::string& command) {
  std::string out;
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) return {-1, ""};
  char buf[4096];
  while (std::size_t n = fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

inline std::string shell_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

// The real server as a child process.
class ServerProcess {
 public:
  explicit ServerProcess(std::vector<std::string> args, std::vector<std::string> env = {}) {
    dir_ = temp_dir("server");
    port_file_ = dir_ + "/port";
    log_file_ = dir_ + "/server.log";
    args.insert(args.begin(), {server_binary(), "--port", "0", "--port-file", port_file_});
    pid_ = fork();
    if (pid_ == 0) {
      prctl(PR_SET_PDEATHSIG, SIGKILL);  // never outlive a crashed test
      const int fd = open(log_file_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      dup2(fd, 1);
      dup2(fd, 2);
      for (const auto& e : env) putenv(const_cast<char*>(strdup(e.c_str())));
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      execv(argv[0], argv.data());
      _exit(127);
    }
    // Wait for the port file (written once the socket is bound, before accepting).
    for (int i = 0; i < 400 && port_ == 0; ++i) {
      if (fs::exists(port_file_)) port_ = std::atoi(read_file(port_file_).c_str());
      if (port_ == 0) std::this_thread::sleep_for(std::chrono::milliseconds(25));
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        exit_status_ = status;
        break;
      }
    }
  }
  ~ServerProcess() {
    if (!exited_) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
    fs::remove_all(dir_);
  }
  ServerProcess(const ServerProcess&) = delete;
  ServerProcess& operator=(const ServerProcess&) = delete;

  int port() const { return port_; }
  bool started() const { return port_ > 0; }
  pid_t pid() const { return pid_; }
  std::string log() const { return read_file(log_file_); }

  std::unique_ptr<httplib::Client> client(int read_timeout_s = 60) const {
    auto c = std::make_unique<httplib::Client>("127.0.0.1", port_);
    c->set_read_timeout(read_timeout_s, 0);
    c->set_write_timeout(30, 0);
    c->set_connection_timeout(5, 0);
    return c;
  }

  void signal(int sig) const { kill(pid_, sig); }

  // Waits for the process to exit; returns its exit code (or -1 on a signal/timeout).
  int wait_exit(std::chrono::seconds timeout = std::chrono::seconds(30)) {
    const auto deadline = std::chrono::steady_clock::now() + timeout;
    while (!exited_ && std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (waitpid(pid_, &status, WNOHANG) == pid_) {
        exited_ = true;
        exit_status_ = status;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    if (!exited_) return -1;
    return WIFEXITED(exit_status_) ? WEXITSTATUS(exit_status_) : -1;
  }

 private:
  std::string dir_, port_file_, log_file_;
  pid_t pid_ = -1;
  int port_ = 0;
  bool exited_ = false;
  int exit_status_ = 0;
};

// Percent-encodes a query parameter value (Debian's httplib 0.11.4 keeps its encoder private).
inline std::string url_encode(const std::string& text) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += char(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

// A TCP socket connected to 127.0.0.1:port, or -1; from the loopback address `source` (another
// client, "127.0.0.2") when one is given.
inline int connect_loopback(int port, const char* source = nullptr) {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  if (source) {
    sockaddr_in from{};
    from.sin_family = AF_INET;
    inet_pton(AF_INET, source, &from.sin_addr);
    if (bind(fd, reinterpret_cast<sockaddr*>(&from), sizeof from) != 0) return close(fd), -1;
  }
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(std::uint16_t(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) return close(fd), -1;
  return fd;
}

inline int connect_from(const char* source, int port) { return connect_loopback(port, source); }

// VmRSS or VmHWM of a process, in MiB (0 if unreadable).
inline double status_mib(pid_t pid, const std::string& field) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(field + ":", 0) == 0) return std::atof(line.c_str() + field.size() + 1) / 1024.0;
  return 0;
}

// Everything the peer sends on fd until it closes; gives up on a read that waits longer than
// timeout_s.
inline std::string read_until_close(int fd, int timeout_s) {
  timeval tv{timeout_s, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string out;
  char buf[4096];
  for (ssize_t n; (n = recv(fd, buf, sizeof buf, 0)) > 0;) out.append(buf, std::size_t(n));
  return out;
}

// Sends raw bytes on a fresh connection and returns the status of the first response (0 if
// none came), for requests cpp-httplib's client refuses to send. Reads the first response
// (by its Content-Length), or everything until the server closes; gives up on a read that
// waits longer than timeout_s.
inline int raw_status(int port, const std::string& bytes, std::string* response = nullptr,
                      bool read_until_close = false, int timeout_s = 3) {
  const int fd = connect_loopback(port);
  if (fd < 0) return 0;
  send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
  timeval tv{timeout_s, 0};
  setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  std::string out;
  char buf[4096];
  for (;;) {
    const ssize_t n = recv(fd, buf, sizeof buf, 0);
    if (n <= 0) break;
    out.append(buf, std::size_t(n));
    const auto head_end = out.find("\r\n\r\n");
    if (!read_until_close && head_end != std::string::npos) {
      const auto cl = out.find("Content-Length: ");
      if (cl != std::string::npos && cl < head_end &&
          out.size() >= head_end + 4 + std::size_t(std::atoi(out.c_str() + cl + 16)))
        break;
    }
  }
  close(fd);
  if (response) *response = out;
  if (out.rfind("HTTP/1.1 ", 0) != 0) return 0;
  return std::atoi(out.c_str() + 9);
}

inline nlohmann::json parse_json(const std::string& body) {
  return nlohmann::json::parse(body, nullptr, /*allow_exceptions=*/false);
}

// Checks the RFC 9457 shape of an error answer; returns the parsed problem.
inline nlohmann::json expect_problem(const httplib::Result& res, int status) {
  EXPECT_TRUE(res) << "no response";
  if (!res) return {};
  EXPECT_EQ(res->status, status) << res->body;
  EXPECT_EQ(res->get_header_value("Content-Type"), "application/problem+json") << res->body;
  nlohmann::json p = parse_json(res->body);
  EXPECT_TRUE(p.is_object()) << res->body;
  if (!p.is_object()) return p;
  EXPECT_EQ(p.value("status", 0), status);
  EXPECT_EQ(p.value("type", "").rfind("urn:meshdenoise:problem:", 0), 0u) << res->body;
  EXPECT_FALSE(p.value("title", "").empty());
  EXPECT_FALSE(p.value("detail", "").empty());
  EXPECT_FALSE(p.value("request_id", "").empty());
  EXPECT_EQ(p.value("request_id", ""), res->get_header_value("X-Request-Id"));
  return p;
}

// Parameters that keep a job running for seconds (to observe it queued or running, cancel it).
inline constexpr const char* kHeavyParams = R"({"n_normal":1000,"n_vertex":1000,"n_aniso":20})";

// The value of a series without labels in a /metrics body (the line that starts with its
// name); -1 when absent.
inline double metric_value(const std::string& metrics, const std::string& series) {
  std::istringstream in(metrics);
  for (std::string line; std::getline(in, line);)
    if (line.rfind(series + " ", 0) == 0) return std::atof(line.c_str() + series.size() + 1);
  return -1;
}

// Polls GET /v1/jobs/{id} until the job is finished; returns its last JSON.
inline nlohmann::json wait_job(httplib::Client& c, const std::string& id,
                               std::chrono::seconds timeout = std::chrono::seconds(60)) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  nlohmann::json job;
  while (std::chrono::steady_clock::now() < deadline) {
    auto r = c.Get("/v1/jobs/" + id);
    if (!r || r->status != 200) return {};
    job = parse_json(r->body);
    const std::string state = job.value("state", "");
    if (state != "queued" && state != "running") return job;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  return job;
}

}  // namespace mdn::test
