#include "cli/mesh.h"

#include <cstdint>
#include <filesystem>
#include <numbers>

#include "core/metrics.h"
#include "core/parallel.h"
#include "cli/options.h"

namespace mdn::cli {
namespace {

using nlohmann::json;

// The extensions an OUT may have ("out.off", ..., "out.gltf").
std::string accepted_extensions() {
  std::string out;
  for (io::Format f : {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Stl, io::Format::Drc,
                       io::Format::Glb, io::Format::Gltf})
    out += (out.empty() ? "." : ", .") + std::string(io::to_string(f));
  return out;
}

}  // namespace

io::Format input_format(const std::string& path, const std::string& bytes) {
  if (auto format = io::format_from_extension(path)) return *format;
  if (auto format = io::sniff_format(bytes)) return *format;
  throw FileError("cannot tell the format of " + (path == kStdio ? std::string("standard input") : path) +
                  " from its extension or its contents (supported: off, obj, ply, stl, drc, glb, gltf)");
}

std::optional<io::Format> output_format_by_name(const std::string& path) {
  if (path == kStdio) return std::nullopt;
  const std::filesystem::path name = std::filesystem::path(path).filename();
  if (!name.has_extension() || name.stem().empty()) return std::nullopt;
  if (auto format = io::format_from_extension(name.string())) return format;
  throw UsageError("cannot write " + path + ": the extension " + name.extension().string() +
                   " names no format this tool writes (accepted: " + accepted_extensions() + ")");
}

LoadedMesh decode_mesh(const std::string& path, const std::string& bytes, io::Format format, const io::Limits& limits) {
  return blame_file(path, [&] {
    LoadedMesh loaded;
    loaded.document = io::decode(bytes, format, io::DecodeOptions{limits, resource_dir(path, format)});
    loaded.merged = merge_surfaces(loaded.document->surfaces());
    mdn::validate_mesh(loaded.merged);
    loaded.scene = scene_mesh(loaded.document->surfaces(), loaded.document->placements());
    mdn::validate_mesh(loaded.scene);  // a non-finite node matrix
    return loaded;
  });
}

LoadedMesh load_mesh(const std::string& path, const InputLimits& limits) {
  const std::string bytes = read_file(path, limits.max_input_bytes);
  return decode_mesh(path, bytes, input_format(path, bytes), limits.decode);
}

json measure(const mdn::TriMesh& truth, const std::string& truth_path, const mdn::TriMesh& result,
             const std::string& result_path, int threads) {
  if (!service::same_faces(truth, result)) {
    throw FileError(result_path + " and the ground truth " + truth_path +
                    " do not have the same faces in the same order (MSAE compares face by face; "
                    "Draco-compressed files renumber faces: measure while writing, or use another format)");
  }
  mdn::Executor executor(threads);
  const double msae = mdn::msae(result, truth);
  const double ev = mdn::vertex_error(result, truth, &executor);
  constexpr double kDeg = 180.0 / std::numbers::pi;
  return {{"msae", msae}, {"msae_deg2", msae * kDeg * kDeg}, {"ev", ev}};
}

}  // namespace mdn::cli
