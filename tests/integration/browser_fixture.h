// Test support for the web page's browser tests: runs one of the puppeteer-core drivers in
// tests/tools/ (Debian's Chromium, headless) on a plan and returns the JSON report it prints
// last; checks that the tools are installed.
#pragma once

#include <cstdlib>
#include <iostream>
#include <string>

#include "http_fixture.h"

namespace mdn::test {

// <build>/artifacts/web/: the drivers' screenshots (kept for people, never compared).
inline std::string web_artifacts_dir() {
  const fs::path dir = fs::path(build_dir()) / "artifacts" / "web";
  fs::create_directories(dir);
  return dir.string();
}

// Runs `node tests/tools/<script> <dir>/plan.json`; returns its report (the last line of its
// output), with a test failure if it exited non-zero, printed no JSON or reported a failure.
inline nlohmann::json run_browser_check(const std::string& script, const nlohmann::json& plan, const std::string& dir) {
  write_file(dir + "/plan.json", plan.dump());
  const std::string tools = source_dir() + "/tests/tools";
  const auto [code, out] = run_command("cd " + shell_quote(tools) + " && node " + script + " " +
                                       shell_quote(dir + "/plan.json") + " 2>&1");
  const std::size_t line = out.rfind("\n{");
  nlohmann::json report = parse_json(out.substr(line == std::string::npos ? 0 : line + 1));
  EXPECT_EQ(code, 0) << out.substr(0, 4000);
  EXPECT_TRUE(report.is_object()) << out.substr(0, 4000);
  if (!report.is_object()) return nlohmann::json::object();
  EXPECT_FALSE(report.contains("failure")) << report.value("failure", "");
  std::cout << script << " steps (ms): " << report.value("step_ms", nlohmann::json::object()).dump() << "\n";
  return report;
}

// A noisy cube (creases and flat faces show what the method keeps and what it removes): n by n
// quads a side, noise of 0.25 mean edge lengths.
inline std::string noisy_cube_off(int n, std::uint64_t seed) { return noisy_off(cube(n), 0.25, seed); }

// Skips nothing: a missing tool is a failure that says how to install it.
inline void check_browser_tools() {
  ASSERT_TRUE(fs::exists(source_dir() + "/tests/tools/node_modules/puppeteer-core/package.json"))
      << "tests/tools/node_modules/puppeteer-core is missing: run `npm install` in tests/tools "
         "(scripts/install-deps.sh build test does it)";
  const std::string chromium = std::getenv("MDN_CHROMIUM") ? std::getenv("MDN_CHROMIUM") : "/usr/bin/chromium";
  ASSERT_TRUE(fs::exists(chromium)) << chromium << " is missing: install the Debian package `chromium` (scripts/deps/apt-test.txt)";
}

}  // namespace mdn::test
