#include "server/http/http_server.h"

#include <httplib.h>
#include <sys/socket.h>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <functional>
#include <map>
#include <optional>
#include <regex>
#include <thread>
#include <utility>

#include "core/params.h"
#include "server/http/transport/connection_gate.h"
#include "server/http/embedded.h"
#include "server/http/routes/compare_routes.h"
#include "server/http/routes/job_routes.h"
#include "server/http/problem.h"
#include "server/http/routes/request_body.h"
#include "server/http/secure_random.h"
#include "server/http/routes/service_routes.h"
#include "server/http/routes/web_routes.h"
#include "service/job_json.h"
#include "service/params_json.h"

namespace mdn::http {
namespace {

using nlohmann::json;

// Response headers a browser script may read (CORS).
constexpr const char* kExposedHeaders =
    "Location, Retry-After, X-Request-Id, Server-Timing, Content-Disposition, Idempotent-Replayed, "
    "X-Denoise-Params, X-Denoise-Input-Bytes, X-Denoise-Output-Bytes, X-Denoise-Vertices, X-Denoise-Faces, "
    "X-Denoise-Notes, X-Denoise-Summary";
constexpr const char* kAllowedRequestHeaders =
    "Authorization, Content-Type, X-Request-Id, X-Denoise-Params, Idempotency-Key";
// Header fields a request may carry (431 beyond; cpp-httplib 0.11.4 has no such limit).
constexpr std::size_t kMaxRequestHeaders = 100;

// ---------------------------------------------------------------- the transport
// Only this file (and the connection gate under it) knows cpp-httplib: the route handlers work
// on the service's own Request and Response (http_message.h), adapted here both ways.

Request to_request(const httplib::Request& in) {
  Request r;
  r.method = in.method;
  r.path = in.path;
  r.headers = Headers(in.headers.begin(), in.headers.end());
  r.params = Params(in.params.begin(), in.params.end());
  for (const auto& m : in.matches) r.matches.push_back(m.str());
  r.remote_addr = in.remote_addr;
  r.remote_port = in.remote_port;
  r.multipart = in.is_multipart_form_data();
  return r;
}

// The body reader of a POST route, over cpp-httplib's.
ContentReader to_reader(const httplib::ContentReader& in) {
  return ContentReader(
      [&in](ContentReceiver receiver) { return in(std::move(receiver)); },
      [&in](FormPartHandler part, ContentReceiver receiver) {
        return in([&part](const httplib::MultipartFormData& f) { return part(FormPart{f.name, f.filename, f.content_type}); },
                  std::move(receiver));
      });
}

// What the handler answered, into cpp-httplib's response (which held the wiring's headers).
void write_back(Response& in, httplib::Response& out) {
  out.status = in.status;
  out.headers = httplib::Headers(in.headers.begin(), in.headers.end());
  out.body = std::move(in.body);
  if (!in.provider) return;
  out.set_content_provider(in.content_length, in.content_type,
                           [provider = std::move(in.provider)](std::size_t offset, std::size_t length, httplib::DataSink& sink) {
                             DataSink to{[&sink](const char* data, std::size_t n) { return sink.write(data, n); }};
                             return provider(offset, length, to);
                           });
}

// The wiring's own answers (pre-routing, errors) are written on cpp-httplib's response.
void replace_header(httplib::Response& res, const std::string& key, const std::string& value) {
  res.headers.erase(key);
  res.set_header(key, value);
}

void close_after_response(httplib::Response& res) {
  replace_header(res, "Connection", "close");
  mark_bytes_left_unread();
}

// The methods whose body cpp-httplib 0.11 reads before routing (its expect_content()).
bool reads_request_body(const std::string& method) {
  return method == "POST" || method == "PUT" || method == "PATCH" || method == "PRI" || method == "DELETE";
}

bool has_request_body(const httplib::Request& req) {
  Request headers_only;
  headers_only.headers = Headers(req.headers.begin(), req.headers.end());
  return has_request_body(headers_only);
}

}  // namespace

// The service: the wiring and the route table over its parts, composed, not inherited: the job
// routes (job_routes.h) and the service's own routes (service_routes.h); the table says which
// part answers each route.
struct HttpService::Impl {
  using HandlerFn = void (*)(Impl&, Context&);
  struct Route {
    std::string method;
    std::string pattern;  // regex over the path
    std::string name;     // metrics label and OpenAPI path
    HandlerFn handler;
    bool reads_body;
    std::regex regex;
  };

  Impl(const ServerConfig& c, std::shared_ptr<const EventLog> l, ServiceParts p)
      : config(c),
        log(std::move(l)),
        parts(std::move(p)),
        metrics(*parts.metrics),
        pool(*parts.pool),
        store(parts.store.get()),
        jobs(config, log, metrics, pool, *store),
        compare(config, metrics),
        service_routes(config, metrics, pool, *store, jobs, [this] { return svr.gate().counts(); }) {
    id_prefix = random_hex(4);
    routes = make_routes();
    for (Route& r : routes) r.regex = std::regex(r.pattern);
    install();
  }

  // All routes, in one table. Patterns match the whole path (std::regex_match).
  static std::vector<Route> make_routes() {
    return {
        {"GET", "/healthz", "/healthz", [](Impl& s, Context& c) { s.service_routes.healthz(c); }, false, {}},
        {"GET", "/readyz", "/readyz", [](Impl& s, Context& c) { s.service_routes.readyz(c); }, false, {}},
        {"GET", "/metrics", "/metrics", [](Impl& s, Context& c) { s.service_routes.metrics_route(c); }, false, {}},
        {"GET", "/openapi.yaml", "/openapi.yaml", [](Impl& s, Context& c) { s.service_routes.openapi(c); }, false, {}},
        {"GET", "/v1/params", "/v1/params", [](Impl& s, Context& c) { s.service_routes.params(c); }, false, {}},
        {"GET", "/v1/params/schema", "/v1/params/schema", [](Impl& s, Context& c) { s.service_routes.params_schema(c); }, false, {}},
        {"GET", "/v1/report/schema", "/v1/report/schema", [](Impl& s, Context& c) { s.service_routes.report_schema(c); }, false, {}},
        {"POST", "/v1/denoise", "/v1/denoise", [](Impl& s, Context& c) { s.jobs.denoise(c); }, true, {}},
        {"POST", "/v1/jobs", "/v1/jobs", [](Impl& s, Context& c) { s.jobs.create_job(c); }, true, {}},
        {"GET", "/v1/jobs/([^/]+)", "/v1/jobs/{id}", [](Impl& s, Context& c) { s.jobs.get_job(c); }, false, {}},
        {"DELETE", "/v1/jobs/([^/]+)", "/v1/jobs/{id}", [](Impl& s, Context& c) { s.jobs.delete_job(c); }, false, {}},
        {"GET", "/v1/jobs/([^/]+)/result", "/v1/jobs/{id}/result", [](Impl& s, Context& c) { s.jobs.get_result(c); }, false, {}},
        {"POST", "/v1/compare", "/v1/compare", [](Impl& s, Context& c) { s.compare.compare(c); }, true, {}},
        {"GET", "/", "/", [](Impl& s, Context& c) { s.service_routes.web_page(c); }, false, {}},
        {"GET", "/web/(.+)", "/web/{path}", [](Impl& s, Context& c) { s.service_routes.web_page(c); }, false, {}},
    };
  }

  // ---------------------------------------------------------------- wiring
  void install() {
    // Connections wait for their request heads in the gate, not on a thread (connection_gate.h).
    // With a per-client connection cap (not behind a proxy that makes every client one
    // address) one address may also hold at most half the HTTP threads.
    const int io_threads = config.effective_io_threads();
    const bool per_client = config.max_connections_per_client < config.max_connections;
    svr.set_gate_options(GateOptions{.io_threads = io_threads,
                                     .probe_threads = 2,
                                     .header_timeout_s = config.header_timeout_s,
                                     .keep_alive_timeout_s = config.keep_alive_timeout_s,
                                     .keep_alive_max = config.keep_alive_max,
                                     .read_timeout_s = std::min(config.read_timeout_s, config.body_stall_timeout_s),
                                     .body_timeout_s = config.body_timeout_s,
                                     .body_min_rate = config.body_min_rate,
                                     .body_rate_grace_s = config.body_rate_grace_s,
                                     .write_timeout_s = config.write_timeout_s,
                                     .max_connections_per_client = config.max_connections_per_client,
                                     .max_connections = config.max_connections,
                                     .threads_per_client = per_client ? std::max(1, io_threads / 2) : io_threads});
    auto secs = [](double s) { return std::pair<time_t, time_t>(time_t(s), time_t((s - double(time_t(s))) * 1e6)); };
    svr.set_keep_alive_timeout(std::max<time_t>(1, time_t(config.keep_alive_timeout_s + 0.5)));
    svr.set_keep_alive_max_count(std::size_t(config.keep_alive_max));
    // The gate's stream applies the read, write, head and body timeouts; cpp-httplib's own are
    // set alike for what it reads itself.
    const double read_s = std::min(config.read_timeout_s, config.body_stall_timeout_s);
    svr.set_read_timeout(secs(read_s).first, secs(read_s).second);
    svr.set_write_timeout(secs(config.write_timeout_s).first, secs(config.write_timeout_s).second);
    // Only bodies read by httplib itself (routes without a ContentReader) obey this; our
    // POST routes count bytes themselves because chunked uploads bypass it (0.11.4).
    svr.set_payload_max_length(std::size_t(config.max_body_bytes));
    // Byte ranges leave the request before routing (http_support.h, request_ranges()), so an
    // error body is never sliced and no handler changes a const request.
    svr.set_request_setup([](httplib::Request& req) {
      set_request_ranges(Ranges(req.ranges.begin(), req.ranges.end()));
      req.ranges.clear();
    });
    svr.set_tcp_nodelay(true);
    // Not httplib::default_socket_options: 0.11.4 sets SO_REUSEPORT there, with which a second
    // server binds the same port without a word and the kernel splits connections between the
    // two (async jobs then answer 404 on half the polls). SO_REUSEADDR alone lets a restart bind
    // while old connections sit in TIME_WAIT and still refuses a port another socket listens on.
    // Remember the listening socket: bind() enlarges its backlog (see there).
    svr.set_socket_options([this](socket_t sock) {
      int yes = 1;
      ::setsockopt(sock, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof yes);
      listen_fd = sock;
    });

    for (Route& r : routes) {
      Route* route = &r;
      if (r.reads_body) {
        svr.Post(r.pattern, [this, route](const httplib::Request& req, httplib::Response& res,
                                          const httplib::ContentReader& reader) { dispatch(*route, req, res, &reader); });
      } else if (r.method == "GET") {
        svr.Get(r.pattern, [this, route](const httplib::Request& req, httplib::Response& res) {
          dispatch(*route, req, res, nullptr);
        });
      } else if (r.method == "DELETE") {
        svr.Delete(r.pattern, [this, route](const httplib::Request& req, httplib::Response& res) {
          dispatch(*route, req, res, nullptr);
        });
      }
    }
    svr.Options(".*", [this](const httplib::Request& req, httplib::Response& res) { preflight(req, res); });
    svr.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) { return pre_routing(req, res); });
    svr.set_error_handler(httplib::Server::HandlerWithResponse(
        [this](const httplib::Request& req, httplib::Response& res) { return on_error(req, res); }));
    svr.set_logger([this](const httplib::Request& req, const httplib::Response& res) { access_log(req, res); });
  }

  std::string new_request_id() {
    return id_prefix + "-" + std::to_string(request_counter.fetch_add(1) + 1);
  }

  static bool valid_request_id(const std::string& id) {
    if (id.empty() || id.size() > 128) return false;
    return std::all_of(id.begin(), id.end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.' || c == ':';
    });
  }

  std::string request_id_of(const httplib::Request& req, httplib::Response& res) {
    if (res.has_header("X-Request-Id")) return res.get_header_value("X-Request-Id");
    std::string id = req.get_header_value("X-Request-Id");
    if (!valid_request_id(id)) id = new_request_id();
    res.set_header("X-Request-Id", id);
    return id;
  }

  // On cpp-httplib's response (the wiring) or the service's (a handler's failure).
  template <class Req, class Res>
  static void write_problem(const Req& req, Res& res, const Problem& p, const std::string& request_id) {
    res.status = p.status;
    if (p.retry_after_s) replace_header(res, "Retry-After", std::to_string(*p.retry_after_s));
    if (p.status == 401) replace_header(res, "WWW-Authenticate", "Bearer realm=\"meshdenoise\"");
    res.set_content(p.to_json(req.path, request_id).dump(-1, ' ', false, json::error_handler_t::replace),
                    kProblemMediaType);
  }

  // Every route handler runs through here once: whatever it throws becomes one problem+json.
  void dispatch(const Route& route, const httplib::Request& in, httplib::Response& out, const httplib::ContentReader* in_reader) {
    std::string request_id = request_id_of(in, out);
    const Request req = to_request(in);
    Response res;  // starts with what the wiring set (X-Request-Id, CORS)
    res.status = out.status;
    res.headers = Headers(out.headers.begin(), out.headers.end());
    std::optional<ContentReader> reader;
    if (in_reader) reader.emplace(to_reader(*in_reader));
    Context ctx{req, res, reader ? &*reader : nullptr, std::move(request_id)};
    try {
      route.handler(*this, ctx);
    } catch (...) {
      const Problem p = problem_from_exception(std::current_exception());
      if (route.reads_body && !ctx.body_consumed && has_request_body(req)) close_after_response(res);
      if (p.status == 503 && (p.type == "queue-full" || p.type == "store-full")) {
        // Overload is expected and already counted in the metrics: one line per interval with
        // the number refused, not one error per request (10k lines a minute under overload).
        std::int64_t refused = 0;
        if (log && overload_log.due(Clock::now(), refused))
          log->warn("overloaded", {{"type", p.type}, {"refused", refused}, {"interval_s", OverloadLog::kIntervalS}});
      } else if (p.status >= 500 && log) {
        log->error("handler_failed", {{"request_id", ctx.request_id}, {"route", route.name}, {"detail", p.detail}});
      }
      try {
        write_problem(req, res, p, ctx.request_id);
      } catch (...) {  // last resort: never let an exception reach httplib
        res.status = 500;
        res.body.clear();
      }
    }
    write_back(res, out);
  }

  httplib::Server::HandlerResponse pre_routing(const httplib::Request& req, httplib::Response& res) {
    take_bytes_left_unread();
    ConnectionGate::request_head_parsed();  // the body's deadline starts now
    {
      std::lock_guard lock(start_mutex);
      request_start[std::this_thread::get_id()] = Clock::now();
    }
    const std::string id = request_id_of(req, res);
    if (!config.cors_origin.empty()) {
      res.set_header("Access-Control-Allow-Origin", config.cors_origin);
      res.set_header("Access-Control-Expose-Headers", kExposedHeaders);
      if (config.cors_origin != "*") res.set_header("Vary", "Origin");
    }
    auto reject = [&](const Problem& p) {
      // The body (if any) stays unread: close the connection so it is not parsed as a request.
      if (has_request_body(req)) close_after_response(res);
      write_problem(req, res, p, id);
      return httplib::Server::HandlerResponse::Handled;
    };
    // RFC 9112, 6.3: both framings in one request are a smuggling vector; refused, and the
    // connection closed after the answer.
    if (req.has_header("Transfer-Encoding") && req.has_header("Content-Length")) {
      close_after_response(res);
      return reject(make_problem(ProblemType::BadRequest, "the request has both Transfer-Encoding and Content-Length"));
    }
    // Several Content-Length fields (or a list) that do not agree: which one frames the body is
    // ambiguous, and a proxy may pick another (request smuggling). RFC 9112, 6.3: 400 and close.
    if (req.get_header_value_count("Content-Length") > 1 || req.get_header_value("Content-Length").find(',') != std::string::npos) {
      std::string first;
      bool conflict = false;
      for (auto [it, end] = req.headers.equal_range("Content-Length"); it != end; ++it) {
        std::string rest = it->second;
        for (std::size_t pos = 0; pos <= rest.size();) {
          const std::size_t comma = std::min(rest.find(',', pos), rest.size());
          const std::string value = trim(std::string_view(rest).substr(pos, comma - pos));
          if (first.empty()) first = value;
          conflict = conflict || value != first || value.empty();
          pos = comma + 1;
        }
      }
      if (conflict) {
        close_after_response(res);
        return reject(make_problem(ProblemType::BadRequest, "the request has conflicting Content-Length values"));
      }
    }
    // RFC 9112, 6: a body is framed by Content-Length or chunked coding whatever the method, but
    // cpp-httplib reads one only for POST, PUT, PATCH, PRI and DELETE. The body of a GET, HEAD or
    // OPTIONS would be parsed as the next request on this connection, and behind a proxy's
    // kept-alive upstream connection its answer handed to another client (a response desync).
    // Such a request is answered and its connection closed, the body unread.
    if (!reads_request_body(req.method) && has_request_body(req)) close_after_response(res);
    if (req.headers.size() > kMaxRequestHeaders)
      return reject(make_problem(ProblemType::TooManyHeaders, "the request has " + std::to_string(req.headers.size()) + " header fields, more than the limit of " +
                                     std::to_string(kMaxRequestHeaders)));
    // Several ranges could multiply a result's size (one 1 MB result became 209 MB with 200
    // ranges in 0.11.4): refuse them. A single range is honoured by result downloads only
    // (job_resource.cpp); the request setup took the ranges out of the request (install()).
    if (request_ranges().size() > 1)
      return reject(make_problem(ProblemType::MultipleRanges, "send at most one byte range"));
    if ((!config.auth_token.empty() || jobs.client_keys().enabled()) && req.method != "OPTIONS" && req.path.rfind("/v1/", 0) == 0) {
      if (!authorized(req.get_header_value("Authorization")))
        return reject(make_problem(ProblemType::Unauthorized, jobs.client_keys().enabled()
                                                                  ? "this server requires 'Authorization: Bearer <your API key>' on /v1 routes"
                                                                  : "this server requires 'Authorization: Bearer <token>' on /v1 routes"));
    }
    return httplib::Server::HandlerResponse::Unhandled;
  }

  // --api-keys: one of the clients' keys; --auth-token: the shared token (constant-time
  // comparisons: timing does not reveal how many leading bytes matched).
  bool authorized(const std::string& header) const {
    if (jobs.client_keys().enabled()) return jobs.client_keys().client(header) != nullptr;
    const std::string token = bearer_token(header);
    return !token.empty() && equal_secrets(token, config.auth_token);
  }

  httplib::Server::HandlerResponse on_error(const httplib::Request& req, httplib::Response& res) {
    if (!res.body.empty()) return httplib::Server::HandlerResponse::Unhandled;  // already a problem
    const std::string id = request_id_of(req, res);
    Problem p;
    switch (res.status) {
      case 404: {
        std::string allow;
        for (const Route& r : routes)
          if (std::regex_match(req.path, r.regex) && allow.find(r.method) == std::string::npos)
            allow += (allow.empty() ? "" : ", ") + r.method;
        if (!allow.empty()) {
          p = make_problem(ProblemType::MethodNotAllowed, req.method + " is not allowed on " + req.path + "; allowed: " + allow);
          replace_header(res, "Allow", allow + ", OPTIONS");
        } else {
          p = make_problem(ProblemType::NotFound, "no route " + req.method + " " + req.path);
        }
        break;
      }
      case 413:
        p = make_problem(ProblemType::TooLarge, "the body exceeds the limit of " + std::to_string(config.max_body_bytes) + " bytes");
        close_after_response(res);
        break;
      case 414:
        p = make_problem(ProblemType::UriTooLong, "the request target is too long");
        close_after_response(res);  // a body, if any, stays unread
        break;
      case 416:
        p = make_problem(ProblemType::RangeNotSatisfiable, "the Range header is invalid");
        break;
      case 400:
        // cpp-httplib could not parse the request line, the headers or the body's framing: what
        // follows on the connection is not a request we can find the start of (0.11.4 would
        // parse each following line as a request of its own).
        p = make_problem(ProblemType::BadRequest, "the HTTP request could not be parsed");
        close_after_response(res);
        break;
      default:
        p = make_problem(ProblemType::HttpError, "the request failed with status " + std::to_string(res.status));
        p.status = res.status;
    }
    write_problem(req, res, p, id);
    return httplib::Server::HandlerResponse::Handled;
  }

  void preflight(const httplib::Request& req, httplib::Response& res) {
    request_id_of(req, res);
    res.status = 204;
    res.set_header("Allow", "GET, POST, DELETE, OPTIONS");
    if (!config.cors_origin.empty()) {
      res.set_header("Access-Control-Allow-Methods", "GET, POST, DELETE, OPTIONS");
      res.set_header("Access-Control-Allow-Headers", kAllowedRequestHeaders);
      res.set_header("Access-Control-Max-Age", "600");
    }
  }

  std::string route_name(const httplib::Request& req) const {
    for (const Route& r : routes)
      if ((r.method == req.method || (req.method == "HEAD" && r.method == "GET")) && std::regex_match(req.path, r.regex))
        return r.name;
    return req.method == "OPTIONS" ? "*" : "unmatched";
  }

  void access_log(const httplib::Request& req, const httplib::Response& res) {
    // Runs after the response was written: close connections that have bytes left unread. Also
    // when the client itself asked for "Connection: close": it may still be sending, and
    // cpp-httplib's plain close would then reset the connection under it (its next write fails
    // and it never reads the answer).
    if (take_bytes_left_unread()) ConnectionGate::close_after_this_response(true);
    else if (res.get_header_value("Connection") == "close") ConnectionGate::close_after_this_response(false);
    const std::string route = route_name(req);
    metrics.count_request(route, req.method, res.status);
    metrics.add_bytes_out(std::int64_t(res.body.size()));
    if (!req.body.empty()) metrics.add_bytes_in(std::int64_t(req.body.size()));
    double ms = -1;
    {
      std::lock_guard lock(start_mutex);
      if (auto it = request_start.find(std::this_thread::get_id()); it != request_start.end()) {
        ms = std::chrono::duration<double, std::milli>(Clock::now() - it->second).count();
        request_start.erase(it);
      }
    }
    if (!log) return;
    // Probes are frequent: log them at debug level.
    const bool probe = route == "/healthz" || route == "/readyz" || route == "/metrics";
    // req.remote_addr is the socket's peer; never the REMOTE_ADDR header a client may send. The
    // client is the peer, or from a --trusted-proxies peer its X-Forwarded-For (decision 86).
    const std::string client = config.trusted_proxies.client_address_of(req.remote_addr, req.headers);
    nlohmann::json fields = {{"request_id", res.get_header_value("X-Request-Id")},
                             {"method", req.method},
                             {"path", req.path},
                             {"route", route},
                             {"status", res.status},
                             {"duration_ms", ms},
                             {"bytes_out", res.body.size()},
                             {"remote", client}};
    if (client != req.remote_addr) fields["proxy"] = req.remote_addr;
    log->log(probe ? spdlog::level::debug : spdlog::level::info, "request", fields);
  }

  // ---------------------------------------------------------------- state
  const ServerConfig config;
  const std::shared_ptr<const EventLog> log;
  ServiceParts parts;  // owns what the three below refer to
  Metrics& metrics;
  WorkerPool& pool;
  JobStore* store;
  JobRoutes jobs;        // the job routes (/v1/denoise, /v1/jobs...)
  CompareRoutes compare;  // POST /v1/compare (a mesh against a reference)
  GatedServer svr;
  ServiceRoutes service_routes;  // the service's own routes (health, readiness, metrics, contract, page)
  std::vector<Route> routes;
  std::string id_prefix;
  std::atomic<std::uint64_t> request_counter{0};
  int listen_fd = -1;
  std::mutex start_mutex;
  std::map<std::thread::id, Clock::time_point> request_start;  // for access-log durations
  // Requests refused for overload since the last "overloaded" line; due() is true (and hands
  // over the count) at most once per interval.
  struct OverloadLog {
    static constexpr int kIntervalS = 10;
    std::mutex mutex;
    std::optional<Clock::time_point> last;
    std::int64_t refused = 0;
    bool due(Clock::time_point now, std::int64_t& count) {
      std::lock_guard lock(mutex);
      ++refused;
      if (last && now - *last < std::chrono::seconds(kIntervalS)) return false;
      last = now;
      count = std::exchange(refused, 0);
      return true;
    }
  } overload_log;
};

HttpService::HttpService(const ServerConfig& config, std::shared_ptr<const EventLog> log, ServiceParts parts)
    : impl_(std::make_unique<Impl>(config, std::move(log), std::move(parts))) {}

HttpService::~HttpService() {
  stop();
}

int HttpService::bind() {
  auto& svr = impl_->svr;
  const auto& c = impl_->config;
  int port = c.port;
  errno = 0;
  if (port == 0) {
    port = svr.bind_to_any_port(c.host);
    if (port < 0) throw BindError("cannot listen on " + c.host + " on any port: " + std::strerror(errno ? errno : EADDRNOTAVAIL));
  } else if (!svr.bind_to_port(c.host, port)) {
    const int error = errno ? errno : EADDRNOTAVAIL;
    const std::string where = c.host + ":" + std::to_string(port);
    throw BindError(error == EADDRINUSE
                        ? "cannot listen on " + where + ": the port is in use (another meshdenoise-server?); stop it or choose another --port"
                        : "cannot listen on " + where + ": " + std::strerror(error));
  }
  // cpp-httplib 0.11.4 listens with a backlog of 5 (CPPHTTPLIB_LISTEN_BACKLOG, fixed when
  // Debian compiled it): a burst of clients overflows it and the kernel drops their handshakes
  // (measured: 2 of 32 simultaneous clients failed). Calling listen() again on a listening
  // socket only changes its backlog.
  if (impl_->listen_fd >= 0) ::listen(impl_->listen_fd, SOMAXCONN);
  return port;
}

bool HttpService::serve() { return impl_->svr.listen_after_bind(); }

void HttpService::begin_drain() {
  impl_->pool.begin_drain();
  impl_->store->begin_drain();
}

bool HttpService::wait_drained(Clock::time_point deadline) {
  const bool drained = impl_->store->wait_drained(deadline);
  // Results that finished during the drain and whose clients are still polling for them are
  // served until fetched, their clients go quiet, or the grace ends: a restart loses nothing
  // that was accepted (decision 67). A result nobody asks for does not hold the exit.
  while (drained && Clock::now() < deadline && impl_->store->results_awaited())
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  return drained;
}

void HttpService::stop() {
  impl_->pool.begin_drain();
  impl_->store->stop();  // memory: its jobs cancelled; Redis: jobs it still runs go back to the shared queue
  impl_->pool.abandon();
  impl_->svr.stop();
}

WorkerPool& HttpService::pool() { return impl_->pool; }

std::vector<JobSnapshot> HttpService::unfinished() {
  // The jobs waiting in the pool that no store here lists (synchronous ones, a shared store's),
  // then the store's own.
  std::vector<JobSnapshot> mine = impl_->store->unfinished(), out;
  for (const auto& job : impl_->pool.queued_jobs())
    if (std::none_of(mine.begin(), mine.end(), [&](const JobSnapshot& s) { return s.id == job->id(); }))
      out.push_back(job->snapshot());
  out.insert(out.end(), mine.begin(), mine.end());
  return out;
}

int HttpService::unfetched_results() { return impl_->store->unfetched_results(); }

std::vector<RouteInfo> HttpService::route_table() {
  std::vector<RouteInfo> out;
  for (const auto& r : Impl::make_routes()) out.push_back({r.method, r.name});
  return out;
}

}  // namespace mdn::http
