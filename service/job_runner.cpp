// One job from bytes to bytes. Both executables go through here, so a mesh denoised by the
// CLI and by the HTTP server with the same parameters gives identical bytes.
#include "service/job_runner.h"

#include <chrono>
#include <memory>
#include <string>
#include <utility>

#include "core/io/encode_check.h"

namespace mdn::service {
namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

bool is_gltf(io::Format format) { return format == io::Format::Glb || format == io::Format::Gltf; }

// The job; `release` (the input's own bytes, or null) is handed to the decoder, which frees it
// as soon as it has read it (io::decode_owned), so a large input's bytes are not held through
// the decoding's copies or the denoising.
JobOutput run(const JobInput& input, std::string* release, const io::Limits& limits, ProgressObserver* progress) {
  // Parameters first: a bad request is refused before any decoding work.
  validate(input.params);

  JobOutput out;
  out.effective = input.params;
  // The job's time limit and cancellation reach the decoder and encoder loops too (not only
  // the core's iterations), so a job stuck in a huge input stops within its limit.
  io::Limits bounded = limits;
  bounded.cancel = progress;
  auto start = Clock::now();
  const io::DecodeOptions how{.limits = bounded, .resource_dir = input.resource_dir};
  std::unique_ptr<io::MeshDocument> document =
      release ? io::decode_owned(std::move(*release), input.format, how) : io::decode(input.bytes, input.format, how);
  out.timings.decode_ms = ms_since(start);

  io::EncodeOptions encode = input.params.output;
  encode.cancel = progress;
  encode.max_memory_bytes = limits.max_decoded_bytes;  // the encoder is bounded like the decoder
  if (!encode.format) encode.format = document->format();
  // The validation step between decode and encode (core/io/encode_check.h): settings the
  // encoder cannot take, or whose memory would exceed the limits, are refused before any
  // denoising work.
  io::check_encode(*document, encode, limits);

  const RunOptions options{.threads = input.threads < 1 ? 1 : input.threads, .progress = progress};
  start = Clock::now();
  std::vector<std::string> run_notes;
  for (TriMesh& surface : document->surfaces()) {
    DenoiseResult result = denoise(surface, input.params.denoise, options);
    // denoise() keeps the connectivity; only positions go back into the document.
    surface.V = std::move(result.mesh.V);
    out.vertices += surface.num_vertices();
    out.faces += surface.num_faces();
    add_stage_timings(out.timings, result.report.timings);
    run_notes.insert(run_notes.end(), result.report.notes.begin(), result.report.notes.end());
    if (result.report.choice)  // e.g. the fallback outside the parameter model's range (core/auto/choose.h)
      for (const std::string& note : result.report.choice->notes) run_notes.push_back(note);
    out.reports.push_back(result.report);
  }
  out.timings.denoise_ms = ms_since(start);

  out.format = *encode.format;
  out.media_type = std::string(io::media_type(out.format));
  out.effective.output.format = out.format;  // echo what was actually produced

  start = Clock::now();
  io::Encoded encoded = document->encode(encode);
  out.bytes = std::move(encoded.bytes);
  out.compression = encoded.compression;  // what the encoder wrote: the one place it is known
  if (is_gltf(out.format)) out.effective.output.compression = out.compression;
  out.timings.encode_ms = ms_since(start);
  out.notes = document->notes();
  out.notes.insert(out.notes.end(), encoded.notes.begin(), encoded.notes.end());  // what the positions became
  out.notes.insert(out.notes.end(), run_notes.begin(), run_notes.end());
  out.placements = document->placements();
  out.surfaces = std::move(document->surfaces());  // the document is done with them
  return out;
}

}  // namespace

JobOutput run_job(const JobInput& input, const io::Limits& limits, ProgressObserver* progress) {
  return run(input, nullptr, limits, progress);
}

JobOutput run_job(JobInput&& input, const io::Limits& limits, ProgressObserver* progress) {
  return run(input, &input.bytes, limits, progress);
}

}  // namespace mdn::service
