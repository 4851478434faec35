#include "server/http/problem.h"

#include <new>

#include "core/errors.h"
#include "core/io/document.h"
#include "core/params.h"

namespace mdn::http {

std::string problem_type_uri(const std::string& slug) { return "urn:meshdenoise:problem:" + slug; }

nlohmann::json Problem::to_json(const std::string& instance, const std::string& request_id) const {
  nlohmann::json j = extensions.is_object() ? extensions : nlohmann::json::object();
  j["type"] = problem_type_uri(type);
  j["title"] = title;
  j["status"] = status;
  j["detail"] = detail;
  j["instance"] = instance;
  j["request_id"] = request_id;
  return j;
}

namespace {

using T = ProblemType;
constexpr ProblemKind kCatalogue[] = {
    {T::BadRequest, "bad-request", "Bad request", 400},
    {T::BadBody, "bad-body", "Unreadable body", 400},
    {T::BadForm, "bad-form", "Bad form", 400},
    {T::BadIdempotencyKey, "bad-idempotency-key", "Bad Idempotency-Key", 400},
    {T::EmptyBody, "empty-body", "Empty body", 400},
    {T::InvalidQuery, "invalid-query", "Invalid query parameter", 400},
    {T::Unauthorized, "unauthorized", "Unauthorized", 401},
    {T::NotFound, "not-found", "Not found", 404},
    {T::MethodNotAllowed, "method-not-allowed", "Method not allowed", 405},
    {T::RequestTimeout, "request-timeout", "Request body stalled", 408},
    {T::LengthRequired, "length-required", "Length required", 411},
    {T::TooLarge, "too-large", "Content too large", 413},
    {T::UriTooLong, "uri-too-long", "URI too long", 414},
    {T::UnsupportedMediaType, "unsupported-media-type", "Unsupported media type", 415},
    {T::RangeNotSatisfiable, "range-not-satisfiable", "Range not satisfiable", 416},
    {T::MultipleRanges, "multiple-ranges", "Multiple ranges not supported", 416},
    {T::TooManyHeaders, "too-many-headers", "Request header fields too large", 431},
    {T::HttpError, "http-error", "HTTP error", 500},
    {T::InvalidParams, "invalid-params", "Invalid parameters", 400},
    {T::MalformedMesh, "malformed-mesh", "Malformed mesh file", 400},
    {T::InvalidMesh, "invalid-mesh", "Invalid mesh", 400},
    {T::UnsupportedContent, "unsupported-content", "Unsupported content", 422},
    {T::SolverFailed, "solver-failed", "The linear solver failed on this mesh", 422},
    {T::ResultTooLarge, "result-too-large", "Result too large", 422},
    {T::JobNotFound, "job-not-found", "Job not found", 404},
    {T::JobNotFinished, "job-not-finished", "Job not finished", 409},
    {T::JobFailed, "job-failed", "Job has no result", 409},
    {T::JobCancelled, "job-cancelled", "Job has no result", 409},
    {T::Cancelled, "cancelled", "Job cancelled", 409},
    {T::TimeLimitExceeded, "time-limit-exceeded", "Job time limit exceeded", 504},
    {T::IdempotencyKeyReused, "idempotency-key-reused", "Idempotency-Key reused", 422},
    {T::AttemptsExhausted, "attempts-exhausted", "Job failed on every attempt", 500},
    {T::InputLost, "input-lost", "Job input lost", 500},
    {T::QueueFull, "queue-full", "Job queue full", 503},
    {T::StoreFull, "store-full", "Job store full", 503},
    {T::OverClientShare, "over-client-share", "Over this client's share", 429},
    {T::QueueUnavailable, "queue-unavailable", "Job store unavailable", 503},
    {T::QueueError, "queue-error", "Job store error", 500},
    {T::Draining, "draining", "Server draining", 503},
    {T::ShuttingDown, "shutting-down", "Server shutting down", 503},
    {T::OutOfMemory, "out-of-memory", "Out of memory", 503},
    {T::Internal, "internal", "Internal server error", 500},
};

constexpr bool catalogue_in_enum_order() {
  for (std::size_t i = 0; i < std::size(kCatalogue); ++i)
    if (static_cast<std::size_t>(kCatalogue[i].type) != i) return false;
  return static_cast<std::size_t>(T::Internal) + 1 == std::size(kCatalogue);
}
static_assert(catalogue_in_enum_order(), "one catalogue row per ProblemType, in the enum's order");

}  // namespace

std::span<const ProblemKind> problem_catalogue() { return kCatalogue; }

const ProblemKind& problem_kind(ProblemType type) { return kCatalogue[static_cast<std::size_t>(type)]; }

Problem make_problem(ProblemType type, std::string detail) {
  const ProblemKind& kind = problem_kind(type);
  return make_problem(kind.status, std::string(kind.slug), std::string(kind.title), std::move(detail));
}

Problem cancelled_before_start() { return make_problem(ProblemType::Cancelled, "cancelled by DELETE before it started"); }

Problem job_not_found(std::string_view id) {
  std::string safe;
  for (char c : id) safe += (static_cast<unsigned char>(c) < 0x20 || c == 0x7f) ? ' ' : c;
  return make_problem(ProblemType::JobNotFound, "no job '" + safe + "' (unknown, deleted or expired)");
}

Problem make_problem(int status, std::string type, std::string title, std::string detail) {
  Problem p;
  p.status = status;
  p.type = std::move(type);
  p.title = std::move(title);
  p.detail = std::move(detail);
  return p;
}

namespace {

Problem invalid_params(const InvalidParamsError& e) {
  Problem p = make_problem(ProblemType::InvalidParams, e.what());
  p.extensions["field"] = e.field();
  // Name the accepted range of numeric fields (single source: core's param_specs()).
  std::string leaf = e.field();
  if (auto dot = leaf.find_last_of('.'); dot != std::string::npos) leaf = leaf.substr(dot + 1);
  for (const ParamSpec& spec : param_specs()) {
    if (spec.name == leaf && e.field().find("output") == std::string::npos) {
      p.extensions["minimum"] = spec.min;
      p.extensions["maximum"] = spec.max;
      p.extensions["integer"] = spec.integer;
      p.extensions["default"] = spec.default_value();
    }
  }
  return p;
}

}  // namespace

Problem problem_from_exception(std::exception_ptr error) {
  try {
    try {
      std::rethrow_exception(error);
    } catch (const HttpError& e) {
      return e.problem();
    } catch (const InvalidParamsError& e) {
      return invalid_params(e);
    } catch (const io::FormatError& e) {
      return make_problem(ProblemType::MalformedMesh, e.what());
    } catch (const InvalidMeshError& e) {
      return make_problem(ProblemType::InvalidMesh, e.what());
    } catch (const io::UnsupportedError& e) {
      Problem p = make_problem(ProblemType::UnsupportedContent, e.what());
      p.extensions["unsupported"] = e.what();
      return p;
    } catch (const io::LimitError& e) {
      return make_problem(ProblemType::TooLarge, e.what());
    } catch (const SolverError& e) {
      return make_problem(ProblemType::SolverFailed, e.what());
    } catch (const CancelledError& e) {
      return make_problem(ProblemType::Cancelled, e.what());
    } catch (const std::bad_alloc&) {
      Problem p = make_problem(ProblemType::OutOfMemory, "the server ran out of memory for this request");
      p.retry_after_s = 5;
      return p;
    } catch (const std::exception& e) {
      return make_problem(ProblemType::Internal, e.what());
    } catch (...) {
      return make_problem(ProblemType::Internal, "unknown exception");
    }
  } catch (...) {  // building the problem itself failed (e.g. out of memory)
    Problem p;
    p.status = 500;
    p.type = "internal";
    p.title = "Internal server error";
    return p;
  }
}

}  // namespace mdn::http
