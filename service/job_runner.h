// One denoising job from bytes to bytes: decode, denoise every surface, encode. Shared by
// the command-line tool and the HTTP server's workers so both give identical bytes.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "core/auto/denoise.h"
#include "service/job_timings.h"
#include "service/params_json.h"

namespace mdn::service {

// The bytes of one input as it arrives, before decoding: the server's --max-body and the
// command-line tool's --max-input default to it (decision 61).
inline constexpr std::int64_t kDefaultMaxInputBytes = std::int64_t{256} << 20;

struct JobInput {
  std::string bytes;
  io::Format format;
  JobParams params;
  int threads = 1;  // threads for the core pipeline
  // glTF: the folder external buffers and images are read from (io::DecodeOptions); only the
  // command-line tool sets it, so the service refuses every external URI.
  std::optional<std::string> resource_dir;
};

struct JobOutput {
  std::string bytes;
  io::Format format;
  std::string media_type;
  // The compression written, as the encoder reports it (io::Encoded): glTF as
  // io::resolve_compression chose it (the input's by default), DRC Draco, every other None.
  io::Compression compression = io::Compression::None;
  JobParams effective;                   // parameters actually used, output.format and compression resolved
  std::vector<DenoiseReport> reports;    // one per surface
  std::vector<std::string> notes;        // from the adapter (e.g. TANGENT dropped)
  std::int64_t vertices = 0, faces = 0;  // summed over surfaces
  JobTimings timings;                    // summed over surfaces
  // The denoised surfaces in the document's order, in the input frame, exactly as encoded
  // (before any quantisation of the output format). Moved out of the document after encoding,
  // so it costs nothing; the CLI's --metrics measures these.
  std::vector<TriMesh> surfaces;
  // Where each surface shows in the asset's scene (io::MeshDocument::placements()), for the
  // CLI's --metrics, which measures in the scene's frame.
  std::vector<std::vector<Eigen::Matrix4d>> placements;
};

// Throws what io::decode and mdn::denoise throw (FormatError, UnsupportedError, LimitError,
// InvalidMeshError, InvalidParamsError, SolverError, CancelledError).
JobOutput run_job(const JobInput& input, const io::Limits& limits, ProgressObserver* progress = nullptr);
// The same, and input.bytes is emptied as soon as it is decoded (the CLI: a 4.8M-face GLB's
// 87 MB are not held through the denoising).
JobOutput run_job(JobInput&& input, const io::Limits& limits, ProgressObserver* progress = nullptr);

// Its JSON view (CLI --report, HTTP, Redis) is service/job_json.h.

}  // namespace mdn::service
