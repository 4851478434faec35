// libFuzzer harness for the parameters text (?params=, X-Denoise-Params, the form field,
// --params): every input parses to parameters that pass validate(), or throws
// InvalidParamsError, which the service answers with a 400 naming the field. Anything else is
// a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>

#include "core/errors.h"
#include "service/params_json.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const mdn::service::JobParams params = mdn::service::job_params_from_text(text);
    mdn::service::validate(params);
    // What was accepted serialises and reads back to the same parameters.
    const std::string echoed = mdn::service::to_json(params).dump();
    if (mdn::service::to_json(mdn::service::job_params_from_text(echoed)).dump() != echoed) {
      std::fprintf(stderr, "FINDING: parameters do not round-trip: %s\n", echoed.c_str());
      std::abort();
    }
  } catch (const mdn::InvalidParamsError&) {
  } catch (const std::exception& e) {
    std::fprintf(stderr, "FINDING: %s\n", e.what());
    std::abort();
  }
  return 0;
}
