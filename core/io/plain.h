// Internal to mdn_io: writers for bare triangle surfaces, used when the caller asks for an
// output container other than the input's (e.g. OFF in, PLY out). They write positions and
// triangles only; what the input carried besides geometry stays with same-format outputs.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/document.h"

namespace mdn::io::detail {

// Surfaces are concatenated into one mesh for the single-mesh formats (OFF, OBJ, PLY, DRC, STL)
// and become one glTF mesh each (one node per mesh) for GLB / glTF.
Encoded encode_plain(const std::vector<TriMesh>& surfaces, Format format, const EncodeOptions& options);

std::string write_off(const TriMesh& mesh);
std::string write_obj(const TriMesh& mesh);
std::string write_ply(const TriMesh& mesh);  // binary little endian, float positions, int indices
std::string write_drc(const TriMesh& mesh, const EncodeOptions& options);
// Binary STL: `header` (80 bytes, padded) and per-facet attribute bytes (0 where absent);
// ASCII STL: `name` after "solid". Facet normals from the written corners.
std::string write_stl_binary(const TriMesh& mesh, std::string_view header = {},
                             const std::vector<std::uint16_t>& attributes = {});
std::string write_stl_ascii(const TriMesh& mesh, std::string_view name);
Encoded write_plain_gltf(const std::vector<TriMesh>& surfaces, Format format, const EncodeOptions& options);

// Throws UnsupportedError (HTTP 422) if a coordinate does not fit in the float32 that `format`
// stores positions in (PLY as written here, glTF), before anything is written.
void check_float_coordinates(const std::vector<TriMesh>& surfaces, Format format);

// Throws InvalidMeshError if a caller changed the number of vertices of a surface (the
// document maps every welded vertex back to the file's copies and needs the same count), and
// UnsupportedError if a position is not finite. Every document's encode() calls it first.
void check_surface_sizes(const std::vector<TriMesh>& surfaces, const std::vector<std::int64_t>& counts);

}  // namespace mdn::io::detail
