// Small pieces the HTTP service's files share (http_server.cpp, job_routes.cpp, request_body.cpp,
// job_resource.cpp, web_routes.cpp): a handler's Context, header and text helpers, and the per-request flag
// that closes a connection whose request body stays unread. Internal to the service.
#pragma once

#include <chrono>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "server/http/transport/http_message.h"

namespace mdn::http {

// What a route handler gets (http_server.cpp's dispatch builds it from cpp-httplib's request
// and writes its response back): the service's own types (http_message.h).
struct Context {
  const Request& req;
  Response& res;
  const ContentReader* reader;  // POST routes only
  std::string request_id;
  bool body_consumed = false;  // POST routes: the whole body was read
};

// Status and a JSON body (invalid UTF-8 replaced).
void set_json(Response& res, const nlohmann::json& j, int status = 200);
std::string lower(std::string s);
std::string trim(std::string_view s);
// "model/gltf-binary; charset=x" -> "model/gltf-binary"
std::string base_media_type(std::string_view content_type);
void replace_header(Response& res, const std::string& key, const std::string& value);
// Answers this request, then closes the connection (access_log does it once the response is
// written, with a lingering close): used when the request body stays unread, or when what
// follows on the connection cannot be told apart from the rest of an unparseable request.
void close_after_response(Response& res);
// What close_after_response does besides the header (the transport's own answers use it).
void mark_bytes_left_unread();
// Whether close_after_response was called for this thread's current request; clears the flag.
bool take_bytes_left_unread();
// The byte ranges of this thread's current request. GatedServer's request setup moves them out
// of cpp-httplib's request (set_request_ranges) before routing, so cpp-httplib never slices an
// answer by itself: the result download applies a single range (job_resource.cpp), every other
// answer ignores them, and no handler has to change a const request.
void set_request_ranges(Ranges ranges);
const Ranges& request_ranges();
// A header value must not carry CR/LF (response splitting) nor other control characters.
std::string header_safe(std::string_view text);
std::string format_ms(double ms);  // "%.3f"
std::string iso8601(std::chrono::system_clock::time_point t);
bool has_request_body(const Request& req);

}  // namespace mdn::http
