#include "cli/denoise.h"

#include <utility>

#include "cli/files.h"
#include "cli/mesh.h"
#include "service/job_json.h"
#include "service/output_files.h"

namespace mdn::cli {

InputFile read_input(const std::string& path, const InputLimits& limits) {
  InputFile in{.path = path, .bytes = read_file(path, limits.max_input_bytes)};
  in.format = input_format(path, in.bytes);
  in.data_beside = in.format == io::Format::Gltf && service::has_external_uris(in.bytes);
  return in;
}

GroundTruth load_truth(const std::string& path, const InputLimits& limits) {
  return {load_mesh(path, limits).scene, path};
}

DenoisedFile denoise_file(InputFile in, const std::string& out_path, const service::JobParams& params, int threads,
                          const io::Limits& limits, CliProgress& progress, const GroundTruth* truth) {
  service::JobOutput output = denoise_input(in.path, std::move(in.bytes), in.format, params, threads, limits, progress);
  DenoisedFile file;
  file.summary = service::output_to_json(output);  // before the bytes move out
  file.faces = output.faces;
  add_paths(file.summary, in.path, in.format, out_path);
  // The metrics measure the computed surface, so every output format gives the same figures;
  // the file's own quantisation (Draco) can be measured afterwards with --metrics GT OUT.
  if (truth) {
    file.metrics = measure(truth->scene, truth->path, scene_mesh(output.surfaces, output.placements), in.path, threads);
  }
  write_output(in.path, in.data_beside, out_path, std::move(output.bytes), output.format);
  return file;
}

}  // namespace mdn::cli
