// The service's own request and response, what every route handler and its helpers work on
// (job_routes, service_routes, request_body, job_resource, web_routes). Only the transport
// (http_server.cpp over connection_gate.h) knows cpp-httplib: it builds a Request from the
// parsed request, hands the handler a Response, and writes that back (issue 35).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace mdn::http {

// Header names compare without regard to case (RFC 9110, 5.1).
struct CaseInsensitiveLess {
  bool operator()(const std::string& a, const std::string& b) const;
};
using Headers = std::multimap<std::string, std::string, CaseInsensitiveLess>;
using Params = std::multimap<std::string, std::string>;
// Byte ranges of a Range header: (first, last), -1 where a bound is absent (a suffix range has
// first -1 and its length as last).
using Ranges = std::vector<std::pair<std::int64_t, std::int64_t>>;

// Receives a piece of the body; false stops the read.
using ContentReceiver = std::function<bool(const char* data, std::size_t length)>;
// One field of a multipart/form-data body, before its bytes.
struct FormPart {
  std::string name;
  std::string filename;
  std::string content_type;
};
using FormPartHandler = std::function<bool(const FormPart& part)>;

// Reads the request body (POST routes): the raw bytes, or a multipart form's fields (each
// FormPart, then its bytes). Returns false when the body could not be read whole.
class ContentReader {
 public:
  using Raw = std::function<bool(ContentReceiver)>;
  using Form = std::function<bool(FormPartHandler, ContentReceiver)>;
  ContentReader(Raw raw, Form form) : raw_(std::move(raw)), form_(std::move(form)) {}
  bool operator()(ContentReceiver receiver) const { return raw_(std::move(receiver)); }
  bool operator()(FormPartHandler part, ContentReceiver receiver) const { return form_(std::move(part), std::move(receiver)); }

 private:
  Raw raw_;
  Form form_;
};

// A parsed request: `matches` are the route pattern's groups (matches[0] the whole path).
struct Request {
  std::string method;
  std::string path;
  Headers headers;
  Params params;  // the query
  std::vector<std::string> matches;
  std::string remote_addr;
  int remote_port = -1;
  bool multipart = false;  // Content-Type multipart/form-data

  bool has_header(const std::string& key) const { return headers.find(key) != headers.end(); }
  // The first value, or "".
  std::string get_header_value(const std::string& key) const;
  bool has_param(const std::string& key) const { return params.find(key) != params.end(); }
  std::string get_param_value(const std::string& key) const;
  bool is_multipart_form_data() const { return multipart; }
};

// Writes a piece of a streamed body; false when the connection failed.
struct DataSink {
  std::function<bool(const char* data, std::size_t length)> write;
};
// Writes `length` bytes of the body from `offset`.
using ContentProvider = std::function<bool(std::size_t offset, std::size_t length, DataSink& sink)>;

// A response: status, headers and a body, or a content provider of known length (the transport
// streams it; a body set this way is never compressed by cpp-httplib).
struct Response {
  int status = -1;
  Headers headers;
  std::string body;
  // set_content_provider: the body's length, media type and provider.
  std::size_t content_length = 0;
  std::string content_type;
  ContentProvider provider;

  bool has_header(const std::string& key) const { return headers.find(key) != headers.end(); }
  std::string get_header_value(const std::string& key) const;
  // Adds a header (a key or value with CR or LF is ignored, as cpp-httplib does).
  void set_header(const std::string& key, const std::string& value);
  void set_content(const char* data, std::size_t size, const std::string& content_type);
  void set_content(const std::string& text, const std::string& content_type) {
    set_content(text.data(), text.size(), content_type);
  }
  void set_content_provider(std::size_t length, const std::string& type, ContentProvider content) {
    content_length = length;
    content_type = type;
    provider = std::move(content);
  }
};

}  // namespace mdn::http
