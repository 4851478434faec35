// libFuzzer harness for one decoder (MDN_FUZZ_FORMAT, set per executable by CMakeLists.txt):
// decode -> validate -> encode. The bytes are decoded with small limits; a document that
// decodes must hold valid surfaces (finite coordinates, indices in range), and must encode both
// to its own container and to the one the input's last byte picks (the encoders crash on
// decoded input, not only the decoders), and the output must decode again. Every error must be
// one the service answers with a 4xx; anything else (another exception, a crash, a sanitizer
// report, a leak, a timeout, memory past -rss_limit_mb) is a finding.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <iterator>
#include <string_view>

#include "core/errors.h"
#include "core/io/document.h"

namespace {

using namespace mdn;

[[noreturn]] void finding(const char* what, const char* detail) {
  std::fprintf(stderr, "FINDING: %s: %s\n", what, detail);
  std::abort();
}

io::Limits fuzz_limits() {
  io::Limits limits;
  limits.max_faces = 20'000;
  limits.max_vertices = 20'000;
  limits.max_decoded_bytes = std::int64_t{64} << 20;
  return limits;
}

void check_surfaces(io::MeshDocument& doc, const char* stage) {
  for (const TriMesh& m : doc.surfaces()) {
    if (m.V.cols() != 3 || m.F.cols() != 3) finding(stage, "a surface is not #V x 3 / #F x 3");
    if (!m.V.allFinite()) finding(stage, "a surface has a non-finite coordinate");
    if (m.F.size() > 0 && (m.F.minCoeff() < 0 || m.F.maxCoeff() >= m.V.rows())) finding(stage, "a face index is out of range");
  }
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
  } catch (const std::exception& e) {
    finding(stage, e.what());
  }
  return false;
}

constexpr io::Format kFormats[] = {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Drc,
                                   io::Format::Glb, io::Format::Gltf, io::Format::Stl};

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
  io::EncodeOptions options;
  options.draco = size % 2 == 0;
  if (size % 3 == 0) options.compression = io::Compression::AsInput;  // follows the input's
  const io::Format other = kFormats[size ? data[size - 1] % std::size(kFormats) : 0];
  for (const io::Format target : {MDN_FUZZ_FORMAT, other}) {
    options.format = target;
    std::string out;
    if (!client_error_or_ok([&] { out = doc->encode(options); }, "encode")) continue;
    // What we write must read back (without limits smaller than what we accepted).
    std::unique_ptr<io::MeshDocument> again;
    try {
      again = io::decode(out, target, io::Limits{});
    } catch (const std::exception& e) {
      finding("our output does not decode", e.what());
    }
    check_surfaces(*again, "re-decode");
  }
  return 0;
}
