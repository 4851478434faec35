// libFuzzer harness for one decoder (MDN_FUZZ_FORMAT, set per executable by CMakeLists.txt):
// decode -> validate -> encode, as a job does. The bytes are decoded with small limits; a
// document that decodes must hold valid surfaces (finite coordinates, indices in range). It is
// then encoded to its own container and to the one the input's last byte picks, with output
// settings the input's last 8 bytes pick (compression, every *_bits, compression_level: the
// encoders crashed and exhausted memory on settings, not only on decoded input), through the
// job's validation step (io::check_encode, with the same limits); whatever it accepts must
// encode, and the output must decode again. Every error must be one the service answers with a
// 4xx or 422; anything else (another exception, a crash, a sanitizer report, a leak, a timeout,
// memory past -rss_limit_mb) is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <optional>
#include <string_view>

#include "core/errors.h"
#include "core/io/document.h"
#include "core/io/encode_check.h"
#include "core/io/output_settings.h"
#include "fuzz_support.h"

namespace {

using namespace mdn;

using fuzz::check_surfaces;
using fuzz::finding;
using fuzz::kFormats;

io::Limits fuzz_limits() {
  io::Limits limits;
  limits.max_faces = 20'000;
  limits.max_vertices = 20'000;
  limits.max_decoded_bytes = std::int64_t{64} << 20;
  return limits;
}

// Runs f; the errors the service maps to 4xx are expected, anything else is a finding.
template <class F>
bool client_error_or_ok(F&& f, const char* stage) {
  try {
    f();
    return true;
  } catch (const io::FormatError&) {
  } catch (const io::UnsupportedError&) {
  } catch (const io::LimitError&) {
  } catch (const InvalidMeshError&) {
  } catch (const InvalidParamsError&) {
  } catch (const std::exception& e) {
    finding(stage, e.what());
  }
  return false;
}

// Output settings from the input's last 8 bytes (0 where the input is shorter): every *_bits
// over its range and a little past it (refused as a parameter error), compression level and
// mode. The whole input is still what is decoded.
io::EncodeOptions fuzzed_options(std::string_view bytes, const io::Limits& limits) {
  std::uint8_t b[8] = {};
  for (std::size_t i = 0; i < 8 && i < bytes.size(); ++i) b[i] = static_cast<std::uint8_t>(bytes[bytes.size() - 1 - i]);
  io::EncodeOptions options;
  options.position_bits = 6 + b[1] % 27;  // 6..32
  options.normal_bits = b[2] % 33;        // 0..32
  options.texcoord_bits = b[3] % 33;
  options.color_bits = b[4] % 33;
  options.generic_bits = b[5] % 33;
  options.compression_level = b[6] % 12;  // 0..11
  constexpr io::Compression kModes[] = {io::Compression::AsInput, io::Compression::None, io::Compression::Draco,
                                        io::Compression::Meshopt};
  options.compression = kModes[b[7] % std::size(kModes)];
  options.max_memory_bytes = limits.max_decoded_bytes;
  return options;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const io::Limits limits = fuzz_limits();
  std::unique_ptr<io::MeshDocument> doc;
  if (!client_error_or_ok([&] { doc = io::decode(bytes, MDN_FUZZ_FORMAT, limits); }, "decode")) return 0;
  check_surfaces(*doc, "decode");
  // The job's validation: the core refuses a surface without vertices or faces (a 400), so
  // such a document never reaches the encoders.
  for (const TriMesh& m : doc->surfaces())
    if (m.V.rows() == 0 || m.F.rows() == 0) return 0;
  io::EncodeOptions options = fuzzed_options(bytes, limits);
  // The request's output settings are checked once, where it is parsed (core/io's one table,
  // decision 69); what fails there never reaches the encoders.
  if (!client_error_or_ok([&] { io::check_output_options(options); }, "check_output_options")) return 0;
  const io::Format other = kFormats[size ? data[size - 1] % std::size(kFormats) : 0];
  for (const io::Format target : {MDN_FUZZ_FORMAT, other}) {
    options.format = target;
    std::string out;
    // The job's validation step first (finite positions, encoder memory), then the encoder, as
    // run_job does.
    if (!client_error_or_ok([&] { io::check_encode(*doc, options, limits); }, "check_encode")) continue;
    if (!client_error_or_ok([&] { out = doc->encode(options).bytes; }, "encode")) continue;
    // What we write must read back (without limits smaller than what we accepted).
    std::unique_ptr<io::MeshDocument> again;
    try {
      again = io::decode(out, target, io::Limits{});
    } catch (const std::exception& e) {
      std::fprintf(stderr, "to %s, compression %s, bits position %d normal %d texcoord %d color %d generic %d, level %d\n",
                   std::string(io::to_string(target)).c_str(),
                   std::string(io::to_string(options.compression)).c_str(),
                   options.position_bits, options.normal_bits, options.texcoord_bits, options.color_bits, options.generic_bits,
                   options.compression_level);
      finding("our output does not decode", e.what());
    }
    check_surfaces(*again, "re-decode");
  }
  return 0;
}
