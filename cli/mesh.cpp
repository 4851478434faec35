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

mdn::TriMesh merge_surfaces(const std::vector<mdn::TriMesh>& surfaces) {
  std::int64_t nv = 0, nf = 0;
  for (const auto& s : surfaces) {
    nv += s.num_vertices();
    nf += s.num_faces();
  }
  mdn::TriMesh merged;
  merged.V.resize(nv, 3);
  merged.F.resize(nf, 3);
  std::int64_t v0 = 0, f0 = 0;
  for (const auto& s : surfaces) {
    merged.V.middleRows(v0, s.num_vertices()) = s.V;
    merged.F.middleRows(f0, s.num_faces()) = s.F.array() + static_cast<std::int32_t>(v0);
    v0 += s.num_vertices();
    f0 += s.num_faces();
  }
  return merged;
}

mdn::TriMesh scene_mesh(const std::vector<mdn::TriMesh>& surfaces,
                        const std::vector<std::vector<Eigen::Matrix4d>>& placements) {
  static const std::vector<Eigen::Matrix4d> kAsIs = {Eigen::Matrix4d::Identity()};
  std::vector<mdn::TriMesh> shown;
  for (std::size_t i = 0; i < surfaces.size(); ++i) {
    const auto& where = i < placements.size() && !placements[i].empty() ? placements[i] : kAsIs;
    for (const Eigen::Matrix4d& m : where) {
      mdn::TriMesh copy = surfaces[i];
      // Rows are points: V * A^T + t^T.
      copy.V = (surfaces[i].V * m.topLeftCorner<3, 3>().transpose()).rowwise() + m.topRightCorner<3, 1>().transpose();
      shown.push_back(std::move(copy));
    }
  }
  return merge_surfaces(shown);
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
  if (truth.num_faces() != result.num_faces() || truth.F != result.F) {
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
