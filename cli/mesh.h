// The meshes of meshdenoise: an input's format (by extension, else by its bytes) and OUT's
// (by extension), decoding under the tool's own limits, a whole document as one mesh, and the
// measures against a ground truth (MSAE, E_v). A mesh or format problem is a FileError naming
// the file it came from.
#pragma once

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/errors.h"
#include "core/io/document.h"
#include "core/mesh.h"
#include "cli/files.h"
#include "cli/options.h"
#include "service/reference.h"

namespace mdn::cli {

// IN's format by its extension, else by its contents; throws FileError when neither tells.
io::Format input_format(const std::string& path, const std::string& bytes);
// OUT's format by its extension; none if it has no extension (then output.format or IN's).
// An extension that names no format is refused rather than written as IN's format.
std::optional<io::Format> output_format_by_name(const std::string& path);

// Runs fn; a mesh or format problem is reported against the file it came from (exit 3).
template <typename Fn>
auto blame_file(const std::string& path, Fn&& fn) -> decltype(fn()) {
  try {
    return fn();
  } catch (const mdn::InvalidParamsError&) {
    throw;  // InvalidParamsError is an invalid_argument too, but it is the user's parameters
  } catch (const mdn::InvalidMeshError& e) {
    throw FileError(path + ": " + e.what());
  } catch (const io::UnsupportedError& e) {
    throw FileError(path + ": unsupported: " + e.what());
  } catch (const io::LimitError& e) {
    throw FileError(path + ": too large: " + e.what());
  }
}

struct LoadedMesh {
  std::unique_ptr<io::MeshDocument> document;
  mdn::TriMesh merged;  // all surfaces in one mesh, in their own coordinates (what is denoised)
  mdn::TriMesh scene;   // the same as the scene shows it (scene_mesh), for the metrics
};

// A whole document as one mesh, and as its scene shows it (--metrics measures in that frame):
// shared with the server's reference comparison (service/reference.h).
using service::merge_surfaces;
using service::scene_mesh;
LoadedMesh decode_mesh(const std::string& path, const std::string& bytes, io::Format format, const io::Limits& limits);
LoadedMesh load_mesh(const std::string& path, const InputLimits& limits);

// MSAE and E_v of `result` against the ground truth (Sec. 7). Both need the same faces in the
// same order; formats that renumber them (Draco) cannot be compared after the fact.
nlohmann::json measure(const mdn::TriMesh& truth, const std::string& truth_path, const mdn::TriMesh& result,
                       const std::string& result_path, int threads);

}  // namespace mdn::cli
