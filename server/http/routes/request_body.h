// Request bodies of the job routes (POST /v1/denoise, POST /v1/jobs) and of the reference
// comparison (POST /v1/compare): the mesh's media type,
// the body read with our own byte count (cpp-httplib 0.11.4 bounds Content-Length bodies only,
// not chunked uploads), multipart forms, and the parameters from ?params=, X-Denoise-Params or
// the form's params field.
#pragma once

#include <chrono>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/document.h"
#include "service/job_runner.h"
#include "server/http/metrics.h"
#include "server/http/problem.h"
#include "server/http/routes/http_support.h"

namespace mdn::http {

// Media types accepted for mesh bodies: their list (for 415 answers) and the 415 problem.
std::string accepted_media_types();
Problem unsupported_media_type(const std::string& detail);
// The container of a mesh body: from its declared media type, else its file name's extension,
// else its bytes. Throws HttpError 415.
io::Format resolve_format(const std::string& content_type, std::string_view bytes, const std::string& filename = {});

// Reads a job's body within --max-body bytes, counting them into the metrics. Thread-safe:
// it keeps no state but its two settings.
class BodyReader {
 public:
  // `stall_timeout_s`: the socket read timeout in effect; a body read that fails after sending
  // nothing for (about) that long, or that is not complete `body_timeout_s` after its head,
  // is answered 408 and the connection closed.
  BodyReader(std::int64_t max_body_bytes, double stall_timeout_s, double body_timeout_s, Metrics& metrics)
      : max_body_bytes_(max_body_bytes), stall_timeout_s_(stall_timeout_s), body_timeout_s_(body_timeout_s), metrics_(metrics) {}
  // Body, container and parameters of a job, from a raw body or a multipart form. Throws
  // HttpError (400, 408, 411, 413, 415) and what job_params_from_text throws.
  service::JobInput read_job_input(Context& ctx);
  // One file of a multipart form.
  struct FormFile {
    std::string bytes, content_type, filename;
  };
  // A multipart form whose fields are among `names`, each at most once, within --max-body bytes
  // (POST /v1/jobs' mesh and params, POST /v1/compare's reference and mesh). Throws HttpError
  // (400 bad form, 408, 411, 413).
  std::map<std::string, FormFile> read_form(Context& ctx, const std::vector<std::string>& names);
  // The body's declared Content-Length when it is a valid one and the body is not chunked; what
  // a route may check before reading the body (the queued-bytes shares).
  static std::optional<std::int64_t> declared_length(const Request& req);

 private:
  std::string read_body(Context& ctx, const ContentReader& reader);
  [[noreturn]] void throw_too_large(Context& ctx);
  void check_declared_length(Context& ctx);
  // After a failed read: 408 (and close) if no byte came for the stall timeout, or the body's
  // deadline passed.
  void check_stall(Context& ctx, std::chrono::steady_clock::time_point last_byte);

  const std::int64_t max_body_bytes_;
  const double stall_timeout_s_;
  const double body_timeout_s_;
  Metrics& metrics_;
};

}  // namespace mdn::http
