// Issue 51, item 1: the output settings are defined once (core/io/output_settings.h). The JSON
// Schema in proto/ and the CLI's --help must say what the table says; this test fails, naming
// the setting and the difference, when either drifts.
#include "core/io/output_settings.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include "io_test_support.h"

namespace mdn::io {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// The source tree: this file's path is relative to the build directory it was compiled in.
fs::path source_root() {
  const char* build = std::getenv("MDN_BUILD_DIR");
  const fs::path self = fs::path(__FILE__).is_absolute() || !build ? fs::path(__FILE__) : fs::path(build) / __FILE__;
  return fs::weakly_canonical(self).parent_path().parent_path().parent_path();
}

Json output_schema() {
  const std::string text = test_io::read_file(source_root() / "proto" / "params.schema.json");
  return Json::parse(text).at("properties").at("output");
}

// Runs of white space as one space (the help wraps the meanings).
std::string squeezed(const std::string& text) {
  std::istringstream words(text);
  std::string out;
  for (std::string w; words >> w;) out += (out.empty() ? "" : " ") + w;
  return out;
}

TEST(OutputSettings, SchemaSaysWhatTheTableSays) {
  const Json schema = output_schema();
  EXPECT_FALSE(schema.value("additionalProperties", true));
  std::set<std::string> in_schema, in_table;
  for (const auto& [name, v] : schema.at("properties").items()) in_schema.insert(name);
  for (const OutputSetting& s : output_settings()) in_table.insert(std::string(s.name));
  EXPECT_EQ(in_schema, in_table);
  for (const OutputSetting& s : output_settings()) {
    const std::string name(s.name);
    if (!schema.at("properties").contains(name)) continue;
    const Json& p = schema.at("properties").at(name);
    EXPECT_EQ(p.value("description", ""), s.meaning) << name;
    EXPECT_EQ(p.value("deprecated", false), s.deprecated) << name;
    switch (s.kind) {
      case SettingKind::Integer:
        EXPECT_EQ(p.at("type"), "integer") << name;
        EXPECT_EQ(p.at("minimum"), s.min) << name;
        EXPECT_EQ(p.at("maximum"), s.max) << name;
        EXPECT_EQ(p.at("default"), s.default_integer()) << name;
        break;
      case SettingKind::Flag:
        EXPECT_EQ(p.at("type"), "boolean") << name;
        break;
      case SettingKind::Choice: {
        Json choices = Json::array();
        for (const std::string& c : s.choices) choices.push_back(c);
        if (s.nullable) choices.push_back(nullptr);
        EXPECT_EQ(p.at("enum"), choices) << name;
        EXPECT_EQ(p.at("type"), s.nullable ? Json::array({"string", "null"}) : Json("string")) << name;
        EXPECT_EQ(p.at("default"), s.default_choice().empty() ? Json(nullptr) : Json(s.default_choice())) << name;
        break;
      }
    }
  }
}

TEST(OutputSettings, HelpSaysWhatTheTableSays) {
  const char* build = std::getenv("MDN_BUILD_DIR");
  ASSERT_NE(build, nullptr) << "MDN_BUILD_DIR is not set (ctest sets it)";
  const fs::path cli = fs::path(build) / "cli" / "meshdenoise";
  ASSERT_TRUE(fs::exists(cli)) << cli << " is not built";
  std::string help;
  ASSERT_EQ(test_io::run_command("'" + cli.string() + "' --help", &help), 0) << help;
  const std::string flat = squeezed(help);
  for (const OutputSetting& s : output_settings()) {
    std::string head = "output." + std::string(s.name) + " " + s.range_text();
    if (s.kind == SettingKind::Integer) head += ", default " + std::to_string(s.default_integer());
    if (s.kind == SettingKind::Choice)
      head += ", default " + (s.default_choice().empty() ? std::string("null") : "\"" + s.default_choice() + "\"");
    EXPECT_NE(flat.find(squeezed(head)), std::string::npos) << "--help lacks \"" << head << "\"";
    EXPECT_NE(flat.find(squeezed(std::string(s.meaning))), std::string::npos) << "--help lacks the meaning of " << s.name;
  }
}

TEST(OutputSettings, DefaultsAreTheEncodersAndRangesAreChecked) {
  const EncodeOptions d = request_defaults();
  EXPECT_EQ(d.compression, Compression::AsInput);
  EXPECT_NO_THROW(check_output_options(d));
  for (const OutputSetting& s : output_settings()) {
    if (s.kind != SettingKind::Integer) continue;
    EXPECT_EQ(s.default_integer(), EncodeOptions{}.*s.field) << s.name;
    for (const int bad : {s.min - 1, s.max + 1}) {
      EncodeOptions o = d;
      o.*s.field = bad;
      try {
        check_output_options(o);
        ADD_FAILURE() << s.name << " = " << bad << " accepted";
      } catch (const InvalidParamsError& e) {
        EXPECT_EQ(e.field(), "output." + std::string(s.name));
        EXPECT_NE(std::string(e.what()).find(s.range_text()), std::string::npos) << e.what();
      }
    }
    for (const int good : {s.min, s.max}) {
      EncodeOptions o = d;
      o.*s.field = good;
      EXPECT_NO_THROW(check_output_options(o)) << s.name << " = " << good;
    }
  }
}

}  // namespace
}  // namespace mdn::io
