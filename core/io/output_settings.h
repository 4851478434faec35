// The output settings, defined once (issue 51, decision 69): every field of the request's
// "output" object with its type, range, default and meaning. service/params_json parses and
// checks the request with it, the CLI's --help prints it, and tests/io/output_settings_test
// fails when proto/params.schema.json's "output" part or the help say otherwise.
//
// The check happens once, where a request is parsed (check_output_options for EncodeOptions
// built in code). The encoders keep only a guard against values they cannot take at all.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/document.h"

namespace mdn::io {

enum class SettingKind {
  Choice,   // a string from `choices` ("format" also takes null: the input's container)
  Integer,  // an integer in [min, max]
  Flag,     // true or false (the deprecated "draco" switch)
};

struct OutputSetting {
  std::string_view name;            // the JSON field of "output"
  SettingKind kind;
  int EncodeOptions::*field;        // Integer: the EncodeOptions field; others: null
  int min, max;                     // Integer: the accepted range, inclusive
  std::vector<std::string> choices;  // Choice: the accepted strings
  bool nullable;                    // Choice: null accepted (and the default)
  bool deprecated;                  // accepted, not echoed
  std::string_view meaning;         // one paragraph, the schema's "description"

  // Integer: the default (from request_defaults()). Choice: the default string, "" for null.
  int default_integer() const;
  std::string default_choice() const;
  // "[8, 30]", "\"off\"|\"obj\"|...|null", "true|false": what the help prints as the range.
  std::string range_text() const;
  // Integer: whether `value` is accepted.
  bool accepts(long long value) const { return value >= min && value <= max; }
};

// Every output setting, in the order the schema and the help list them.
std::span<const OutputSetting> output_settings();
// The setting named `name`, or null.
const OutputSetting* find_output_setting(std::string_view name);

// What a request gets for the fields it leaves out: EncodeOptions' defaults with
// compression AsInput (a request gets back what it sent, issue 18).
EncodeOptions request_defaults();

// For EncodeOptions built in code rather than parsed: every Integer setting in its range, or
// InvalidParamsError naming "output.<name>" and the range.
void check_output_options(const EncodeOptions& options);

}  // namespace mdn::io
