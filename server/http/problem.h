// RFC 9457 problem details: the one error shape of the HTTP API. Every handler is wrapped
// once (http_server.cpp); whatever it throws becomes a Problem through problem_from_exception.
#pragma once

#include <exception>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

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

// Every problem type the server answers with: one row per slug, its fixed title and status.
// proto/openapi.yaml lists the same slugs (components.schemas.Problem.properties.type.enum).
enum class ProblemType {
  // Requests the HTTP layer refuses.
  BadRequest, BadBody, BadForm, BadIdempotencyKey, EmptyBody, InvalidQuery, Unauthorized, NotFound,
  MethodNotAllowed, RequestTimeout, LengthRequired, TooLarge, UriTooLong, UnsupportedMediaType, RangeNotSatisfiable,
  MultipleRanges, TooManyHeaders, HttpError,
  // The job's input and parameters.
  InvalidParams, MalformedMesh, InvalidMesh, UnsupportedContent, SolverFailed, ResultTooLarge,
  // Jobs and their store.
  JobNotFound, JobNotFinished, JobFailed, JobCancelled, Cancelled, TimeLimitExceeded, IdempotencyKeyReused,
  AttemptsExhausted, InputLost, QueueFull, StoreFull, OverClientShare, QueueUnavailable, QueueError, Draining, ShuttingDown,
  // The server itself.
  OutOfMemory, Internal,
};

struct ProblemKind {
  ProblemType type;
  std::string_view slug;
  std::string_view title;
  int status;  // HttpError: the status httplib answered with replaces it
};

// The catalogue, in the enum's order.
std::span<const ProblemKind> problem_catalogue();
const ProblemKind& problem_kind(ProblemType type);

// The problem of `type` with its slug, title and status from the catalogue.
Problem make_problem(ProblemType type, std::string detail);
// 409 cancelled by DELETE: before the job started (memory and Redis stores alike).
Problem cancelled_before_start();
// 404 job-not-found for a job id as the client sent it (sanitised for the detail).
Problem job_not_found(std::string_view id);
// A problem read back from storage (the Redis store keeps a finished job's error as JSON).
Problem make_problem(int status, std::string type, std::string title, std::string detail);

// Maps any exception to its problem (never throws):
//   HttpError -> its problem; InvalidParamsError -> 400 invalid-params naming "field" (with the
//   accepted range when the field is numeric); io::FormatError -> 400 malformed-mesh;
//   InvalidMeshError -> 400 invalid-mesh; io::UnsupportedError -> 422 unsupported-content;
//   io::LimitError -> 413 too-large; SolverError -> 422 solver-failed; CancelledError -> 409
//   cancelled; bad_alloc -> 503 out-of-memory; anything else -> 500 internal.
Problem problem_from_exception(std::exception_ptr error);

}  // namespace mdn::http
