// The web page as a person reads it after a run, in headless Chromium against the real server
// (tests/tools/check_web_reading.mjs, which starts the server itself so that it can stop it and
// start it again on the same port), at 1280x800 and 400x800: the download and a one-line summary
// in view when a job ends, no sideways scroll and no value cut off, "What ran" in words and true
// to what ran after an override, a wrong field placed below the sticky bar with the error
// tracking it, plain messages for an empty or refused file, the heat map lit with signed and
// unsigned modes and a range the user sets, the view turned and zoomed from the keyboard, polls
// at a few a second, and a server that goes away: the result kept, the page saying so and
// trying again until the server is back. Screenshots land in <build>/artifacts/web/.
#include <cmath>
#include <map>
#include <regex>

#include "browser_fixture.h"

namespace mdn::test {
namespace {

using nlohmann::json;

TEST(WebPageReading, ResultsInViewInWordsAndKeptWhenTheServerGoesAway) {
  check_browser_tools();
  const std::string dir = temp_dir("web_reading");
  write_file(dir + "/cube.off", noisy_cube_off(12, 23));
  write_file(dir + "/clean-cube.off", off_text(cube(12)));  // the same faces, no noise
  write_file(dir + "/empty.off", "");
  write_file(dir + "/broken.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");  // a vertex and a face short
  write_file(dir + "/sphere.off", noisy_sphere_off(6, 7));                           // 80k faces
  const json plan = {{"server", {server_binary(), "--workers", "1"}},
                     {"out", web_artifacts_dir()},
                     {"mesh", dir + "/cube.off"},
                     {"override", {{"field", "n_normal"}, {"value", "7"}}},
                     {"invalid", json::array({json::array({"n_normal", "5000"}), json::array({"n_vertex", "5000"})})},
                     {"empty", dir + "/empty.off"},
                     {"broken", dir + "/broken.off"},
                     {"zero", dir + "/cube.off"},
                     {"reference", dir + "/clean-cube.off"},
                     // A few seconds of work even on an idle machine (20k faces with 300 vertex
                     // iterations took 1.0 s there): long enough to count polls.
                     {"slow", {{"mesh", dir + "/sphere.off"}, {"set", {{"n_normal", "1000"}, {"n_vertex", "1000"}}}}}};
  const json report = run_browser_check("check_web_reading.mjs", plan, dir);
  ASSERT_TRUE(report.contains("sizes")) << report.dump(1);
  EXPECT_TRUE(report.at("page_errors").empty()) << report.at("page_errors");

  const std::regex set_name(R"(a\d[\d.]*_t\d+_k\d+)");
  for (const json& v : report.at("sizes")) {
    const std::string at = std::to_string(v.at("width").get<int>()) + "x" + std::to_string(v.at("height").get<int>());
    ASSERT_EQ(v.value("state", ""), "done") << at << ": " << v;
    // 2: the job's end shows the download and a one-line summary without scrolling.
    EXPECT_TRUE(v.at("download").at("inside").get<bool>()) << at << ": Download out of view: " << v.at("download");
    EXPECT_TRUE(v.at("result_line").at("inside").get<bool>()) << at << ": no summary in view: " << v.at("result_line");
    EXPECT_NE(v.at("result_line").at("text").get<std::string>().find("faces"), std::string::npos) << at << ": " << v.at("result_line");
    EXPECT_NE(v.at("result_line").at("text").get<std::string>().find("moved"), std::string::npos) << at << ": " << v.at("result_line");
    // 1: no sideways scroll, no value outside its card, timing bars drawn with their units.
    for (const char* which : {"layout", "what_ran_layout"}) {
      const json& l = v.at(which);
      EXPECT_LE(l.at("scroll_width").get<int>(), l.at("width").get<int>()) << at << " " << which << ": the page scrolls sideways";
      EXPECT_TRUE(l.at("outside").empty()) << at << " " << which << ": text outside its card: " << l.at("outside");
    }
    const json& l = v.at("layout");
    ASSERT_FALSE(l.at("bar_widths").empty()) << at;
    double widest = 0;
    for (const auto& w : l.at("bar_widths")) widest = std::max(widest, w.get<double>());
    EXPECT_GT(widest, 30) << at << ": the longest stage's bar is " << widest << " px";
    for (const auto& row : l.at("timing_rows")) EXPECT_TRUE(std::regex_search(row.get<std::string>(), std::regex(R"(\d (ms|s)$)"))) << at << ": " << row;
    // 5: what ran, in words: the override's value (not the model's pick), no set identifiers,
    // no ratio jargon.
    const std::string words = v.at("what_ran");
    EXPECT_NE(words.find("7 normal-filter iterations"), std::string::npos) << at << ": " << words;
    EXPECT_NE(words.find("n_normal 7; auto chose the rest"), std::string::npos) << at << ": " << words;
    EXPECT_EQ(words.find("Expected"), std::string::npos) << at << ": a prediction for a set that did not run: " << words;
    EXPECT_FALSE(std::regex_search(words, set_name)) << at << ": " << words;
    EXPECT_EQ(words.find("x the best set's"), std::string::npos) << at << ": " << words;
    EXPECT_NE(words.find("Noise read"), std::string::npos) << at << ": " << words;
    // 4: the focused field below the sticky bar, in view; the error names the first field still wrong.
    const json& inv = v.at("invalid");
    EXPECT_TRUE(inv.at("first").at("focused").get<bool>()) << at << ": " << inv;
    EXPECT_TRUE(inv.at("first").at("below_bar").get<bool>()) << at << ": the field lies under the action bar: " << inv;
    EXPECT_TRUE(inv.at("first").at("label_below_bar").get<bool>()) << at << ": " << inv;
    EXPECT_TRUE(inv.at("first").at("in_view").get<bool>()) << at << ": " << inv;
    EXPECT_EQ(inv.at("title"), "Check n_normal") << at;
    EXPECT_EQ(inv.at("title_after_first_fix"), "Check n_vertex") << at << ": the error still names a fixed field";
    EXPECT_FALSE(inv.at("shown_after_both_fixed").get<bool>()) << at;
    // 7: an empty file is said to be empty, nothing sent; a refused file's canvas text is the
    // browser's own reason, without "the server reads files on its own" beside the refusal.
    const json& empty = v.at("empty");
    EXPECT_EQ(empty.at("state"), "failed") << at << ": " << empty;
    EXPECT_EQ(empty.at("sent"), 0) << at << ": " << empty;
    EXPECT_NE(empty.at("title").get<std::string>().find("empty"), std::string::npos) << at << ": " << empty;
    EXPECT_EQ(empty.at("detail").get<std::string>().find("not a off file"), std::string::npos) << at << ": " << empty;
    EXPECT_TRUE(empty.at("error").at("inside").get<bool>()) << at << ": " << empty;
    const json& broken = v.at("broken");
    EXPECT_EQ(broken.at("state"), "failed") << at << ": " << broken;
    const std::string canvas = broken.at("canvas_text");
    EXPECT_EQ(canvas.find("reads files on its own"), std::string::npos) << at << ": " << canvas;
    EXPECT_NE(canvas.find("declares 4 vertices and 2 faces"), std::string::npos) << at << ": " << canvas;
  }

  // 8: the heat map on the lit surface: a run that moved nothing is one colour, yet lit (its
  // brightness varies with the faces' orientation, as the cube's sides do).
  const json& heat = report.at("heat");
  ASSERT_EQ(heat.at("zero_state"), "done") << heat;
  const json& zero = heat.at("zero_pixels");
  EXPECT_GT(zero.at("drawn").get<int>(), 1000) << zero;
  EXPECT_GT(zero.at("luma_p90").get<double>(), 1.25 * zero.at("luma_p10").get<double>() + 2) << "the heat map is unlit: " << zero;
  // Signed: the scale runs from -end (in) to +end (out), every vertex in the histogram.
  ASSERT_EQ(heat.at("state"), "done") << heat;
  const auto total = [](const json& bins) { int n = 0; for (const auto& b : bins) n += b.get<int>(); return n; };
  const int vertices = total(heat.at("distance").at("bins"));
  EXPECT_GT(vertices, 6 * 12 * 12) << heat.at("distance");
  EXPECT_NE(heat.at("signed").at("min").get<std::string>().find("−"), std::string::npos) << heat.at("signed");
  EXPECT_NE(heat.at("signed").at("max").get<std::string>().find("out"), std::string::npos) << heat.at("signed");
  EXPECT_EQ(total(heat.at("signed").at("bins")), vertices) << heat.at("signed");
  // A range typed in: the legend ends there, and more vertices pile into the last bin.
  EXPECT_NEAR(heat.at("ranged").at("edge_lengths").get<double>(), 0.05, 1e-9) << heat.at("ranged");
  EXPECT_GT(heat.at("ranged").at("bins").back().get<int>(), heat.at("distance").at("bins").back().get<int>()) << heat;
  EXPECT_NE(heat.at("ranged").at("note").get<std::string>().find("where you set it"), std::string::npos) << heat.at("ranged");
  // A wrong range is said beside the field and changes nothing.
  EXPECT_FALSE(heat.at("bad_range").at("error").get<std::string>().empty()) << heat.at("bad_range");
  EXPECT_NEAR(heat.at("bad_range").at("legend").at("edge_lengths").get<double>(), 0.05, 1e-9) << heat.at("bad_range");

  // The reference comparison: the server's figures, the CLI's for the same files (the input's
  // E_v and MSAE as `meshdenoise --metrics` prints them), the result closer to the reference
  // than the input, and the heat map showing the signed deviation.
  const json& ref = report.at("reference");
  ASSERT_EQ(ref.at("state"), "done") << ref;
  ASSERT_EQ(ref.at("rows").size(), 2u) << ref;
  const json& input_row = ref.at("rows")[0];
  const json& result_row = ref.at("rows")[1];
  EXPECT_EQ(input_row.at("row"), "input");
  EXPECT_EQ(result_row.at("row"), "result");
  const auto [cli_code, cli_out] = run_command(shell_quote(cli_binary()) + " --metrics " + shell_quote(dir + "/clean-cube.off") + " " +
                                               shell_quote(dir + "/cube.off"));
  ASSERT_EQ(cli_code, 0) << cli_out;
  const json cli = parse_json(cli_out);
  EXPECT_NEAR(input_row.at("ev").get<double>(), cli.at("ev").get<double>(), 1e-12 + 1e-9 * cli.at("ev").get<double>()) << ref;
  EXPECT_NEAR(input_row.at("msae").get<double>(), cli.at("msae_deg2").get<double>(), 1e-9 * cli.at("msae_deg2").get<double>()) << ref;
  EXPECT_LT(result_row.at("ev").get<double>(), input_row.at("ev").get<double>()) << ref;
  EXPECT_LT(result_row.at("msae").get<double>(), input_row.at("msae").get<double>()) << ref;
  EXPECT_EQ(ref.at("mode"), "reference") << ref;
  EXPECT_NE(ref.at("title").get<std::string>().find("Deviation from the reference"), std::string::npos) << ref;
  EXPECT_NE(ref.at("min").get<std::string>().find("−"), std::string::npos) << "a signed deviation: " << ref;
  EXPECT_GT(ref.at("pixels").at("drawn").get<int>(), 1000) << ref;

  // 8: the keyboard turns (three 15° steps), tilts, zooms (the model grows on screen), pans and
  // frames the model again.
  const json& keys = report.at("keys");
  ASSERT_TRUE(keys.at("start").contains("azimuth")) << "the canvas reports no view: " << keys;
  auto turned = std::fmod(std::abs(keys.at("left3").at("azimuth").get<double>() - keys.at("start").at("azimuth").get<double>()), 360.0);
  EXPECT_NEAR(std::min(turned, 360 - turned), 45, 0.5) << keys;
  EXPECT_EQ(keys.at("left3").at("target"), keys.at("start").at("target")) << "arrows must turn the view, not pan it: " << keys;
  EXPECT_NEAR(keys.at("up").at("polar").get<double>(), keys.at("left3").at("polar").get<double>() - 15, 0.5) << keys;
  EXPECT_NEAR(keys.at("zoomed").at("distance").get<double>() * 1.44, keys.at("up").at("distance").get<double>(), 1e-3 * keys.at("up").at("distance").get<double>()) << keys;
  EXPECT_GT(keys.at("zoomed").at("pixels").get<int>(), 1.3 * keys.at("up").at("pixels").get<int>()) << keys;
  EXPECT_NE(keys.at("panned").at("target"), keys.at("zoomed").at("target")) << keys;
  EXPECT_NEAR(keys.at("framed").at("distance").get<double>(), keys.at("start").at("distance").get<double>(), 1e-6) << keys;
  EXPECT_NEAR(keys.at("framed").at("azimuth").get<double>(), keys.at("start").at("azimuth").get<double>(), 1e-6) << keys;

  // The output panel: what each file holds and the server's checks; the strengths side by
  // side, each with its time and displacement (Strong moves the surface more than Light), one
  // shown as the page's result and ready to download.
  const json& features = report.at("features");
  ASSERT_EQ(features.at("state"), "done") << features;
  const std::string panel = features.at("output_panel");
  for (const char* word : {"Input", "Output", "OFF", "glTF binary", "Draco", "POSITION", "Compression", "What the server"})
    EXPECT_NE(panel.find(word), std::string::npos) << word << " missing from the output panel: " << panel;
  ASSERT_EQ(features.at("rows").size(), 3u) << features;
  std::map<std::string, json> rows;
  for (const json& r : features.at("rows")) rows[r.at("strength")] = r;
  for (const char* key : {"auto", "light", "strong"}) {
    ASSERT_TRUE(rows.count(key)) << key << ": " << features.at("rows");
    EXPECT_NE(rows[key].at("text").get<std::string>().find("on the server"), std::string::npos) << rows[key];
    EXPECT_GT(rows[key].at("run_s").get<double>(), 0) << rows[key];
  }
  EXPECT_GT(rows["strong"].at("mean").get<double>(), rows["light"].at("mean").get<double>()) << features.at("rows");
  const json& shown = features.at("shown");
  EXPECT_EQ(shown.at("state"), "done") << shown;
  EXPECT_NE(shown.at("download").get<std::string>().find("-strong.glb"), std::string::npos) << shown;
  EXPECT_EQ(shown.at("strength"), "strong") << shown;
  EXPECT_NE(shown.at("what_ran").get<std::string>().find("Strong (fixed settings)"), std::string::npos) << shown;
  EXPECT_FALSE(shown.at("stale").get<bool>()) << shown;
  for (const char* which : {"layout", "narrow_layout"}) {
    const json& l = features.at(which);
    EXPECT_LE(l.at("scroll_width").get<int>(), l.at("width").get<int>()) << which;
    EXPECT_TRUE(l.at("outside").empty()) << which << ": text outside its card: " << l.at("outside");
  }

  // 3: polls at no more than a few a second; the server gone: the previous result stays, the
  // page says so and that it tries again; back on the same port, the run goes through.
  const json& server = report.at("server");
  ASSERT_EQ(server.at("slow_state"), "done") << server;
  std::cout << "polls: " << server.at("polls") << " in " << server.at("poll_seconds") << " s\n";
  ASSERT_GT(server.at("poll_seconds").get<double>(), 1.0) << "the job was too quick to count polls: " << server;
  EXPECT_LE(server.at("polls").get<double>() / server.at("poll_seconds").get<double>(), 4.0) << server;
  const json& down = server.at("down");
  EXPECT_TRUE(down.at("results_shown").get<bool>()) << "the previous result was wiped: " << down;
  EXPECT_TRUE(down.at("download_shown").get<bool>()) << down;
  EXPECT_GT(down.at("pixels").at("drawn").get<int>(), 1000) << down;
  EXPECT_EQ(down.at("title"), "The server cannot be reached") << down;
  EXPECT_NE(down.at("detail").get<std::string>().find("again"), std::string::npos) << down;
  EXPECT_NE(down.at("stage").get<std::string>().find("trying again"), std::string::npos) << down;
  EXPECT_EQ(server.at("back_state"), "done") << server;
  EXPECT_EQ(server.at("error_after"), "") << server;
  fs::remove_all(dir);
}

// Item 7 through the API: an empty file in a form is named empty (it was "not a off file (no
// mesh format recognised)").
TEST(WebPageReading, AnEmptyMeshFileInAFormIsSaidToBeEmpty) {
  ServerProcess server({"--workers", "1"});
  ASSERT_TRUE(server.started()) << server.log();
  auto r = server.client()->Post("/v1/jobs", httplib::MultipartFormDataItems{{"mesh", "", "scan.off", "application/octet-stream"}});
  const json problem = expect_problem(r, 400);
  EXPECT_EQ(problem.value("detail", ""), "the form's 'mesh' file (scan.off) is empty: 0 bytes, no mesh in it") << problem.dump();
}

}  // namespace
}  // namespace mdn::test
