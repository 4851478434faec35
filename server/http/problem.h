// RFC 9457 problem details: the one error shape of the HTTP API. Every handler is wrapped
// once (http_server.cpp); whatever it throws becomes a Problem through problem_from_exception.
#pragma once

#include <exception>
#include <optional>
#include <stdexcept>
#include <string>

#include <nlohmann/json.hpp>

namespace mdn::http {

// Media type of every error body.
inline constexpr const char* kProblemMediaType = "application/problem+json";

struct Problem {
  int status = 500;
  std::string type;    // short slug, e.g. "invalid-params"; serialised as "urn:meshdenoise:problem:<slug>"
  std::string title;   // fixed per type
  std::string detail;  // this occurrence, for humans
  nlohmann::json extensions = nlohmann::json::object();  // e.g. "field", "minimum", "maximum"
  std::optional<int> retry_after_s;  // sets the Retry-After header (503, 409 on unfinished jobs)

  // The body, with "instance" (the request path) and "request_id" added.
  nlohmann::json to_json(const std::string& instance, const std::string& request_id) const;
};

std::string problem_type_uri(const std::string& slug);

// Thrown by handlers for errors decided at the HTTP layer (411, 415, 404, 503 ...).
class HttpError : public std::runtime_error {
 public:
  explicit HttpError(Problem p) : std::runtime_error(p.detail), problem_(std::move(p)) {}
  const Problem& problem() const noexcept { return problem_; }

 private:
  Problem problem_;
};

// Builders for the common cases.
Problem make_problem(int status, std::string type, std::string title, std::string detail);

// Maps any exception to its problem (never throws):
//   HttpError -> its problem; InvalidParamsError -> 400 invalid-params naming "field" (with the
//   accepted range when the field is numeric); io::FormatError -> 400 malformed-mesh;
//   InvalidMeshError -> 400 invalid-mesh; io::UnsupportedError -> 422 unsupported-content;
//   io::LimitError -> 413 too-large; SolverError -> 422 solver-failed; CancelledError -> 409
//   cancelled; bad_alloc -> 503 out-of-memory; anything else -> 500 internal.
Problem problem_from_exception(std::exception_ptr error);

}  // namespace mdn::http
