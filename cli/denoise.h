// The one denoise path of meshdenoise: a single run (IN OUT) and every file of an --out-dir
// batch go through denoise_file(), so both read, denoise, measure and write a file the same way.
#pragma once

#include <cstdint>
#include <optional>
#include <string>

#include <nlohmann/json.hpp>

#include "cli/job.h"
#include "core/io/document.h"
#include "core/mesh.h"
#include "service/job_runner.h"

namespace mdn::cli {

// One input as read: its path ("-": standard input), bytes and format (by extension, else by
// content). Throws FileError.
struct InputFile {
  std::string path;
  std::string bytes;
  io::Format format = io::Format::Off;
  bool data_beside = false;  // a .gltf whose buffers or images are files beside it
};
InputFile read_input(const std::string& path, const InputLimits& limits);

// A ground truth for --metrics: the mesh as its scene shows it, and where it came from.
struct GroundTruth {
  mdn::TriMesh scene;
  std::string path;
};
GroundTruth load_truth(const std::string& path, const InputLimits& limits);

// What denoising one file gave: the --report summary (input and output paths included), the
// metrics against the ground truth when one was given, and the faces (the batch's line).
struct DenoisedFile {
  nlohmann::json summary;
  std::optional<nlohmann::json> metrics;
  std::int64_t faces = 0;
};

// Runs IN through the shared job runner, measures the computed surfaces against `truth` (if
// any; before writing, so a failed comparison leaves no OUT) and writes OUT with the one output
// writer. A problem with the input is a FileError naming it. The input's bytes go to the job,
// which frees them once decoded under `limits`.
DenoisedFile denoise_file(InputFile in, const std::string& out_path, const service::JobParams& params, int threads,
                          const io::Limits& limits, CliProgress& progress, const GroundTruth* truth = nullptr);

}  // namespace mdn::cli
