// The web page (server/web/) against the real server on loopback: its routes and headers over
// HTTP, then the page itself in headless Chromium (Debian's package) driven by puppeteer-core
// (pinned in tests/tools) through tests/tools/check_web_page.mjs: a noisy mesh uploaded through
// the file input, the job awaited, the canvas and the legend read, the download compared byte for
// byte with POST /v1/denoise, refused files' errors read, every other input format drawn, a long
// job cancelled, every request and console message checked; then what people meet using it:
// status, Cancel and errors in view at 1280x800 and 400x800, no stale panel,
// an invalid field answered inline, heat-map colours equal to the legend's, a large OFF result
// fetched fast, a job cancelled when its page is closed. Screenshots are written to
// <build>/artifacts/web/ (not compared). Needs `npm install` in tests/tools and the Debian
// package `chromium` (scripts/install-deps.sh build test).
#include <algorithm>
#include <chrono>
#include <iostream>
#include <thread>
#include <map>
#include <regex>
#include <set>

#include "browser_fixture.h"

namespace mdn::test {
namespace {

using nlohmann::json;

// Every field of GET /v1/params' schema but the deprecated ones, output fields as
// "output.<name>": what the form must list.
std::vector<std::string> schema_fields(const json& params) {
  std::vector<std::string> out;
  for (const auto& [name, prop] : params.at("schema").at("properties").items()) {
    if (name == "output" && prop.value("type", "") == "object") {
      for (const auto& [sub, p] : prop.at("properties").items())
        if (!p.value("deprecated", false)) out.push_back("output." + sub);
    } else if (!prop.value("deprecated", false)) {
      out.push_back(name);
    }
  }
  return out;
}

// The page's driver (tests/tools/check_web_page.mjs) on a plan.
json run_page(const json& plan, const std::string& dir) { return run_browser_check("check_web_page.mjs", plan, dir); }

// Requests the page made: all to this server (or data:/blob: URLs it made itself).
void expect_loopback_only(const json& report, int port) {
  const std::string origin = "http://127.0.0.1:" + std::to_string(port) + "/";
  ASSERT_FALSE(report.at("requests").empty());
  for (const auto& url : report.at("requests")) {
    const std::string u = url.get<std::string>();
    EXPECT_TRUE(u.rfind(origin, 0) == 0 || u.rfind("data:", 0) == 0 || u.rfind("blob:" + origin.substr(0, origin.size() - 1), 0) == 0)
        << "a request left the server: " << u;
  }
  // No request failed, except a long poll the page dropped itself (it replaced that job).
  for (const auto& f : report.at("failed_requests")) {
    const bool own_abort = f.value("error", "") == "net::ERR_ABORTED" && f.value("url", "").find("?wait=") != std::string::npos;
    EXPECT_TRUE(own_abort) << f;
  }
  EXPECT_TRUE(report.at("page_errors").empty()) << report.at("page_errors");
}

// Console errors: none, except the browser's own line for an answer the step expects (a refused
// file's 415, the first 401 with auth on).
void expect_no_console_errors(const json& report, const std::map<std::string, int>& expected_status_by_phase) {
  for (const auto& m : report.at("console")) {
    if (m.at("type") != "error") continue;
    const std::string phase = m.at("phase"), text = m.at("text");
    const auto it = expected_status_by_phase.find(phase);
    const bool expected = it != expected_status_by_phase.end() &&
                          text.find("status of " + std::to_string(it->second)) != std::string::npos;
    EXPECT_TRUE(expected) << "console error in phase " << phase << ": " << text;
  }
}

TEST(WebPage, ServesThePageAndItsFilesWithTypesCachingAndPolicy) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  auto page = c->Get("/");
  ASSERT_TRUE(page);
  EXPECT_EQ(page->status, 200);
  EXPECT_EQ(page->get_header_value("Content-Type"), "text/html; charset=utf-8");
  EXPECT_EQ(page->get_header_value("Cache-Control"), "no-cache");
  EXPECT_EQ(page->get_header_value("X-Content-Type-Options"), "nosniff");
  const std::string csp = page->get_header_value("Content-Security-Policy");
  EXPECT_NE(csp.find("default-src 'self'"), std::string::npos) << csp;
  EXPECT_NE(csp.find("script-src 'self' 'wasm-unsafe-eval';"), std::string::npos) << csp;
  EXPECT_EQ(csp.find("unsafe-inline"), std::string::npos) << csp;
  EXPECT_EQ(csp.find("http"), std::string::npos) << "no other origin may be allowed: " << csp;
  EXPECT_EQ(page->body, c->Get("/web/index.html")->body);

  // Revalidation: the same ETag gives 304 with no body; another one the file.
  const std::string etag = page->get_header_value("ETag");
  ASSERT_FALSE(etag.empty());
  auto again = c->Get("/", {{"If-None-Match", etag}});
  EXPECT_EQ(again->status, 304);
  EXPECT_TRUE(again->body.empty());
  EXPECT_EQ(c->Get("/", {{"If-None-Match", "\"other\""}})->status, 200);

  // Every module the page imports, transitively, is served by this server with its media type.
  std::set<std::string> seen;
  std::vector<std::string> pending = {"/web/app.js"};
  // Import statements start a line ("import ... from '...'" or "} from '...'" ending a
  // multi-line one); examples in comments do not.
  const std::regex import_re(R"(^(?:import\s[^'"]*?|\} )from\s*'([^']+)')", std::regex::ECMAScript | std::regex::multiline);
  while (!pending.empty()) {
    const std::string url = pending.back();
    pending.pop_back();
    if (!seen.insert(url).second) continue;
    auto r = c->Get(url);
    ASSERT_TRUE(r);
    ASSERT_EQ(r->status, 200) << url;
    EXPECT_EQ(r->get_header_value("Content-Type"), "text/javascript; charset=utf-8") << url;
    for (std::sregex_iterator m(r->body.begin(), r->body.end(), import_re), end; m != end; ++m) {
      const std::string spec = (*m)[1];
      ASSERT_EQ(spec.rfind(".", 0), 0u) << url << " imports the bare specifier '" << spec << "'";
      fs::path target = fs::path(url).parent_path() / spec;
      pending.push_back(target.lexically_normal().string());
    }
  }
  EXPECT_TRUE(seen.count("/web/vendor/three/build/three.core.js"));
  EXPECT_TRUE(seen.count("/web/vendor/three/examples/jsm/loaders/DRACOLoader.js"));
  auto wasm = c->Get("/web/vendor/three/examples/jsm/libs/draco/draco_decoder.wasm");
  EXPECT_EQ(wasm->status, 200);
  EXPECT_EQ(wasm->get_header_value("Content-Type"), "application/wasm");
  EXPECT_EQ(wasm->body.substr(0, 4), std::string("\0asm", 4));
  EXPECT_EQ(c->Get("/web/style.css")->get_header_value("Content-Type"), "text/css; charset=utf-8");

  // gzip-encoded for clients that accept it: another representation with its own strong ETag,
  // the same bytes once decoded (cpp-httplib's client decodes), much smaller on the wire.
  const std::string core = "/web/vendor/three/build/three.core.js";
  auto plain = c->Get(core, {{"Accept-Encoding", "identity"}});
  auto gz = c->Get(core, {{"Accept-Encoding", "gzip, deflate, br"}});
  ASSERT_TRUE(plain && gz);
  EXPECT_EQ(plain->get_header_value("Content-Encoding"), "");
  EXPECT_EQ(gz->get_header_value("Content-Encoding"), "gzip");
  EXPECT_EQ(gz->get_header_value("Vary"), "Accept-Encoding");
  EXPECT_EQ(gz->body, plain->body);
  EXPECT_LT(std::stoll(gz->get_header_value("Content-Length")) * 3, std::stoll(plain->get_header_value("Content-Length")));
  EXPECT_NE(gz->get_header_value("ETag"), plain->get_header_value("ETag"));
  EXPECT_EQ(c->Get(core, {{"Accept-Encoding", "gzip"}, {"If-None-Match", gz->get_header_value("ETag")}})->status, 304);
  EXPECT_EQ(c->Get(core, {{"Accept-Encoding", "gzip;q=0"}})->get_header_value("Content-Encoding"), "");

  expect_problem(c->Get("/web/nope.js"), 404);
  expect_problem(c->Get("/web/../proto/openapi.yaml"), 404);
  expect_problem(c->Post("/", "x", "text/plain"), 405);

  // --web off: an API-only server; the page is a 404, the API unchanged.
  ServerProcess api_only({"--workers", "1", "--web", "off"});
  ASSERT_TRUE(api_only.started()) << api_only.log();
  auto a = api_only.client();
  expect_problem(a->Get("/"), 404);
  expect_problem(a->Get("/web/app.js"), 404);
  EXPECT_EQ(a->Get("/v1/params")->status, 200);
}

TEST(WebPage, DenoisesAnUploadedMeshAndShowsBeforeAndAfter) {
  check_browser_tools();
  ServerProcess server({"--workers", "2"});
  ASSERT_TRUE(server.started()) << server.log();
  auto c = server.client();
  const std::string dir = temp_dir("web");
  const std::string mesh = noisy_cube_off(16, 19);
  write_file(dir + "/noisy-cube.off", mesh);
  const std::string png = std::string("\x89PNG\r\n\x1a\n", 8) + std::string(64, 'x');
  write_file(dir + "/photo.png", png);
  const std::string broken = "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";  // a vertex and a face short
  write_file(dir + "/broken.off", broken);

  // The noisy cube in every other container the service reads (its own output is one), for the
  // page to draw as inputs.
  json formats = json::array();
  for (const std::string format_params : {R"({"format":"glb"})", R"({"format":"gltf","draco":false})",
                                          R"({"format":"drc"})", R"({"format":"obj"})", R"({"format":"ply"})",
                                          R"({"format":"stl"})"}) {
    const json p = {{"mode", "manual"}, {"n_normal", 0}, {"n_vertex", 0}, {"output", json::parse(format_params)}};
    auto r = c->Post("/v1/denoise", {{"X-Denoise-Params", p.dump()}}, mesh, "model/x-off");
    ASSERT_TRUE(r && r->status == 200) << format_params;
    const std::string name = dir + "/noisy-cube." + json::parse(format_params).at("format").get<std::string>();
    write_file(name, r->body);
    formats.push_back(name);
  }
  // A long job to cancel while it runs (seconds: 20k faces with heavy parameters).
  write_file(dir + "/big.off", noisy_sphere_off(5, 3));
  const json heavy_params = json::parse(kHeavyParams);
  json heavy = json::object();
  for (const auto& [k, v] : heavy_params.items()) heavy[k] = std::to_string(v.get<int>());
  // A 4 MB OFF, converted only (mode none): its result is a 4 MB OFF too.
  write_file(dir + "/large.off", off_text(cube(100)));

  // Pinned in the form: one method parameter, the output container and Draco (the page
  // must read it back through DRACOLoader's worker).
  const json plan = {{"url", "http://127.0.0.1:" + std::to_string(server.port()) + "/"},
                     {"out", web_artifacts_dir()},
                     {"mesh", dir + "/noisy-cube.off"},
                     {"set", {{"n_normal", "12"}, {"output.format", "\"glb\""}, {"output.compression", "\"draco\""}}},
                     {"refused", {dir + "/photo.png", dir + "/broken.off"}},
                     {"formats", formats},
                     {"drop", formats[0]},
                     {"cancel", {{"mesh", dir + "/big.off"}, {"set", heavy}, {"then", dir + "/noisy-cube.off"}}},
                     {"view", {{"slow", dir + "/big.off"}, {"set", heavy}, {"refused", dir + "/broken.off"}}},
                     {"invalid", {{"field", "n_normal"}, {"value", "5000"}}},
                     {"zero", dir + "/noisy-cube.off"},
                     {"large", dir + "/large.off"},
                     {"close", {{"mesh", dir + "/big.off"}, {"set", heavy}}},
                     {"full", true}};
  const json report = run_page(plan, dir);
  ASSERT_TRUE(report.contains("state")) << report.dump(1);
  ASSERT_EQ(report.at("state"), "done") << report.value("error_text", "");

  // The form lists exactly the fields of /v1/params, each once.
  const json params = parse_json(c->Get("/v1/params")->body);
  std::vector<std::string> form = report.at("form_fields"), expected = schema_fields(params);
  std::sort(form.begin(), form.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(form, expected);
  for (const auto& p : params.at("parameters"))
    EXPECT_TRUE(std::count(form.begin(), form.end(), p.at("name").get<std::string>())) << p.at("name");

  // Both halves of the canvas show a mesh (not just the background).
  const json& canvas = report.at("canvas");
  const double area = canvas.at("width").get<double>() * canvas.at("height").get<double>() / 2;
  EXPECT_GT(canvas.at("before_pixels").get<double>(), 0.05 * area) << canvas;
  EXPECT_GT(canvas.at("after_pixels").get<double>(), 0.05 * area) << canvas;
  // The displacement legend has a range > 0, in edge lengths and model units; sigma was 0.25 edge
  // lengths, so the vertices moved by a fraction of an edge, not by many edges.
  const json& legend = report.at("legend");
  EXPECT_FALSE(legend.at("hidden").get<bool>());
  EXPECT_GT(legend.at("edge_lengths").get<double>(), 0.02) << legend;
  EXPECT_LT(legend.at("edge_lengths").get<double>(), 2.0) << legend;
  EXPECT_GT(legend.at("model_units").get<double>(), 0) << legend;

  // The CLI command carries the run's parameters; the file downloaded in the browser is what
  // POST /v1/denoise returns for the same input and parameters, byte for byte.
  const std::string params_text = R"({"n_normal":12,"output":{"format":"glb","compression":"draco"}})";
  EXPECT_NE(report.value("cli", "").find("--params '" + params_text + "'"), std::string::npos) << report.value("cli", "");
  EXPECT_NE(report.value("curl", "").find("/v1/denoise"), std::string::npos) << report.value("curl", "");
  EXPECT_EQ(report.at("download_state"), "completed");
  ASSERT_EQ(report.at("downloads").size(), 1u) << report.at("downloads");
  const std::string downloaded = read_file(report.at("downloads")[0].get<std::string>());
  auto direct = c->Post("/v1/denoise", {{"X-Denoise-Params", params_text}}, mesh, "model/x-off");
  ASSERT_TRUE(direct && direct->status == 200);
  EXPECT_EQ(downloaded.size(), direct->body.size());
  EXPECT_TRUE(downloaded == direct->body) << "the page's download differs from POST /v1/denoise";
  EXPECT_EQ(downloaded.substr(0, 4), "glTF");

  // Refused files: the page shows the problem the API gives for the same bytes.
  ASSERT_EQ(report.at("refused").size(), 2u);
  const std::pair<std::string, std::string> bodies[] = {{png, "application/octet-stream"}, {broken, "model/x-off"}};
  for (std::size_t i = 0; i < 2; ++i) {
    const json& shown = report.at("refused")[i];
    auto r = c->Post("/v1/denoise", bodies[i].first, bodies[i].second.c_str());
    ASSERT_TRUE(r && r->status >= 400 && r->status < 500) << shown;
    const json problem = parse_json(r->body);
    EXPECT_EQ(shown.at("state"), "failed") << shown;
    EXPECT_TRUE(shown.at("visible").get<bool>()) << shown;
    EXPECT_EQ(shown.at("title"), problem.at("title")) << shown;
    EXPECT_EQ(shown.at("detail"), problem.at("detail")) << shown;
  }

  // Every input format is drawn, before and after, with its heat map.
  ASSERT_EQ(report.at("formats").size(), formats.size());
  for (const json& f : report.at("formats")) {
    EXPECT_EQ(f.at("state"), "done") << f;
    EXPECT_GT(f.at("canvas").at("before_pixels").get<double>(), 0.05 * area) << f;
    EXPECT_GT(f.at("canvas").at("after_pixels").get<double>(), 0.05 * area) << f;
    EXPECT_FALSE(f.at("legend_hidden").get<bool>()) << f;
  }

  // A file dropped on the page runs like a chosen one.
  const json& dropped = report.at("drop");
  EXPECT_EQ(dropped.at("state"), "done") << dropped;
  EXPECT_NE(dropped.at("file").get<std::string>().find("noisy-cube.glb"), std::string::npos) << dropped;
  EXPECT_GT(dropped.at("canvas").at("after_pixels").get<double>(), 0.05 * area) << dropped;

  // Cancel: the page showed the stage and fraction while the job ran, then its end.
  const json& cancelled = report.at("cancel");
  EXPECT_EQ(cancelled.at("running").at("state"), "running") << cancelled;
  EXPECT_NE(cancelled.at("running").at("stage").get<std::string>().find(" %"), std::string::npos) << cancelled;
  EXPECT_EQ(cancelled.at("state"), "cancelled") << cancelled;
  // A file chosen while a job ran: that job was cancelled, the new one ran.
  EXPECT_EQ(cancelled.at("replaced_state"), "done") << cancelled;
  const json replaced = wait_job(*c, cancelled.at("replaced_job").get<std::string>());
  EXPECT_EQ(replaced.value("state", ""), "cancelled") << replaced.dump();

  // Keyboard: the controls a person needs are reached with Tab.
  const json& tabs = report.at("tab_order");
  for (const char* id : {"file", "run", "canvas", "download", "copy-curl", "copy-cli"})
    EXPECT_NE(std::find(tabs.begin(), tabs.end(), id), tabs.end()) << id << " is not reachable with Tab: " << tabs;
  EXPECT_FALSE(report.value("narrow_overflow", true)) << "the page scrolls sideways at 420 px";
  for (const char* id : {"file", "run"}) {
    const json ring = report.at("focus_ring").value(id, json::object());
    EXPECT_NE(ring.value("style", "none"), "none") << id << " has no visible focus: " << ring;
    EXPECT_GE(ring.value("width", 0.0), 2.0) << id << ": " << ring;
  }

  // The page closed while its job ran: the job ends within seconds (keepalive DELETE on pagehide).
  const json& closed = report.at("close");
  ASSERT_EQ(closed.at("state"), "running") << closed;
  const std::string closed_job = closed.at("job");
  json after_close;
  const auto poll_end = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < poll_end) {
    after_close = parse_json(c->Get("/v1/jobs/" + closed_job)->body);
    if (after_close.value("state", "") != "queued" && after_close.value("state", "") != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const double close_to_end_s =
      (std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count() -
       closed.at("closed_at_ms").get<double>()) / 1000;
  EXPECT_EQ(after_close.value("state", ""), "cancelled") << after_close.dump();
  std::cout << "job ended " << close_to_end_s << " s after its page was closed (at most: the poll's own step)\n";
  EXPECT_LT(close_to_end_s, 10.0);

  // In view at both sizes, with no scrolling: a running job's status, progress and Cancel; a
  // refused file's error. The user's own Cancel is no error. No panel of the earlier result
  // while another file runs, nor after a failure.
  ASSERT_EQ(report.at("view").size(), 2u) << report.at("view");
  for (const json& v : report.at("view")) {
    for (const char* what : {"stage", "cancel", "progress"})
      EXPECT_TRUE(v.at("running").at(what).at("inside").get<bool>()) << v.at("width") << " " << what << ": " << v.at("running");
    EXPECT_EQ(v.at("cancelled").at("state"), "cancelled") << v;
    EXPECT_FALSE(v.at("cancelled").at("error_shown").get<bool>()) << "a user's own Cancel shown as an error: " << v;
    EXPECT_EQ(v.at("refused_state"), "failed") << v;
    EXPECT_TRUE(v.at("refused").at("error").at("inside").get<bool>()) << v.at("width") << ": " << v.at("refused");
    EXPECT_TRUE(v.at("refused").at("stage").at("inside").get<bool>()) << v.at("width") << ": " << v.at("refused");
    for (const char* panel : {"panels_while_second_runs", "panels_after_failure"})
      for (const auto& [id, shown] : v.at(panel).items()) EXPECT_FALSE(shown.get<bool>()) << v.at("width") << " " << panel << ": #" << id;
    if (v.contains("panels_after_first")) {
      EXPECT_TRUE(v.at("panels_after_first").at("results").get<bool>()) << v;
      EXPECT_TRUE(v.at("panels_after_first").at("legend").get<bool>()) << v;
    }
  }

  // A wrong field: answered within a second, in view, naming the field, focused; nothing sent.
  const json& invalid = report.at("invalid");
  EXPECT_LT(invalid.at("on_run_ms").get<double>(), 1000) << invalid;
  EXPECT_LT(invalid.at("on_choose_ms").get<double>(), 1000) << invalid;
  EXPECT_NE(invalid.at("title").get<std::string>().find("n_normal"), std::string::npos) << invalid;
  EXPECT_NE(invalid.at("detail").get<std::string>().find("0 to 1000"), std::string::npos) << invalid;
  EXPECT_TRUE(invalid.at("error").at("inside").get<bool>()) << invalid;
  EXPECT_EQ(invalid.at("focused"), "n_normal") << invalid;
  EXPECT_FALSE(invalid.at("field_error").get<std::string>().empty()) << invalid;
  EXPECT_EQ(invalid.at("jobs_sent"), 0) << invalid;
  EXPECT_FALSE(invalid.at("error_after_fix").get<bool>()) << invalid;
  EXPECT_EQ(invalid.at("state_after_fix"), "done") << invalid;

  // The heat map's colours on screen are the legend's, on the lit surface: every flat-coloured
  // pixel of the result is some colour of the scale times a brightness (a denoised cube), and a
  // run that moved nothing is the scale's zero, lit. Colour-space-confused rendering, or a
  // tinted light, is tens of levels off.
  const json& heat = report.at("heat");
  std::cout << "heat map vs legend (max channel difference, lit): " << heat.dump() << "\n";
  EXPECT_GT(heat.at("samples").get<int>(), 200) << heat;
  EXPECT_LE(heat.at("median").get<int>(), 4) << heat;
  EXPECT_LE(heat.at("p95").get<int>(), 10) << heat;
  const json& zero = report.at("zero");
  EXPECT_EQ(zero.at("state"), "done") << zero;
  EXPECT_TRUE(zero.at("stale_after_change").get<bool>()) << "a result of other parameters is not marked: " << zero;
  EXPECT_FALSE(zero.at("stale_after_revert").get<bool>()) << zero;
  std::cout << "heat map of a run that moved nothing: " << zero.at("heat").dump() << "\n";
  EXPECT_GT(zero.at("heat").at("samples").get<int>(), 200) << zero;
  EXPECT_LE(zero.at("heat").at("p95").get<int>(), 4) << zero;
  EXPECT_LE(zero.at("heat").at("p95_position").get<double>(), 0.02) << "pixels of a run that moved nothing away from the scale's zero: " << zero;
  // The histogram counts every result vertex (the cube's 6 x 16 x 16 + 2, or more where the
  // Draco result splits some); a click on the result reads one.
  int binned = 0;
  for (const auto& n : report.at("histogram")) binned += n.get<int>();
  EXPECT_GE(binned, 6 * 16 * 16 + 2) << report.at("histogram");
  EXPECT_LE(binned, 6 * (6 * 16 * 16 + 2)) << report.at("histogram");
  EXPECT_FALSE(report.at("pick").at("hidden").get<bool>()) << report.at("pick");
  EXPECT_FALSE(report.at("pick").at("moved").get<std::string>().empty()) << report.at("pick");

  // A 4 MB OFF result: gzip-encoded on the wire, fetched in well under a second on a quiet
  // machine (the bound is loose for a busy CI one; Brotli at quality 11 took 8-13 s).
  const json& large = report.at("large");
  ASSERT_EQ(large.at("state"), "done") << large;
  const json& timing = large.at("timing");
  std::cout << "4 MB OFF result in the page: " << timing.dump() << "\n";
  EXPECT_GT(timing.at("decoded_bytes").get<double>(), 3.5e6) << timing;
  EXPECT_LT(timing.at("encoded_bytes").get<double>() * 2, timing.at("decoded_bytes").get<double>()) << timing;
  EXPECT_LT(timing.at("duration_ms").get<double>(), 3000) << timing;

  expect_loopback_only(report, server.port());
  expect_no_console_errors(report, {{"refused:photo.png", 415}});
  fs::remove_all(dir);
}

TEST(WebPage, AsksForTheTokenOnceWhenAuthIsOn) {
  check_browser_tools();
  ServerProcess server({"--workers", "1"}, {"MDN_AUTH_TOKEN=s3cret"});
  ASSERT_TRUE(server.started()) << server.log();
  const std::string dir = temp_dir("web_auth");
  write_file(dir + "/sphere.off", noisy_sphere_off(2, 5));
  const json plan = {{"url", "http://127.0.0.1:" + std::to_string(server.port()) + "/"},
                     {"out", dir},
                     {"mesh", dir + "/sphere.off"},
                     {"token", "s3cret"}};
  const json report = run_page(plan, dir);
  ASSERT_TRUE(report.contains("state")) << report.dump(1);
  EXPECT_EQ(report.at("state"), "done") << report.value("error_text", "");
  // One 401 (the page's first API call), then every API call carried the token.
  int unauthorized = 0;
  for (const auto& s : report.at("statuses")) unauthorized += s.at("status") == 401;
  EXPECT_EQ(unauthorized, 1) << report.at("statuses");
  EXPECT_NE(report.value("curl", "").find("Authorization: Bearer $MDN_TOKEN"), std::string::npos) << report.value("curl", "");
  EXPECT_EQ(report.value("curl", "").find("s3cret"), std::string::npos) << "the token must not be shown";
  expect_loopback_only(report, server.port());
  expect_no_console_errors(report, {{"auth", 401}, {"load", 401}});
  fs::remove_all(dir);
}

}  // namespace
}  // namespace mdn::test
