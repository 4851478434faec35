// Configuration of meshdenoise-server: every setting, its default, flag and environment
// variable. Parsed once in main() and passed down; nothing reads the environment later.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "server/http/trusted_proxies.h"

namespace mdn::http {

enum class LogFormat { Text, Json };

// Where a redis:// --queue points. Parsed at startup; a malformed URL is a ConfigError.
struct RedisAddress {
  std::string host = "127.0.0.1";
  int port = 6379;
  int db = 0;
  std::string password;  // empty: no AUTH
};
// Parses redis://[[user]:password@]host[:port][/db] (db in [0, 15]). Throws ConfigError.
RedisAddress parse_redis_url(const std::string& url);
// The --queue setting: "memory" -> nullopt, else parse_redis_url. Throws ConfigError.
std::optional<RedisAddress> parse_queue_setting(const std::string& text);
// As --help and the logs show it: "memory" or the URL, the password never printed.
std::string show_queue_setting(const std::optional<RedisAddress>& queue);

// One client of --api-keys: its name (logs, metrics) and its secret (Authorization: Bearer).
struct ApiKey {
  std::string name;
  std::string key;
};
// The --api-keys file: one client per line, "name:key" (name: 1 to 64 of [A-Za-z0-9._-];
// key: 16 to 256 visible ASCII characters, no spaces); blank lines and lines starting with
// '#' are skipped. Names and keys must be unique. Throws ConfigError naming the line.
std::vector<ApiKey> parse_api_keys(const std::string& text);

struct ServerConfig {
  // --- Listening ---
  std::string host = "127.0.0.1";  // --host / MDN_HOST; 0.0.0.0 to listen on every interface
  int port = 8080;                 // --port / MDN_PORT; 0 picks a free port (see port_file)
  std::string port_file;           // --port-file / MDN_PORT_FILE; written once bound (tests)

  // --- Execution ---
  int workers = 0;            // --workers; pipeline threads; 0 = number of cores; [0, 256]
  int threads_per_job = 1;    // --threads-per-job; threads inside one pipeline run; [1, 64]
  int queue_capacity = 64;    // --queue-capacity; queued (not yet running) jobs; [1, 100000]
  double job_time_limit_s = 300;   // --job-time-limit; seconds of running time per job; (0, 1e6]
  double sync_start_timeout_s = 30;  // --sync-start-timeout; POST /v1/denoise waits this long for a worker, then 503
  double result_ttl_s = 600;       // --result-ttl; seconds a finished job and its result are kept
  int max_stored_jobs = 1024;      // --max-stored-jobs; finished jobs kept at most (oldest evicted)
  // Fair shares (decisions 78, 79). A client is an --api-keys client, or a source address
  // without keys. 0: the default that effective_*() computes.
  int client_max_stored_jobs = 0;  // --client-max-stored-jobs; jobs one client keeps (0: a quarter of --max-stored-jobs)
  std::int64_t max_queued_bytes = 0;  // --max-queued-bytes; bodies of jobs not started, all clients (0: a quarter of the memory)
  std::int64_t client_max_queued_bytes = 0;  // --client-max-queued-bytes; the same, one client (0: --max-body, at most a quarter of --max-queued-bytes)

  // --- Job store (asynchronous jobs; see docker/README.md "Job store") ---
  // --queue / MDN_QUEUE: "memory" (this process only, the default: nullopt) or
  // redis://[:password@]host[:port][/db] (shared by every replica; Redis Streams), parsed once.
  std::optional<RedisAddress> queue;
  std::string queue_prefix = "mdn:";    // --queue-prefix; Redis key prefix (several services per Redis)
  double queue_reclaim_idle_s = 10;     // --queue-reclaim-idle; a job silent this long is taken over
  int queue_max_attempts = 3;           // --queue-max-attempts; runs of one job before it fails
  std::int64_t queue_max_result_bytes = std::int64_t{256} << 20;  // --queue-max-result; stored result bytes

  // --- Input limits ---
  std::int64_t max_body_bytes = std::int64_t{256} << 20;  // --max-body; request body bytes
  std::int64_t max_faces = 5'000'000;                     // --max-faces; per surface
  std::int64_t max_vertices = 5'000'000;                  // --max-vertices; per surface
  // Decoder limits (core/io/document.h io::Limits, whose defaults these repeat; checked before
  // anything is allocated, refused with 413 naming the limit).
  std::int64_t max_decoded_bytes = std::int64_t{1} << 30;  // --max-decoded-bytes; bytes a decoder may allocate
  int max_json_depth = 64;                                  // --max-json-depth; glTF JSON nesting, [1, 1000]
  std::int64_t max_nodes = 100'000;                         // --max-nodes; glTF "nodes" entries
  std::int64_t max_accessors = 1'000'000;                   // --max-accessors; glTF accessors + buffer views

  // --- Connections (cpp-httplib holds one I/O thread per connection it serves; a connection
  // reaches one only once its request head has arrived: see connection_gate.h) ---
  int io_threads = 0;               // --io-threads; HTTP threads, 0 = 4 per core, at least 8; [0, 4096], >= 4 if set
  // --header-timeout: seconds from a connection's accept (or its previous response) to the end
  // of its request head; then 408 and close (slowloris).
  double header_timeout_s = 10;
  // --body-timeout: seconds a whole request body may take, however steadily it trickles; then
  // 408 and close.
  double body_timeout_s = 300;
  int max_connections_per_client = 64;  // --max-connections-per-client; open connections per source address, beyond: 503
  int max_connections = 2048;           // --max-connections; open connections in all (and below the fd limit), beyond: 503
  double keep_alive_timeout_s = 2;  // --keep-alive-timeout; short, idle clients hold a thread
  int keep_alive_max = 100;         // --keep-alive-max; requests per connection
  double read_timeout_s = 30;       // --read-timeout
  // --body-stall-timeout: seconds a request body may send nothing before 408 and close (the
  // socket read timeout in effect is the smaller of this and --read-timeout).
  double body_stall_timeout_s = 10;
  // --body-min-rate, --body-rate-grace: after the grace, a body must have kept this many bytes
  // a second since it began; then 408 and close (decision 63; 0: no floor).
  double body_min_rate = 500;
  double body_rate_grace_s = 10;
  double write_timeout_s = 30;      // --write-timeout

  // --- Operations ---
  double drain_grace_s = 30;     // --drain-grace; on SIGTERM, time for queued+running jobs
  std::string auth_token;        // --auth-token / MDN_AUTH_TOKEN; empty = no auth (prefer the env)
  // --api-keys FILE / MDN_API_KEYS: per-client keys (parse_api_keys), read once at startup;
  // with keys, each client sees, cancels and downloads only its own jobs (404 for others').
  // Exclusive with --auth-token.
  std::vector<ApiKey> api_keys;
  std::string api_keys_file;
  // --trusted-proxies / MDN_TRUSTED_PROXIES: CIDRs of the proxies in front (decision 86); from
  // those, the client is read from X-Forwarded-For for the shares and the access log. None: the
  // socket's peer is the client.
  TrustedProxies trusted_proxies;
  std::string cors_origin = "*"; // --cors-origin; Access-Control-Allow-Origin; empty = no CORS
  bool web = true;               // --web / MDN_WEB on|off; the web page at / (off: API only)
  LogFormat log_format = LogFormat::Text;  // --log-format text|json
  std::string log_level = "info";          // --log-level trace|debug|info|warn|error|off

  int effective_workers() const;
  int effective_client_max_stored_jobs() const;           // at least 1
  std::int64_t effective_max_queued_bytes() const;         // the machine's memory / 4 (64 MiB if unknown)
  std::int64_t effective_client_max_queued_bytes() const;
  int effective_io_threads() const;  // io_threads, or for 0: max(8, 4 x hardware_concurrency)
};

// The memory this process may use: the cgroup's limit (v2 memory.max, v1
// memory.limit_in_bytes) when one is set and lower, else the physical memory; 0 if unknown.
std::int64_t memory_available_to_process();

// The decoder limits of the configuration (--max-faces ... --max-accessors): what the workers and
// POST /v1/compare decode under.
io::Limits decode_limits(const ServerConfig& config);

// A bad flag, environment variable or value; what() names it.
class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct ParsedCommandLine {
  ServerConfig config;
  bool help = false;
  bool version = false;
};

// Defaults, then MDN_* environment variables (getenv-style lookup passed in so tests can
// supply their own), then flags (--name value or --name=value). Throws ConfigError.
ParsedCommandLine parse_command_line(const std::vector<std::string>& args,
                                     const std::function<const char*(const char*)>& getenv_fn);
// --help text: every setting with its flag, environment variable and default.
std::string help_text();

}  // namespace mdn::http
