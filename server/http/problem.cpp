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
  Problem p = make_problem(400, "invalid-params", "Invalid parameters", e.what());
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
      return make_problem(400, "malformed-mesh", "Malformed mesh file", e.what());
    } catch (const InvalidMeshError& e) {
      return make_problem(400, "invalid-mesh", "Invalid mesh", e.what());
    } catch (const io::UnsupportedError& e) {
      Problem p = make_problem(422, "unsupported-content", "Unsupported content", e.what());
      p.extensions["unsupported"] = e.what();
      return p;
    } catch (const io::LimitError& e) {
      return make_problem(413, "too-large", "Content too large", e.what());
    } catch (const SolverError& e) {
      return make_problem(422, "solver-failed", "The linear solver failed on this mesh", e.what());
    } catch (const CancelledError& e) {
      return make_problem(409, "cancelled", "Job cancelled", e.what());
    } catch (const std::bad_alloc&) {
      Problem p = make_problem(503, "out-of-memory", "Out of memory", "the server ran out of memory for this request");
      p.retry_after_s = 5;
      return p;
    } catch (const std::exception& e) {
      return make_problem(500, "internal", "Internal server error", e.what());
    } catch (...) {
      return make_problem(500, "internal", "Internal server error", "unknown exception");
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
