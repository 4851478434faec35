#include "server/http/routes/http_support.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <ctime>
#include <utility>

namespace mdn::http {

// ---------------------------------------------------------------- http_message.h

bool CaseInsensitiveLess::operator()(const std::string& a, const std::string& b) const {
  return std::lexicographical_compare(a.begin(), a.end(), b.begin(), b.end(), [](unsigned char x, unsigned char y) {
    return std::tolower(x) < std::tolower(y);
  });
}

namespace {
template <class Map>
std::string first_value(const Map& map, const std::string& key) {
  const auto it = map.find(key);
  return it == map.end() ? std::string() : it->second;
}
bool has_crlf(const std::string& s) { return s.find_first_of("\r\n") != std::string::npos; }
}  // namespace

std::string Request::get_header_value(const std::string& key) const { return first_value(headers, key); }
std::string Request::get_param_value(const std::string& key) const { return first_value(params, key); }
std::string Response::get_header_value(const std::string& key) const { return first_value(headers, key); }

void Response::set_header(const std::string& key, const std::string& value) {
  if (!has_crlf(key) && !has_crlf(value)) headers.emplace(key, value);
}

void Response::set_content(const char* data, std::size_t size, const std::string& type) {
  body.assign(data, size);
  headers.erase("Content-Type");
  set_header("Content-Type", type);
}

// ---------------------------------------------------------------- helpers

void set_json(Response& res, const nlohmann::json& j, int status) {
  res.status = status;
  res.set_content(j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

std::string lower(std::string s) {
  for (char& c : s) c = char(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(std::string_view s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string_view::npos) return {};
  const auto e = s.find_last_not_of(" \t");
  return std::string(s.substr(b, e - b + 1));
}

// "model/gltf-binary; charset=x" -> "model/gltf-binary"
std::string base_media_type(std::string_view content_type) {
  return lower(trim(content_type.substr(0, content_type.find(';'))));
}

void replace_header(Response& res, const std::string& key, const std::string& value) {
  res.headers.erase(key);
  res.set_header(key, value);
}

namespace {
// Set when this thread's current request leaves bytes unread on its connection. cpp-httplib runs
// a request from pre-routing (or, for a request it cannot parse, the error handler) to the
// logger on one thread, so access_log reads it for the same request.
thread_local bool t_bytes_left_unread = false;
}  // namespace

bool take_bytes_left_unread() { return std::exchange(t_bytes_left_unread, false); }

namespace {
thread_local Ranges t_request_ranges;
}  // namespace

void set_request_ranges(Ranges ranges) { t_request_ranges = std::move(ranges); }

const Ranges& request_ranges() { return t_request_ranges; }

// Answers this request, then closes the connection (access_log does it once the response is
// written, with a lingering close): used when the request body stays unread, or when what
// follows on the connection cannot be told apart from the rest of an unparseable request.
void close_after_response(Response& res) {
  replace_header(res, "Connection", "close");
  mark_bytes_left_unread();
}

void mark_bytes_left_unread() { t_bytes_left_unread = true; }

// A header value must not carry CR/LF (response splitting) nor other control characters.
std::string header_safe(std::string_view text) {
  std::string out;
  for (char c : text) out += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c;
  return out;
}

std::string format_ms(double ms) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", ms);
  return buf;
}

std::string iso8601(std::chrono::system_clock::time_point t) {
  const std::time_t tt = std::chrono::system_clock::to_time_t(t);
  std::tm tm{};
  gmtime_r(&tt, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

bool has_request_body(const Request& req) {
  if (lower(req.get_header_value("Transfer-Encoding")).find("chunked") != std::string::npos) return true;
  return req.has_header("Content-Length") && req.get_header_value("Content-Length") != "0";
}

}  // namespace mdn::http
