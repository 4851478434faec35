// The HTTP API end to end against the real binary: synchronous and asynchronous round trips
// byte-for-byte equal to the CLI's output, multipart forms, idempotency, cancellation, time
// limit, result expiry, auth, CORS, request ids, /v1/params and /metrics.
#include <algorithm>
#include <string>
#include <vector>

#include "http_fixture.h"

#include "service/params_json.h"

namespace mdn::test {
namespace {

using nlohmann::json;

class HttpApi : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(fs::exists(server_binary())) << server_binary() << " was not built";
    dir_ = temp_dir("api");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // The CLI's output for the same input and parameters.
  std::string cli_output(const std::string& input, const std::string& in_ext, const std::string& out_ext,
                         const std::string& params) {
    const std::string in = dir_ + "/in." + in_ext, out = dir_ + "/out." + out_ext;
    write_file(in, input);
    fs::remove(out);
    const auto [code, text] = run_command(cli_binary() + " --params " + shell_quote(params) + " " + shell_quote(in) +
                                          " " + shell_quote(out) + " 2>&1");
    EXPECT_EQ(code, 0) << text;
    return read_file(out);
  }

  std::string dir_;
};

TEST_F(HttpApi, SynchronousDenoiseEqualsCliOutputByteForByte) {
  ServerProcess server({"--workers", "2"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string noisy = noisy_sphere_off(3, 11);
  const std::string params = R"({"n_normal":12,"n_vertex":8,"sigma_gamma":35})";
  const std::string expected = cli_output(noisy, "off", "off", params);
  ASSERT_FALSE(expected.empty());

  auto c = server.client();
  httplib::Headers headers = {{"X-Denoise-Params", params}, {"X-Request-Id", "sync-test-1"}};
  auto r = c->Post("/v1/denoise", headers, noisy, "model/x-off");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->body, expected);
  EXPECT_EQ(r->get_header_value("X-Request-Id"), "sync-test-1");
  EXPECT_EQ(r->get_header_value("X-Denoise-Faces"), "1280");
  EXPECT_EQ(r->get_header_value("X-Denoise-Input-Bytes"), std::to_string(noisy.size()));
  EXPECT_EQ(r->get_header_value("X-Denoise-Output-Bytes"), std::to_string(expected.size()));
  // The effective parameters: every field, the given ones changed, the others at core's defaults.
  // (output.format resolved to the input's container).
  const json effective = parse_json(r->get_header_value("X-Denoise-Params"));
  json expected_params = service::to_json(service::job_params_from_text(params));
  expected_params["output"]["format"] = "off";
  EXPECT_EQ(effective, expected_params);
  EXPECT_EQ(effective["n_normal"], 12);
  // What ran, in the bounded summary header (issue 51): auto mode chose the unpinned fields.
  const json summary = parse_json(r->get_header_value("X-Denoise-Summary"));
  EXPECT_LT(r->get_header_value("X-Denoise-Summary").size(), 1000u);
  EXPECT_EQ(summary["surfaces"], 1);
  EXPECT_EQ(summary["more"], 0);
  EXPECT_EQ(summary["ran"][0]["mode"], "auto");
  EXPECT_EQ(summary["ran"][0]["params"]["n_normal"], 12);
  EXPECT_EQ(summary["ran"][0]["params"]["sigma_gamma"], 35);
  EXPECT_FALSE(r->has_header("X-Denoise-Report"));
  // The full report: ?report=1 answers multipart/mixed, the mesh and then the result's JSON
  // with what auto measured.
  auto full = c->Post("/v1/denoise?report=1", headers, noisy, "model/x-off");
  ASSERT_TRUE(full);
  ASSERT_EQ(full->status, 200) << full->body;
  const std::string type = full->get_header_value("Content-Type");
  ASSERT_EQ(type.rfind("multipart/mixed; boundary=", 0), 0u) << type;
  const std::string boundary = "--" + type.substr(type.find('=') + 1);
  const std::size_t mesh_at = full->body.find("\r\n\r\n") + 4;
  const std::size_t json_part = full->body.find("\r\n" + boundary + "\r\nContent-Type: application/json\r\n\r\n");
  ASSERT_NE(json_part, std::string::npos) << full->body.substr(0, 300);
  EXPECT_EQ(full->body.substr(mesh_at, json_part - mesh_at), expected);
  const std::size_t json_at = full->body.find("\r\n\r\n", json_part + 2) + 4;
  const json result = parse_json(full->body.substr(json_at, full->body.rfind("\r\n" + boundary + "--") - json_at));
  const json& report = result["reports"];
  ASSERT_TRUE(report.is_array() && report.size() == 1) << result;
  EXPECT_EQ(report[0]["mode"], "auto");
  EXPECT_EQ(report[0]["params"]["n_normal"], 12);
  EXPECT_TRUE(report[0]["params"]["alpha"].is_number());
  EXPECT_GT(report[0]["measures"]["noise"].get<double>(), 0);
  const std::string timing = r->get_header_value("Server-Timing");
  for (const char* stage : {"queue;dur=", "decode;dur=", "prefilter;dur=", "normal;dur=", "vertex;dur=", "encode;dur=",
                            "total;dur="})
    EXPECT_NE(timing.find(stage), std::string::npos) << timing;

  // The same through ?params= (URL-encoded by the client) and as a multipart form.
  auto q = c->Post(("/v1/denoise?params=" + url_encode(params)).c_str(), noisy, "text/plain");
  ASSERT_TRUE(q);
  EXPECT_EQ(q->status, 200) << q->body;
  EXPECT_EQ(q->body, expected);
  httplib::MultipartFormDataItems form = {{"mesh", noisy, "noisy.off", "application/octet-stream"},
                                          {"params", params, "", "application/json"}};
  auto m = c->Post("/v1/denoise", form);
  ASSERT_TRUE(m);
  EXPECT_EQ(m->status, 200) << m->body;
  EXPECT_EQ(m->body, expected);
}

TEST_F(HttpApi, AsynchronousJobEqualsCliOutputAndReportsProgress) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string noisy = noisy_sphere_off(3, 12);
  const std::string params = R"({"n_aniso":1,"output":{"format":"ply"}})";
  const std::string expected = cli_output(noisy, "off", "ply", params);

  auto c = server.client();
  auto r = c->Post(("/v1/jobs?params=" + url_encode(params)).c_str(), noisy, "model/x-off");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string location = r->get_header_value("Location");
  EXPECT_FALSE(r->get_header_value("Retry-After").empty());
  const json created = parse_json(r->body);
  EXPECT_EQ(location, "/v1/jobs/" + created.value("id", ""));
  // A job this small may finish before its 202 is written (a worker starts it at once).
  const std::string first = created.value("state", "");
  EXPECT_TRUE(first == "queued" || first == "running" || first == "succeeded") << first;

  const json done = wait_job(*c, created["id"]);
  ASSERT_EQ(done.value("state", ""), "succeeded") << done.dump();
  EXPECT_EQ(done["progress"]["stage"], "done");
  EXPECT_DOUBLE_EQ(done["progress"]["fraction"].get<double>(), 1.0);
  EXPECT_EQ(done["result"]["faces"], 1280);
  EXPECT_EQ(done["result"]["format"], "ply");
  EXPECT_EQ(done["result"]["params"], service::to_json(service::job_params_from_text(params)));  // format given
  EXPECT_GT(done["result"]["timings_ms"]["normal_filter"].get<double>(), 0.0);
  // The job's run holds its decode, denoise and encode steps (1 ms of slack for rounding).
  const json& ms = done["result"]["timings_ms"];
  EXPECT_LE(ms["decode"].get<double>() + ms["denoise"].get<double>() + ms["encode"].get<double>(),
            done["timings_s"]["run"].get<double>() * 1000 + 1);

  auto result = c->Get(location + "/result");
  ASSERT_TRUE(result);
  ASSERT_EQ(result->status, 200);
  EXPECT_EQ(result->body, expected);
  // One byte range is honoured.
  auto part = c->Get(location + "/result", {{"Range", "bytes=0-9"}});
  ASSERT_TRUE(part);
  EXPECT_EQ(part->status, 206);
  EXPECT_EQ(part->body, expected.substr(0, 10));
  // A finished job is deleted by DELETE, and then gone.
  auto del = c->Delete(location);
  ASSERT_TRUE(del);
  EXPECT_EQ(del->status, 204);
  expect_problem(c->Get(location), 404);
}

// A result download honours one byte range: a suffix range counts from the end, an open one
// runs to it, a last byte past the end is clamped to the result's, a first byte past it is a
// 416 that names the size; an error answer is never sliced by a Range header.
TEST_F(HttpApi, ResultByteRangesAsRfc9110Says) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string noisy = noisy_sphere_off(2, 3);
  auto c = server.client();
  auto r = c->Post("/v1/jobs?params=%7B%22mode%22%3A%22none%22%7D", noisy, "model/x-off");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 202) << r->body;
  const std::string location = r->get_header_value("Location");
  ASSERT_EQ(wait_job(*c, parse_json(r->body)["id"]).value("state", ""), "succeeded");
  auto full = c->Get(location + "/result");
  ASSERT_TRUE(full && full->status == 200);
  const std::string bytes = full->body;
  const std::string size = std::to_string(bytes.size());
  const struct {
    std::string range, body, content_range;
  } cases[] = {
      {"bytes=0-9", bytes.substr(0, 10), "bytes 0-9/" + size},
      {"bytes=-5", bytes.substr(bytes.size() - 5), "bytes " + std::to_string(bytes.size() - 5) + "-" + std::to_string(bytes.size() - 1) + "/" + size},
      {"bytes=10-", bytes.substr(10), "bytes 10-" + std::to_string(bytes.size() - 1) + "/" + size},
      {"bytes=3-99999999", bytes.substr(3), "bytes 3-" + std::to_string(bytes.size() - 1) + "/" + size},
  };
  for (const auto& k : cases) {
    auto part = c->Get(location + "/result", {{"Range", k.range}});
    ASSERT_TRUE(part);
    EXPECT_EQ(part->status, 206) << k.range;
    EXPECT_EQ(part->body, k.body) << k.range;
    EXPECT_EQ(part->get_header_value("Content-Range"), k.content_range) << k.range;
  }
  auto beyond = c->Get(location + "/result", {{"Range", "bytes=" + size + "-"}});
  expect_problem(beyond, 416);
  EXPECT_EQ(beyond->get_header_value("Content-Range"), "bytes */" + size);
  // An error answer with a Range header: the whole problem document, not a slice of it.
  const json missing = expect_problem(c->Get("/v1/jobs/0123456789abcdef0123456789abcdef/result", {{"Range", "bytes=0-3"}}), 404);
  EXPECT_EQ(missing.value("status", 0), 404);
}

TEST_F(HttpApi, GlbRoundTripEqualsCli) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  // OFF in, Draco-compressed GLB out; then that GLB in, GLB out: both equal the CLI's bytes.
  const std::string noisy = noisy_sphere_off(3, 13);
  const std::string to_glb = R"({"output":{"format":"glb","draco":true}})";
  auto c = server.client();
  auto r = c->Post("/v1/denoise", {{"X-Denoise-Params", to_glb}}, noisy, "model/x-off");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_EQ(r->get_header_value("Content-Type"), "model/gltf-binary");
  EXPECT_EQ(r->body.substr(0, 4), "glTF");
  EXPECT_EQ(r->body, cli_output(noisy, "off", "glb", to_glb));

  const std::string glb = r->body;
  auto again = c->Post("/v1/denoise", glb, "model/gltf-binary");
  ASSERT_TRUE(again);
  ASSERT_EQ(again->status, 200) << again->body;
  EXPECT_EQ(again->body, cli_output(glb, "glb", "glb", "{}"));
}

TEST_F(HttpApi, IdempotencyKeyReturnsTheSameJob) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string a = noisy_sphere_off(2, 1), b = noisy_sphere_off(2, 2);
  auto first = c->Post("/v1/jobs", {{"Idempotency-Key", "k-1"}}, a, "model/x-off");
  auto second = c->Post("/v1/jobs", {{"Idempotency-Key", "k-1"}}, a, "model/x-off");
  ASSERT_TRUE(first && second);
  ASSERT_EQ(first->status, 202);
  ASSERT_EQ(second->status, 202);
  EXPECT_EQ(first->get_header_value("Location"), second->get_header_value("Location"));
  EXPECT_EQ(second->get_header_value("Idempotent-Replayed"), "true");
  // Same key, other body: refused. Other key, same body: a new job.
  expect_problem(c->Post("/v1/jobs", {{"Idempotency-Key", "k-1"}}, b, "model/x-off"), 422);
  auto other = c->Post("/v1/jobs", {{"Idempotency-Key", "k-2"}}, a, "model/x-off");
  ASSERT_TRUE(other);
  EXPECT_EQ(other->status, 202);
  EXPECT_NE(other->get_header_value("Location"), first->get_header_value("Location"));
}

// A job that runs for seconds: a 20k-face sphere with the maximum iteration counts.

TEST_F(HttpApi, DeleteCancelsQueuedAndRunningJobs) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string heavy = noisy_sphere_off(5, 3);
  auto running = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, heavy, "model/x-off");
  auto queued = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, heavy, "model/x-off");
  ASSERT_TRUE(running && queued);
  ASSERT_EQ(running->status, 202);
  ASSERT_EQ(queued->status, 202);
  const std::string running_url = running->get_header_value("Location");
  const std::string queued_url = queued->get_header_value("Location");
  // Wait until the first one runs.
  for (int i = 0; i < 200; ++i) {
    if (parse_json(c->Get(running_url)->body).value("state", "") == "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  auto d1 = c->Delete(queued_url);
  ASSERT_TRUE(d1);
  EXPECT_EQ(d1->status, 200);
  EXPECT_EQ(parse_json(d1->body).value("state", ""), "cancelled");
  auto d2 = c->Delete(running_url);
  ASSERT_TRUE(d2);
  EXPECT_EQ(d2->status, 202);
  EXPECT_TRUE(parse_json(d2->body).value("cancel_requested", false));
  const json stopped = wait_job(*c, parse_json(running->body)["id"], std::chrono::seconds(20));
  EXPECT_EQ(stopped.value("state", ""), "cancelled") << stopped.dump();
  const json p = expect_problem(c->Get(running_url + "/result"), 409);
  EXPECT_EQ(p.value("job_state", ""), "cancelled");
}

// GET /v1/jobs/{id}?wait=S: one request instead of a polling loop.
TEST_F(HttpApi, LongPollAnswersWhenTheJobFinishesOrTheWaitEnds) {
  using Ms = std::chrono::milliseconds;
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  auto heavy = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, noisy_sphere_off(6, 3), "model/x-off");
  ASSERT_TRUE(heavy);
  ASSERT_EQ(heavy->status, 202);
  const std::string heavy_url = heavy->get_header_value("Location");

  // The wait ends first: the job as it is then, after about that long.
  auto t = std::chrono::steady_clock::now();
  auto r = c->Get(heavy_url + "?wait=0.4");
  ASSERT_TRUE(r);
  ASSERT_EQ(r->status, 200) << r->body;
  EXPECT_GE(std::chrono::duration_cast<Ms>(std::chrono::steady_clock::now() - t).count(), 390);
  const std::string state = parse_json(r->body).value("state", "");
  EXPECT_TRUE(state == "queued" || state == "running") << state;
  EXPECT_EQ(r->get_header_value("Retry-After"), "1");

  // The job ends first (cancelled from another connection once the long poll waits, as
  // /metrics shows): the answer comes then, long before the client's 20 s read timeout.
  std::thread canceller([&] {
    auto m = server.client();
    for (int i = 0; i < 500 && metric_value(m->Get("/metrics")->body, "mdn_long_polls") != 1; ++i)
      std::this_thread::sleep_for(Ms(20));
    m->Delete(heavy_url);
  });
  auto waiting = server.client(20);
  r = waiting->Get(heavy_url + "?wait=60");
  canceller.join();
  ASSERT_TRUE(r) << "the long poll did not answer when the job ended";
  EXPECT_EQ(parse_json(r->body).value("state", ""), "cancelled") << r->body;
  EXPECT_TRUE(r->get_header_value("Retry-After").empty());
  EXPECT_EQ(metric_value(c->Get("/metrics")->body, "mdn_long_polls"), 0);

  // A small job: one long poll sees it succeed.
  auto small = c->Post("/v1/jobs", noisy_sphere_off(3, 5), "model/x-off");
  ASSERT_TRUE(small);
  r = c->Get(small->get_header_value("Location") + "?wait=60");
  ASSERT_TRUE(r);
  EXPECT_EQ(parse_json(r->body).value("state", ""), "succeeded") << r->body;
  // wait=0 answers at once.
  r = c->Get(small->get_header_value("Location") + "?wait=0");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);

  for (const char* bad : {"-1", "61", "abc", "", "1s", "nan", "inf"}) {
    const json p = expect_problem(c->Get(heavy_url + "?wait=" + url_encode(bad)), 400);
    EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:invalid-query") << bad;
    EXPECT_EQ(p.value("field", ""), "wait") << bad;
    EXPECT_EQ(p.value("maximum", 0), 60) << bad;
  }
  expect_problem(c->Get("/v1/jobs/0123456789abcdef0123456789abcdef?wait=5"), 404);
}

TEST_F(HttpApi, JobTimeLimitFailsTheJob) {
  ServerProcess server({"--workers", "1", "--job-time-limit", "0.3"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string heavy = noisy_sphere_off(5, 4);
  const json p = expect_problem(c->Post("/v1/denoise", {{"X-Denoise-Params", kHeavyParams}}, heavy, "model/x-off"), 504);
  EXPECT_EQ(p.value("type", ""), "urn:meshdenoise:problem:time-limit-exceeded");
  auto r = c->Post("/v1/jobs", {{"X-Denoise-Params", kHeavyParams}}, heavy, "model/x-off");
  ASSERT_TRUE(r);
  const json job = wait_job(*c, parse_json(r->body)["id"], std::chrono::seconds(20));
  EXPECT_EQ(job.value("state", ""), "failed");
  EXPECT_EQ(job["error"].value("status", 0), 504);
  // The server still works.
  auto ok = c->Post("/v1/denoise", noisy_sphere_off(1), "model/x-off");
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
}

TEST_F(HttpApi, ResultsExpire) {
  ServerProcess server({"--workers", "1", "--result-ttl", "0.5"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  auto r = c->Post("/v1/jobs", noisy_sphere_off(1), "model/x-off");
  ASSERT_TRUE(r);
  const std::string id = parse_json(r->body)["id"];
  EXPECT_EQ(wait_job(*c, id).value("state", ""), "succeeded");
  std::this_thread::sleep_for(std::chrono::milliseconds(1200));
  expect_problem(c->Get("/v1/jobs/" + id), 404);
  expect_problem(c->Get("/v1/jobs/" + id + "/result"), 404);
}

TEST_F(HttpApi, BearerTokenAuth) {
  ServerProcess server({}, {"MDN_AUTH_TOKEN=s3cret"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  auto denied = c->Get("/v1/params");
  const json p = expect_problem(denied, 401);
  EXPECT_EQ(denied->get_header_value("WWW-Authenticate").rfind("Bearer", 0), 0u);
  expect_problem(c->Get("/v1/params", {{"Authorization", "Bearer wrong"}}), 401);
  auto ok = c->Get("/v1/params", {{"Authorization", "Bearer s3cret"}});
  ASSERT_TRUE(ok);
  EXPECT_EQ(ok->status, 200);
  // Probes stay open for orchestrators.
  EXPECT_EQ(c->Get("/healthz")->status, 200);
  EXPECT_EQ(c->Get("/readyz")->status, 200);
}

TEST_F(HttpApi, CorsRequestIdsParamsAndMetrics) {
  ServerProcess server({});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  // CORS preflight and exposed headers.
  auto pre = c->Options("/v1/denoise", {{"Origin", "http://example.org"},
                                        {"Access-Control-Request-Method", "POST"},
                                        {"Access-Control-Request-Headers", "X-Denoise-Params"}});
  ASSERT_TRUE(pre);
  EXPECT_EQ(pre->status, 204);
  EXPECT_EQ(pre->get_header_value("Access-Control-Allow-Origin"), "*");
  EXPECT_NE(pre->get_header_value("Access-Control-Allow-Methods").find("POST"), std::string::npos);
  EXPECT_NE(pre->get_header_value("Access-Control-Allow-Headers").find("X-Denoise-Params"), std::string::npos);
  auto health = c->Get("/healthz", {{"Origin", "http://example.org"}});
  const std::string exposed = health->get_header_value("Access-Control-Expose-Headers");
  for (const char* h : {"Location", "Retry-After", "X-Request-Id"}) EXPECT_NE(exposed.find(h), std::string::npos);

  // Request ids: honoured when valid, generated (and unique) otherwise.
  EXPECT_EQ(c->Get("/healthz", {{"X-Request-Id", "abc-123"}})->get_header_value("X-Request-Id"), "abc-123");
  const std::string g1 = c->Get("/healthz", {{"X-Request-Id", "bad id with spaces"}})->get_header_value("X-Request-Id");
  const std::string g2 = c->Get("/healthz")->get_header_value("X-Request-Id");
  EXPECT_FALSE(g1.empty());
  EXPECT_NE(g1, "bad id with spaces");
  EXPECT_NE(g1, g2);

  // /v1/params: core's defaults and ranges, and the schema.
  auto params = c->Get("/v1/params");
  ASSERT_EQ(params->status, 200);
  const json pj = parse_json(params->body);
  EXPECT_EQ(pj["defaults"], service::to_json(service::JobParams{}));
  ASSERT_EQ(pj["parameters"].size(), param_specs().size());
  EXPECT_EQ(pj["parameters"][0]["name"], "alpha");
  EXPECT_EQ(pj["schema"]["type"], "object");

  // /metrics counts what happened. The job's own metrics hold as soon as its response is in
  // (the job is counted, and its worker free, before its end is published): no polling.
  ASSERT_EQ(c->Post("/v1/denoise", noisy_sphere_off(1), "model/x-off")->status, 200);
  auto m = c->Get("/metrics");
  ASSERT_EQ(m->status, 200);
  for (const char* line : {"mdn_jobs_total{state=\"succeeded\"} 1", "mdn_job_duration_seconds_count 1",
                           "mdn_job_queue_wait_seconds_bucket{le=\"+Inf\"} 1", "mdn_queue_depth 0",
                           "mdn_jobs_running 0"})
    EXPECT_NE(m->body.find(line), std::string::npos) << line << "\n" << m->body;
  expect_problem(c->Get("/v1/jobs/unknown"), 404);
  // Requests are counted once their response is written, by the thread that wrote it (each of
  // these requests has a connection, so a thread, of its own): poll briefly for all of them.
  const std::vector<std::string> counted = {
      "mdn_http_requests_total{route=\"/v1/denoise\",method=\"POST\",status=\"200\"} 1",
      "mdn_http_requests_total{route=\"/v1/jobs/{id}\",method=\"GET\",status=\"404\"} 1"};
  auto all_counted = [&] {
    return std::all_of(counted.begin(), counted.end(), [&](const std::string& l) { return m->body.find(l) != std::string::npos; });
  };
  for (int i = 0; i < 100 && !all_counted(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    m = c->Get("/metrics");
    ASSERT_EQ(m->status, 200);
  }
  for (const std::string& line : counted) EXPECT_NE(m->body.find(line), std::string::npos) << line << "\n" << m->body;
  for (const char* line : {"mdn_http_request_bytes_total ", "mdn_http_response_bytes_total "})
    EXPECT_NE(m->body.find(line), std::string::npos) << line << "\n" << m->body;
}

TEST_F(HttpApi, HelpListsEverySettingAndBadFlagsFail) {
  const auto [code, text] = run_command(server_binary() + " --help");
  EXPECT_EQ(code, 0);
  for (const char* flag : {"--host", "--port", "--workers", "--threads-per-job", "--queue-capacity", "--max-body",
                           "--max-faces", "--job-time-limit", "--result-ttl", "--keep-alive-timeout", "--read-timeout",
                           "--write-timeout", "--io-threads", "--drain-grace", "--auth-token", "--cors-origin",
                           "--log-format", "MDN_WORKERS", "MDN_AUTH_TOKEN"})
    EXPECT_NE(text.find(flag), std::string::npos) << flag;
  EXPECT_EQ(run_command(server_binary() + " --workers -3 2>&1").first, 2);
  EXPECT_EQ(run_command(server_binary() + " --no-such-flag 2>&1").first, 2);
  EXPECT_EQ(run_command("MDN_QUEUE_CAPACITY=zero " + server_binary() + " 2>&1").first, 2);
  const auto [bad_limit, message] = run_command(server_binary() + " --max-json-depth 0 2>&1");
  EXPECT_EQ(bad_limit, 2);
  EXPECT_NE(message.find("--max-json-depth"), std::string::npos) << message;
}

TEST_F(HttpApi, JsonLogsCarryRequestIds) {
  ServerProcess server({"--log-format", "json"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  ASSERT_EQ(c->Get("/v1/params", {{"X-Request-Id", "log-me-42"}})->status, 200);
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  bool found = false;
  std::istringstream lines(server.log());
  for (std::string line; std::getline(lines, line);) {
    const json j = parse_json(line);
    ASSERT_TRUE(j.is_object()) << "not a JSON line: " << line;
    if (j.value("request_id", "") == "log-me-42") {
      found = true;
      EXPECT_EQ(j.value("event", ""), "request");
      EXPECT_EQ(j.value("status", 0), 200);
      EXPECT_EQ(j.value("route", ""), "/v1/params");
    }
  }
  EXPECT_TRUE(found) << server.log();
}

}  // namespace
}  // namespace mdn::test
