// One denoising job from bytes to bytes: decode, denoise every surface, encode. Shared by
// the command-line tool and the HTTP server's workers so both give identical bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "core/pipeline.h"
#include "server/params_json.h"

namespace mdn::service {

struct JobInput {
  std::string bytes;
  io::Format format;
  JobParams params;
  int threads = 1;  // threads for the core pipeline
};

struct JobOutput {
  std::string bytes;
  io::Format format;
  std::string media_type;
  JobParams effective;                  // parameters actually used
  std::vector<DenoiseReport> reports;   // one per surface
  std::vector<std::string> notes;       // from the adapter (e.g. TANGENT dropped)
  std::int64_t vertices = 0, faces = 0; // summed over surfaces
  double decode_ms = 0, denoise_ms = 0, encode_ms = 0;
  StageTimings stages;                  // summed over surfaces
  // Added by the cli engineer (additive): the denoised surfaces in the document's order, in the
  // input frame, exactly as encoded (before any quantisation of the output format). Moved out
  // of the document after encoding, so it costs nothing; the CLI's --metrics measures these.
  std::vector<TriMesh> surfaces;
};

// Throws what io::decode and mdn::denoise throw (FormatError, UnsupportedError, LimitError,
// InvalidMeshError, InvalidParamsError, SolverError, CancelledError).
JobOutput run_job(const JobInput& input, const io::Limits& limits, ProgressObserver* progress = nullptr);

// Added by the cli engineer (additive): the JSON summary of a finished job, the same shape the
// CLI prints with --report and the HTTP server may echo:
//   { "format": "off", "media_type": ..., "bytes": N, "vertices": N, "faces": N,
//     "params": to_json(effective), "timings_ms": { "decode", "denoise", "encode", "setup", "measure",
//     "initial", "region", "anisotropic", "normal", "vertex", "prefilter", "total" },
//     "surfaces": [ report_to_json(r) ... ], "notes": [ ... ] }
// Timings are wall-clock and vary between runs; everything else is deterministic.
// fold_ratio, cluster_area_ratio, region_*, "mode", "params" (what ran: the six parameters and
// region_mode, as a manual-mode params object) and, in auto mode, "measures".
nlohmann::json report_to_json(const DenoiseReport& report);
nlohmann::json job_summary_json(const JobOutput& output);

}  // namespace mdn::service
