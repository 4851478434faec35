// libFuzzer harness for the whole job path, as the service runs a request (issue 49, item 9:
// the Draco encoder's crash at levels 9-10 was found this way): parameters + mesh + encoder.
// An input is one byte that picks the container (as a request's Content-Type would), the
// parameters' text up to the first '\n' (?params= / X-Denoise-Params: any mode, any output
// settings) and the mesh's bytes after it. service::run_job decodes under small limits,
// validates, denoises on one thread and encodes; its output must decode again with valid
// surfaces. Every error must be one the service answers with a 4xx or 422 (problem.cpp's
// catalogue: malformed, invalid mesh or parameters, unsupported, too large, solver failed);
// anything else (another exception, a crash, a sanitizer report, a leak, a timeout, memory past
// -rss_limit_mb) is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <memory>
#include <string>
#include <string_view>

#include "core/errors.h"
#include "core/io/document.h"
#include "service/job_runner.h"
#include "service/params_json.h"
#include "fuzz_support.h"

namespace {

using namespace mdn;

using fuzz::check_surfaces;
using fuzz::finding;
using fuzz::kFormats;

// Small enough that "mode": "search" on a mesh at the limit stays well inside -timeout under
// the sanitizers.
io::Limits fuzz_limits() {
  io::Limits limits;
  limits.max_faces = 1'000;
  limits.max_vertices = 1'000;
  limits.max_decoded_bytes = std::int64_t{32} << 20;
  return limits;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2) return 0;
  const std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  const std::size_t newline = rest.find('\n');
  if (newline == std::string_view::npos) return 0;
  service::JobInput job;
  job.format = kFormats[data[0] % std::size(kFormats)];
  job.bytes = std::string(rest.substr(newline + 1));
  job.threads = 1;
  const io::Limits limits = fuzz_limits();
  service::JobOutput out;
  try {
    job.params = service::job_params_from_text(std::string(rest.substr(0, newline)));
    out = service::run_job(std::move(job), limits);
  } catch (const InvalidParamsError&) {
    return 0;
  } catch (const io::FormatError&) {
    return 0;
  } catch (const io::UnsupportedError&) {
    return 0;
  } catch (const io::LimitError&) {
    return 0;
  } catch (const InvalidMeshError&) {
    return 0;
  } catch (const SolverError&) {
    return 0;
  } catch (const std::exception& e) {
    finding("run_job", e.what());
  }
  // What the service answers must read back, with surfaces as valid as the decoder's.
  std::unique_ptr<io::MeshDocument> again;
  try {
    again = io::decode(out.bytes, out.format, io::Limits{});
  } catch (const std::exception& e) {
    finding("the job's output does not decode", e.what());
  }
  check_surfaces(*again, "re-decode");
  return 0;
}
