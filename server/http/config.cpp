#include "server/http/config.h"

#include <algorithm>
#include <charconv>
#include <cctype>
#include <cmath>
#include <fstream>
#include <sstream>
#include <thread>

#include <unistd.h>

namespace mdn::http {
namespace {

std::int64_t parse_int(const std::string& name, const std::string& text, std::int64_t lo, std::int64_t hi) {
  std::int64_t value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  std::int64_t multiplier = 1;
  if (ec == std::errc() && ptr != end && ptr + 1 == end) {  // size suffixes for byte counts
    switch (*ptr) {
      case 'k': case 'K': multiplier = std::int64_t{1} << 10; ++ptr; break;
      case 'm': case 'M': multiplier = std::int64_t{1} << 20; ++ptr; break;
      case 'g': case 'G': multiplier = std::int64_t{1} << 30; ++ptr; break;
      default: break;
    }
  }
  if (ec != std::errc() || ptr != end || text.empty())
    throw ConfigError(name + ": expected an integer, got '" + text + "'");
  if (value > hi / multiplier || value < lo / multiplier || value * multiplier < lo || value * multiplier > hi)
    throw ConfigError(name + ": " + text + " is outside [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
  return value * multiplier;
}

double parse_seconds(const std::string& name, const std::string& text, double lo, double hi, bool lo_open) {
  double value = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, value);
  if (ec != std::errc() || ptr != end || text.empty() || !std::isfinite(value))
    throw ConfigError(name + ": expected a number of seconds, got '" + text + "'");
  if (value < lo || (lo_open && value == lo) || value > hi) {
    std::ostringstream range;
    range << (lo_open ? "(" : "[") << lo << ", " << hi << "]";
    throw ConfigError(name + ": " + text + " is outside " + range.str());
  }
  return value;
}

struct Setting {
  const char* flag;  // without "--"
  const char* env;
  const char* help;
  std::function<void(ServerConfig&, const std::string& name, const std::string& value)> set;
  std::function<std::string(const ServerConfig&)> show;
};

std::string show_double(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

// Listening, workers and jobs.
std::vector<Setting> listen_and_jobs_settings() {
  return {
      {"host", "MDN_HOST", "address to listen on (0.0.0.0: every interface)",
       [](ServerConfig& c, const std::string&, const std::string& v) { c.host = v; },
       [](const ServerConfig& c) { return c.host; }},
      {"port", "MDN_PORT", "TCP port; 0 picks a free one (see --port-file)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.port = int(parse_int(n, v, 0, 65535)); },
       [](const ServerConfig& c) { return std::to_string(c.port); }},
      {"port-file", "MDN_PORT_FILE", "write the bound port to this file once listening (for scripts and tests)",
       [](ServerConfig& c, const std::string&, const std::string& v) { c.port_file = v; },
       [](const ServerConfig& c) { return c.port_file.empty() ? std::string("(none)") : c.port_file; }},
      {"workers", "MDN_WORKERS", "worker threads running the pipeline; 0 = number of cores",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.workers = int(parse_int(n, v, 0, 256)); },
       [](const ServerConfig& c) { return std::to_string(c.workers) + " (" + std::to_string(c.effective_workers()) + " here)"; }},
      {"threads-per-job", "MDN_THREADS_PER_JOB", "threads inside one pipeline run, [1, 64]",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.threads_per_job = int(parse_int(n, v, 1, 64)); },
       [](const ServerConfig& c) { return std::to_string(c.threads_per_job); }},
      {"queue-capacity", "MDN_QUEUE_CAPACITY", "jobs waiting for a worker (Redis: in the shared queue too); beyond it new jobs get 503",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.queue_capacity = int(parse_int(n, v, 1, 100000)); },
       [](const ServerConfig& c) { return std::to_string(c.queue_capacity); }},
      {"job-time-limit", "MDN_JOB_TIME_LIMIT", "seconds of running time after which a job fails",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.job_time_limit_s = parse_seconds(n, v, 0, 1e6, true); },
       [](const ServerConfig& c) { return show_double(c.job_time_limit_s); }},
      {"sync-start-timeout", "MDN_SYNC_START_TIMEOUT",
       "seconds a synchronous POST /v1/denoise waits for a free worker; then 503 with Retry-After",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.sync_start_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.sync_start_timeout_s); }},
      {"result-ttl", "MDN_RESULT_TTL", "seconds a finished job and its result stay available",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.result_ttl_s = parse_seconds(n, v, 0, 1e7, true); },
       [](const ServerConfig& c) { return show_double(c.result_ttl_s); }},
      {"max-stored-jobs", "MDN_MAX_STORED_JOBS", "asynchronous jobs kept at most (queued, running, finished); when all are taken, new ones get 503",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_stored_jobs = int(parse_int(n, v, 1, 1000000)); },
       [](const ServerConfig& c) { return std::to_string(c.max_stored_jobs); }},
      {"client-max-stored-jobs", "MDN_CLIENT_MAX_STORED_JOBS",
       "asynchronous jobs one client (API key, or address without keys) keeps, not counting downloaded or cancelled "
       "ones; beyond, its new ones get 429 while others are served; 0 = a quarter of --max-stored-jobs",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.client_max_stored_jobs = int(parse_int(n, v, 0, 1000000)); },
       [](const ServerConfig& c) {
         return std::to_string(c.client_max_stored_jobs) + " (" + std::to_string(c.effective_client_max_stored_jobs()) + " here)";
       }},
      {"max-queued-bytes", "MDN_MAX_QUEUED_BYTES",
       "request bodies held for jobs not started yet, all clients, in bytes (suffix K, M or G); beyond, 503; "
       "0 = a quarter of the memory (cgroup limit or physical)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_queued_bytes = parse_int(n, v, 0, std::int64_t{1} << 50); },
       [](const ServerConfig& c) {
         return std::to_string(c.max_queued_bytes) + " (" + std::to_string(c.effective_max_queued_bytes()) + " here)";
       }},
      {"client-max-queued-bytes", "MDN_CLIENT_MAX_QUEUED_BYTES",
       "the same for one client; beyond, its new jobs get 429 while others are served; 0 = --max-body, at most a quarter "
       "of --max-queued-bytes",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.client_max_queued_bytes = parse_int(n, v, 0, std::int64_t{1} << 50); },
       [](const ServerConfig& c) {
         return std::to_string(c.client_max_queued_bytes) + " (" + std::to_string(c.effective_client_max_queued_bytes()) + " here)";
       }},
  };
}

// The job store (memory or Redis).
std::vector<Setting> job_store_settings() {
  return {
      {"queue", "MDN_QUEUE", "job store: memory (this process) or redis://[:password@]host[:port][/db] (shared by replicas)",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         try {
           c.queue = parse_queue_setting(v);
         } catch (const ConfigError& e) {
           throw ConfigError(n + ": " + e.what());
         }
       },
       [](const ServerConfig& c) { return show_queue_setting(c.queue); }},
      {"queue-prefix", "MDN_QUEUE_PREFIX", "Redis key prefix of this service's jobs and stream",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         if (v.empty() || v.size() > 64 || v.find_first_of(" \t\r\n") != std::string::npos)
           throw ConfigError(n + ": expected 1 to 64 characters without spaces, got '" + v + "'");
         c.queue_prefix = v;
       },
       [](const ServerConfig& c) { return c.queue_prefix; }},
      {"queue-reclaim-idle", "MDN_QUEUE_RECLAIM_IDLE",
       "Redis: seconds without a heartbeat after which another replica takes over a running job",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.queue_reclaim_idle_s = parse_seconds(n, v, 0.5, 3600, false); },
       [](const ServerConfig& c) { return show_double(c.queue_reclaim_idle_s); }},
      {"queue-max-attempts", "MDN_QUEUE_MAX_ATTEMPTS", "Redis: runs of one job (first run and takeovers) before it fails",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.queue_max_attempts = int(parse_int(n, v, 1, 100)); },
       [](const ServerConfig& c) { return std::to_string(c.queue_max_attempts); }},
      {"queue-max-result", "MDN_QUEUE_MAX_RESULT", "Redis: largest result stored, in bytes (suffix K, M or G; at most 512M)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.queue_max_result_bytes = parse_int(n, v, 1, std::int64_t{512} << 20); },
       [](const ServerConfig& c) { return std::to_string(c.queue_max_result_bytes); }},
  };
}

// Request and decoder limits.
std::vector<Setting> limit_settings() {
  return {
      {"max-body", "MDN_MAX_BODY", "largest request body in bytes (suffix K, M or G allowed)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_body_bytes = parse_int(n, v, 1, std::int64_t{1} << 40); },
       [](const ServerConfig& c) { return std::to_string(c.max_body_bytes); }},
      {"max-faces", "MDN_MAX_FACES", "largest number of faces of one surface",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_faces = parse_int(n, v, 1, std::int64_t{1} << 31); },
       [](const ServerConfig& c) { return std::to_string(c.max_faces); }},
      {"max-vertices", "MDN_MAX_VERTICES", "largest number of vertices of one surface",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_vertices = parse_int(n, v, 1, std::int64_t{1} << 31); },
       [](const ServerConfig& c) { return std::to_string(c.max_vertices); }},
      {"max-decoded-bytes", "MDN_MAX_DECODED_BYTES", "bytes a decoder may allocate for one input, scene JSON and node trees included (suffix K, M or G)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_decoded_bytes = parse_int(n, v, 1 << 20, std::int64_t{1} << 40); },
       [](const ServerConfig& c) { return std::to_string(c.max_decoded_bytes); }},
      {"max-json-depth", "MDN_MAX_JSON_DEPTH", "glTF: deepest nesting of JSON objects and arrays, [1, 1000]",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_json_depth = int(parse_int(n, v, 1, 1000)); },
       [](const ServerConfig& c) { return std::to_string(c.max_json_depth); }},
      {"max-nodes", "MDN_MAX_NODES", "glTF: most entries of \"nodes\"",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_nodes = parse_int(n, v, 1, 100'000'000); },
       [](const ServerConfig& c) { return std::to_string(c.max_nodes); }},
      {"max-accessors", "MDN_MAX_ACCESSORS", "glTF: most accessors plus buffer views (and primitives)",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_accessors = parse_int(n, v, 1, 100'000'000); },
       [](const ServerConfig& c) { return std::to_string(c.max_accessors); }},
  };
}

// Connections and the drain.
std::vector<Setting> connection_settings() {
  return {
      {"io-threads", "MDN_IO_THREADS", "HTTP threads; each open connection holds one; at most half wait in long polls; 0 = 4 per core, at least 8",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         c.io_threads = int(parse_int(n, v, 0, 4096));
         if (c.io_threads > 0 && c.io_threads < 4) throw ConfigError(n + ": " + v + " is below 4 (0 picks 4 per core)");
       },
       [](const ServerConfig& c) { return std::to_string(c.io_threads) + " (" + std::to_string(c.effective_io_threads()) + " here)"; }},
      {"header-timeout", "MDN_HEADER_TIMEOUT",
       "seconds for a request head to arrive (from the connection's start or its previous response); then 408 and close",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.header_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.header_timeout_s); }},
      {"body-timeout", "MDN_BODY_TIMEOUT", "seconds a whole request body may take to arrive; then 408 and close",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.body_timeout_s = parse_seconds(n, v, 0, 1e5, true); },
       [](const ServerConfig& c) { return show_double(c.body_timeout_s); }},
      {"max-connections-per-client", "MDN_MAX_CONNECTIONS_PER_CLIENT",
       "open connections from one source address; beyond, new ones are answered 503 and closed",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_connections_per_client = int(parse_int(n, v, 1, 1000000)); },
       [](const ServerConfig& c) { return std::to_string(c.max_connections_per_client); }},
      {"max-connections", "MDN_MAX_CONNECTIONS",
       "open connections in all (also kept below half the process's file limit); beyond, new ones are answered 503 and closed",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.max_connections = int(parse_int(n, v, 1, 1000000)); },
       [](const ServerConfig& c) { return std::to_string(c.max_connections); }},
      {"keep-alive-timeout", "MDN_KEEP_ALIVE_TIMEOUT", "seconds an idle keep-alive connection is kept",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.keep_alive_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.keep_alive_timeout_s); }},
      {"keep-alive-max", "MDN_KEEP_ALIVE_MAX", "requests served on one connection",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.keep_alive_max = int(parse_int(n, v, 1, 1000000)); },
       [](const ServerConfig& c) { return std::to_string(c.keep_alive_max); }},
      {"read-timeout", "MDN_READ_TIMEOUT", "seconds to wait for request bytes",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.read_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.read_timeout_s); }},
      {"body-stall-timeout", "MDN_BODY_STALL_TIMEOUT",
       "seconds a request body may send nothing before the answer is 408 and the connection closes",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.body_stall_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.body_stall_timeout_s); }},
      {"body-min-rate", "MDN_BODY_MIN_RATE",
       "bytes per second a request body must average once --body-rate-grace has passed; then 408 and close; 0 = no floor",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.body_min_rate = parse_seconds(n, v, 0, 1e12, false); },
       [](const ServerConfig& c) { return show_double(c.body_min_rate); }},
      {"body-rate-grace", "MDN_BODY_RATE_GRACE", "seconds from a body's start before --body-min-rate applies",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.body_rate_grace_s = parse_seconds(n, v, 0, 3600, false); },
       [](const ServerConfig& c) { return show_double(c.body_rate_grace_s); }},
      {"write-timeout", "MDN_WRITE_TIMEOUT", "seconds to wait while sending response bytes",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.write_timeout_s = parse_seconds(n, v, 0, 3600, true); },
       [](const ServerConfig& c) { return show_double(c.write_timeout_s); }},
      {"drain-grace", "MDN_DRAIN_GRACE", "on SIGTERM/SIGINT, seconds allowed for queued and running jobs",
       [](ServerConfig& c, const std::string& n, const std::string& v) { c.drain_grace_s = parse_seconds(n, v, 0, 1e6, false); },
       [](const ServerConfig& c) { return show_double(c.drain_grace_s); }},
  };
}

// Access, the web page and logs.
std::vector<Setting> access_and_log_settings() {
  return {
      {"auth-token", "MDN_AUTH_TOKEN", "require 'Authorization: Bearer <token>' on /v1 (prefer the variable: flags show in ps)",
       [](ServerConfig& c, const std::string&, const std::string& v) { c.auth_token = v; },
       [](const ServerConfig& c) { return c.auth_token.empty() ? std::string("(none)") : std::string("(set)"); }},
      {"api-keys", "MDN_API_KEYS",
       "file of per-client keys, one 'name:key' a line: /v1 then needs 'Authorization: Bearer <key>', and a client "
       "sees only its own jobs",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         std::ifstream in(v, std::ios::binary);
         std::ostringstream text;
         text << in.rdbuf();
         if (!in) throw ConfigError(n + ": cannot read '" + v + "'");
         try {
           c.api_keys = parse_api_keys(text.str());
         } catch (const ConfigError& e) {
           throw ConfigError(n + " " + v + ": " + e.what());
         }
         c.api_keys_file = v;
       },
       [](const ServerConfig& c) { return c.api_keys_file.empty() ? std::string("(none)") : c.api_keys_file; }},
      {"trusted-proxies", "MDN_TRUSTED_PROXIES",
       "comma-separated IPv4/IPv6 CIDRs of the proxies in front (e.g. 10.0.0.0/8,::1/128): from a peer in them, the "
       "client (its share, the access log) is the rightmost X-Forwarded-For entry not in them; empty = the peer",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         try {
           c.trusted_proxies = TrustedProxies::parse(v);
         } catch (const std::invalid_argument& e) {
           throw ConfigError(n + ": " + e.what());
         }
       },
       [](const ServerConfig& c) { return c.trusted_proxies.empty() ? std::string("(none)") : c.trusted_proxies.text(); }},
      {"cors-origin", "MDN_CORS_ORIGIN", "Access-Control-Allow-Origin for browser clients; empty disables CORS",
       [](ServerConfig& c, const std::string&, const std::string& v) { c.cors_origin = v; },
       [](const ServerConfig& c) { return c.cors_origin.empty() ? std::string("(disabled)") : c.cors_origin; }},
      {"web", "MDN_WEB", "on or off: serve the web page at / (off for API-only deployments)",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         if (v == "on" || v == "true" || v == "1") c.web = true;
         else if (v == "off" || v == "false" || v == "0") c.web = false;
         else throw ConfigError(n + ": expected on or off, got '" + v + "'");
       },
       [](const ServerConfig& c) { return std::string(c.web ? "on" : "off"); }},
      {"log-format", "MDN_LOG_FORMAT", "text or json (one JSON object per line)",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         if (v == "text") c.log_format = LogFormat::Text;
         else if (v == "json") c.log_format = LogFormat::Json;
         else throw ConfigError(n + ": expected text or json, got '" + v + "'");
       },
       [](const ServerConfig& c) { return std::string(c.log_format == LogFormat::Json ? "json" : "text"); }},
      {"log-level", "MDN_LOG_LEVEL", "trace, debug, info, warn, error or off",
       [](ServerConfig& c, const std::string& n, const std::string& v) {
         static const char* levels[] = {"trace", "debug", "info", "warn", "error", "off"};
         for (const char* l : levels)
           if (v == l) { c.log_level = v; return; }
         throw ConfigError(n + ": expected trace, debug, info, warn, error or off, got '" + v + "'");
       },
       [](const ServerConfig& c) { return c.log_level; }},
  };
}

// Every setting, in --help's order.
const std::vector<Setting>& settings() {
  static const std::vector<Setting> table = [] {
    std::vector<Setting> all;
    for (auto part : {listen_and_jobs_settings, job_store_settings, limit_settings, connection_settings,
                      access_and_log_settings}) {
      std::vector<Setting> group = part();
      all.insert(all.end(), std::make_move_iterator(group.begin()), std::make_move_iterator(group.end()));
    }
    return all;
  }();
  return table;
}

}  // namespace

std::vector<ApiKey> parse_api_keys(const std::string& text) {
  std::vector<ApiKey> keys;
  std::istringstream in(text);
  std::string line;
  for (int number = 1; std::getline(in, line); ++number) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') continue;
    const std::string where = "line " + std::to_string(number);
    const auto colon = line.find(':');
    if (colon == std::string::npos) throw ConfigError(where + ": expected name:key");
    ApiKey k{line.substr(0, colon), line.substr(colon + 1)};
    const bool name_ok = !k.name.empty() && k.name.size() <= 64 && std::all_of(k.name.begin(), k.name.end(), [](char ch) {
      return std::isalnum(static_cast<unsigned char>(ch)) || ch == '.' || ch == '_' || ch == '-';
    });
    if (!name_ok) throw ConfigError(where + ": the name must be 1 to 64 of A-Z a-z 0-9 . _ -");
    const bool key_ok = k.key.size() >= 16 && k.key.size() <= 256 &&
                        std::all_of(k.key.begin(), k.key.end(), [](char ch) { return ch > 0x20 && ch < 0x7f; });
    if (!key_ok) throw ConfigError(where + ": the key must be 16 to 256 visible ASCII characters");
    for (const ApiKey& other : keys)
      if (other.name == k.name || other.key == k.key)
        throw ConfigError(where + ": " + (other.name == k.name ? "the name '" + k.name + "'" : std::string("the key")) +
                          " repeats an earlier line");
    keys.push_back(std::move(k));
  }
  if (keys.empty()) throw ConfigError("no keys (one 'name:key' a line)");
  return keys;
}

RedisAddress parse_redis_url(const std::string& url) {
  const std::string scheme = "redis://";
  if (url.rfind(scheme, 0) != 0) throw ConfigError("expected memory or redis://host[:port][/db], got '" + url + "'");
  std::string rest = url.substr(scheme.size());
  RedisAddress a;
  if (const auto at = rest.rfind('@'); at != std::string::npos) {
    const std::string userinfo = rest.substr(0, at);
    const auto colon = userinfo.find(':');
    // redis://:password@host (Redis < 6 style) or redis://user:password@host; only the
    // password is used (AUTH password, the default user).
    a.password = colon == std::string::npos ? userinfo : userinfo.substr(colon + 1);
    rest = rest.substr(at + 1);
  }
  std::string hostport = rest, db;
  if (const auto slash = rest.find('/'); slash != std::string::npos) {
    hostport = rest.substr(0, slash);
    db = rest.substr(slash + 1);
  }
  std::string port;
  if (!hostport.empty() && hostport.front() == '[') {  // [::1]:6379
    const auto close = hostport.find(']');
    if (close == std::string::npos) throw ConfigError("unclosed '[' in the Redis URL '" + url + "'");
    a.host = hostport.substr(1, close - 1);
    if (close + 1 < hostport.size()) {
      if (hostport[close + 1] != ':') throw ConfigError("bad Redis URL '" + url + "'");
      port = hostport.substr(close + 2);
    }
  } else if (const auto colon = hostport.rfind(':'); colon != std::string::npos) {
    a.host = hostport.substr(0, colon);
    port = hostport.substr(colon + 1);
  } else {
    a.host = hostport;
  }
  if (a.host.empty()) throw ConfigError("the Redis URL '" + url + "' names no host");
  for (char ch : a.host)
    if (static_cast<unsigned char>(ch) <= 0x20 || ch == '/' || ch == '?' || ch == '#')
      throw ConfigError("bad host in the Redis URL '" + url + "'");
  if (!port.empty() || hostport.back() == ':') a.port = int(parse_int("Redis port", port, 1, 65535));
  if (!db.empty()) a.db = int(parse_int("Redis database", db, 0, 15));
  return a;
}

std::optional<RedisAddress> parse_queue_setting(const std::string& text) {
  if (text == "memory") return std::nullopt;
  return parse_redis_url(text);
}

std::string show_queue_setting(const std::optional<RedisAddress>& queue) {
  if (!queue) return "memory";
  const std::string host = queue->host.find(':') == std::string::npos ? queue->host : "[" + queue->host + "]";
  return "redis://" + std::string(queue->password.empty() ? "" : "(credentials)@") + host + ":" +
         std::to_string(queue->port) + "/" + std::to_string(queue->db);
}

namespace {

// A cgroup limit file's value; 0 for "max", an absent file or nonsense.
std::int64_t cgroup_limit(const char* path) {
  std::ifstream in(path);
  std::string text;
  if (!(in >> text) || text == "max") return 0;
  try {
    const long long v = std::stoll(text);
    return v > 0 && v < (std::int64_t{1} << 60) ? v : 0;  // v1 says "no limit" with a huge number
  } catch (const std::exception&) {
    return 0;
  }
}

}  // namespace

std::int64_t memory_available_to_process() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  std::int64_t physical = pages > 0 && page > 0 ? std::int64_t(pages) * page : 0;
  for (const char* path : {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"})
    if (const std::int64_t limit = cgroup_limit(path); limit > 0 && (physical == 0 || limit < physical)) physical = limit;
  return physical;
}


int ServerConfig::effective_client_max_stored_jobs() const {
  return client_max_stored_jobs > 0 ? client_max_stored_jobs : std::max(1, max_stored_jobs / 4);
}

std::int64_t ServerConfig::effective_max_queued_bytes() const {
  if (max_queued_bytes > 0) return max_queued_bytes;
  const std::int64_t memory = memory_available_to_process();
  return memory > 0 ? memory / 4 : std::int64_t{64} << 20;
}

std::int64_t ServerConfig::effective_client_max_queued_bytes() const {
  // By default one client may queue as much as one largest body (decision 79).
  if (client_max_queued_bytes > 0) return client_max_queued_bytes;
  return std::max<std::int64_t>(1, std::min(max_body_bytes, effective_max_queued_bytes() / 4));
}

int ServerConfig::effective_io_threads() const {
  if (io_threads > 0) return io_threads;
  // One thread per open connection: a few per core, and enough for a handful of long polls
  // and uploads on a small machine (64 fixed threads were too many on 2 cores).
  const unsigned cores = std::thread::hardware_concurrency();
  return std::max(8, 4 * int(cores > 0 ? cores : 1));
}

int ServerConfig::effective_workers() const {
  if (workers > 0) return workers;
  const unsigned cores = std::thread::hardware_concurrency();
  return cores > 0 ? int(cores) : 1;
}

ParsedCommandLine parse_command_line(const std::vector<std::string>& args,
                                     const std::function<const char*(const char*)>& getenv_fn) {
  ParsedCommandLine out;
  for (const Setting& s : settings()) {
    if (const char* v = getenv_fn ? getenv_fn(s.env) : nullptr; v != nullptr)
      s.set(out.config, s.env, v);
  }
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string& arg = args[i];
    if (arg == "--help" || arg == "-h") { out.help = true; continue; }
    if (arg == "--version") { out.version = true; continue; }
    if (arg.rfind("--", 0) != 0) throw ConfigError("unexpected argument '" + arg + "' (see --help)");
    std::string name = arg.substr(2), value;
    bool has_value = false;
    if (auto eq = name.find('='); eq != std::string::npos) {
      value = name.substr(eq + 1);
      name.resize(eq);
      has_value = true;
    }
    const Setting* found = nullptr;
    for (const Setting& s : settings())
      if (name == s.flag) found = &s;
    if (found == nullptr) throw ConfigError("unknown flag --" + name + " (see --help)");
    if (!has_value) {
      if (i + 1 >= args.size()) throw ConfigError("--" + name + " needs a value");
      value = args[++i];
    }
    found->set(out.config, "--" + name, value);
  }
  if (!out.config.api_keys.empty() && !out.config.auth_token.empty())
    throw ConfigError("--api-keys and --auth-token exclude each other: give the shared token's clients a key each");
  // Redis keeps a value of at most 512 MiB (proto-max-bulk-len): a request body is one.
  if (out.config.queue && out.config.max_body_bytes > (std::int64_t{512} << 20))
    throw ConfigError("--max-body: at most 536870912 (512M) with --queue redis://, got " +
                      std::to_string(out.config.max_body_bytes));
  return out;
}

std::string help_text() {
  const ServerConfig defaults;
  std::ostringstream out;
  out << "meshdenoise-server: HTTP service for robust mesh denoising (Lu, Chen, Schaefer).\n\n"
      << "Usage: meshdenoise-server [--flag value | --flag=value]...\n\n"
      << "Every setting can also come from its environment variable; flags win.\n\n";
  for (const Setting& s : settings()) {
    out << "  --" << s.flag << " (" << s.env << ")\n      " << s.help << "; default: " << s.show(defaults) << "\n";
  }
  out << "  --help     this text\n  --version  print the version\n\n"
      << "API: GET /openapi.yaml describes every route; GET /v1/params lists the parameters.\n"
      << "SIGTERM/SIGINT: /readyz turns 503, new jobs get 503, accepted jobs finish within\n"
      << "--drain-grace seconds and the process exits as soon as the last one ends and the results\n"
      << "that clients are still polling for are fetched (a result nobody asked about for 3 s does\n"
      << "not hold it; jobs still stuck 5 s after the grace are not waited for).\n\n"
      << "Exit codes: 0 stopped after a clean drain, 1 the drain ran out of grace (or a fatal\n"
      << "error), 2 bad configuration, 3 cannot listen on --host:--port (e.g. the port is in use;\n"
      << "a second server is refused rather than sharing the port).\n";
  return out.str();
}

io::Limits decode_limits(const ServerConfig& c) {
  io::Limits limits;
  limits.max_faces = c.max_faces;
  limits.max_vertices = c.max_vertices;
  limits.max_decoded_bytes = c.max_decoded_bytes;
  limits.max_json_depth = c.max_json_depth;
  limits.max_nodes = c.max_nodes;
  limits.max_accessors = c.max_accessors;
  return limits;
}

}  // namespace mdn::http
