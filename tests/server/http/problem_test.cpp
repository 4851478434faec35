// The problem catalogue and the mapping of exceptions to problems (RFC 9457).
#include "server/http/problem.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <functional>
#include <fstream>
#include <new>
#include <regex>
#include <set>
#include <sstream>

#include "core/errors.h"
#include "core/io/document.h"
#include "core/params.h"

namespace mdn::http {
namespace {

std::string openapi_text() {
  // ctest sets MDN_SOURCE_DIR; the build compiles the tree's path in for runs by hand.
  const char* source = std::getenv("MDN_SOURCE_DIR");
  const std::filesystem::path root = source ? source : MDN_DEFAULT_SOURCE_DIR;
  std::ifstream in(root / "proto" / "openapi.yaml");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(ProblemCatalogue, SlugsAreUniqueAndTheOpenApiDocumentListsExactlyThem) {
  std::set<std::string> code;
  for (const ProblemKind& k : problem_catalogue()) {
    EXPECT_TRUE(code.insert(std::string(k.slug)).second) << k.slug;
    EXPECT_FALSE(k.title.empty()) << k.slug;
    EXPECT_GE(k.status, 400) << k.slug;
    EXPECT_LT(k.status, 600) << k.slug;
  }
  const std::string doc = openapi_text();
  ASSERT_FALSE(doc.empty());
  std::set<std::string> documented;
  const std::regex urn("urn:meshdenoise:problem:([a-z-]+)");
  for (auto it = std::sregex_iterator(doc.begin(), doc.end(), urn); it != std::sregex_iterator(); ++it)
    documented.insert((*it)[1]);
  EXPECT_EQ(documented, code);
}

TEST(ProblemCatalogue, BuildersTakeSlugTitleAndStatusFromTheTable) {
  const Problem p = make_problem(ProblemType::QueueFull, "the job queue is full");
  EXPECT_EQ(p.status, 503);
  EXPECT_EQ(p.type, "queue-full");
  EXPECT_EQ(p.title, "Job queue full");
  EXPECT_EQ(p.detail, "the job queue is full");
  EXPECT_EQ(cancelled_before_start().status, 409);
  EXPECT_EQ(cancelled_before_start().type, "cancelled");
  const Problem missing = job_not_found("a\r\nSet-Cookie: x");
  EXPECT_EQ(missing.status, 404);
  EXPECT_EQ(missing.detail.find('\n'), std::string::npos) << "no control characters of the id in the detail";
}

TEST(ProblemCatalogue, BodyHasTheRfc9457MembersAndKeepsExtensions) {
  Problem p = make_problem(ProblemType::InvalidQuery, "wait must be a number");
  p.extensions["field"] = "wait";
  const nlohmann::json j = p.to_json("/v1/jobs/x", "req-1");
  EXPECT_EQ(j["type"], "urn:meshdenoise:problem:invalid-query");
  EXPECT_EQ(j["status"], 400);
  EXPECT_EQ(j["instance"], "/v1/jobs/x");
  EXPECT_EQ(j["request_id"], "req-1");
  EXPECT_EQ(j["field"], "wait");
}

std::string title_of(const std::string& slug) {
  for (const ProblemKind& k : problem_catalogue())
    if (k.slug == slug) return std::string(k.title);
  return "(no such slug)";
}

Problem from(auto&& thrower) {
  try {
    thrower();
  } catch (...) {
    return problem_from_exception(std::current_exception());
  }
  ADD_FAILURE() << "did not throw";
  return {};
}

TEST(ProblemMapping, EachExceptionBecomesItsProblem) {
  struct Case {
    std::function<void()> thrower;
    std::string slug;
    int status;
  };
  const Case cases[] = {
      {[] { throw io::FormatError("bad header"); }, "malformed-mesh", 400},
      {[] { throw InvalidMeshError("index out of range"); }, "invalid-mesh", 400},
      {[] { throw io::UnsupportedError("sparse morph targets"); }, "unsupported-content", 422},
      {[] { throw io::LimitError("too many faces"); }, "too-large", 413},
      {[] { throw SolverError("not positive definite"); }, "solver-failed", 422},
      {[] { throw CancelledError(); }, "cancelled", 409},
      {[] { throw std::bad_alloc(); }, "out-of-memory", 503},
      {[] { throw std::runtime_error("oops"); }, "internal", 500},
      {[] { throw 42; }, "internal", 500},
      {[] { throw HttpError(make_problem(ProblemType::Draining, "bye")); }, "draining", 503},
  };
  for (const Case& c : cases) {
    const Problem p = from(c.thrower);
    EXPECT_EQ(p.type, c.slug);
    EXPECT_EQ(p.status, c.status) << c.slug;
    EXPECT_EQ(p.title, title_of(c.slug)) << c.slug;
  }
  EXPECT_EQ(from([] { throw std::bad_alloc(); }).retry_after_s, 5);
}

TEST(ProblemMapping, InvalidParamsNameTheFieldAndItsRange) {
  const Problem p = from([] { throw InvalidParamsError("n_normal", "must be at most 1000"); });
  EXPECT_EQ(p.status, 400);
  EXPECT_EQ(p.type, "invalid-params");
  EXPECT_EQ(p.extensions["field"], "n_normal");
  ASSERT_TRUE(p.extensions.contains("maximum"));
  EXPECT_TRUE(p.extensions["integer"].get<bool>());
  // An output field is not one of the method's parameters: no range.
  const Problem out = from([] { throw InvalidParamsError("output.position_bits", "bad"); });
  EXPECT_FALSE(out.extensions.contains("maximum"));
}

}  // namespace
}  // namespace mdn::http
