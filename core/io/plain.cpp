// Writers for bare triangle surfaces (cross-format conversion).
#include "core/io/plain.h"

#include <draco/mesh/mesh.h>

#include <cstring>
#include <limits>
#include <string>

#include "core/io/detail.h"
#include "core/io/draco_codec.h"

namespace mdn::io::detail {
namespace {

TriMesh concatenate(const std::vector<TriMesh>& surfaces) {
  TriMesh out;
  Eigen::Index nv = 0, nf = 0;
  for (const auto& s : surfaces) {
    nv += s.V.rows();
    nf += s.F.rows();
  }
  out.V.resize(nv, 3);
  out.F.resize(nf, 3);
  Eigen::Index v = 0, f = 0;
  for (const auto& s : surfaces) {
    out.V.middleRows(v, s.V.rows()) = s.V;
    out.F.middleRows(f, s.F.rows()) = s.F.array() + static_cast<std::int32_t>(v);
    v += s.V.rows();
    f += s.F.rows();
  }
  return out;
}

// Bytes a text writer's output is likely to take (about 20 per coordinate, 8 per index), so its
// string grows at most once or twice.
std::size_t text_size_estimate(const TriMesh& mesh) {
  return static_cast<std::size_t>(mesh.V.rows() * 60 + mesh.F.rows() * 24 + 64);
}

}  // namespace

void check_surface_sizes(const std::vector<TriMesh>& surfaces, const std::vector<std::int64_t>& counts) {
  if (surfaces.size() != counts.size())
    throw InvalidMeshError("the document had " + std::to_string(counts.size()) + " surfaces, now " +
                           std::to_string(surfaces.size()));
  for (std::size_t i = 0; i < counts.size(); ++i)
    if (surfaces[i].V.rows() != counts[i] || surfaces[i].V.cols() != 3)
      throw InvalidMeshError("surface " + std::to_string(i) + " had " + std::to_string(counts[i]) +
                             " vertices; replaced positions must keep that count");
  // A non-finite position would be written as "nan" / "inf" (text) or as a float no reader
  // takes back (binary): every writer refuses it here, before writing anything.
  for (const TriMesh& s : surfaces)
    if (!s.V.allFinite()) throw UnsupportedError("the mesh cannot be written: a vertex position is not a finite number");
}

void check_float_coordinates(const std::vector<TriMesh>& surfaces, Format format) {
  constexpr double kFloatMax = std::numeric_limits<float>::max();
  for (const TriMesh& s : surfaces)
    if (s.V.size() > 0 && !(s.V.cwiseAbs().maxCoeff() <= kFloatMax))  // NaN fails too
      throw UnsupportedError("the mesh cannot be written as " + std::string(to_string(format)) +
                             ": a coordinate is outside the float range (|x| > 3.4e38)");
}

std::string write_off(const TriMesh& mesh) {
  std::string out = "OFF\n" + std::to_string(mesh.V.rows()) + ' ' + std::to_string(mesh.F.rows()) + " 0\n";
  out.reserve(text_size_estimate(mesh));
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
    for (int k = 0; k < 3; ++k) {
      if (k) out += ' ';
      append_number(out, mesh.V(i, k));
    }
    out += '\n';
  }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    out += '3';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, std::int64_t{mesh.F(f, k)});
    }
    out += '\n';
  }
  return out;
}

std::string write_obj(const TriMesh& mesh) {
  std::string out;
  out.reserve(text_size_estimate(mesh));
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
    out += 'v';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, mesh.V(i, k));
    }
    out += '\n';
  }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    out += 'f';
    for (int k = 0; k < 3; ++k) {
      out += ' ';
      append_number(out, std::int64_t{mesh.F(f, k)} + 1);
    }
    out += '\n';
  }
  return out;
}

std::string write_ply(const TriMesh& mesh) {
  static_assert(std::endian::native == std::endian::little, "binary PLY writer assumes a little-endian host");
  std::string out = "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(mesh.V.rows()) +
                    "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(mesh.F.rows()) +
                    "\nproperty list uchar int vertex_indices\nend_header\n";
  out.reserve(out.size() + static_cast<std::size_t>(mesh.V.rows() * 12 + mesh.F.rows() * 13));
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
    for (int k = 0; k < 3; ++k) {
      const auto value = static_cast<float>(mesh.V(i, k));
      out.append(reinterpret_cast<const char*>(&value), 4);
    }
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    out += char(3);
    for (int k = 0; k < 3; ++k) {
      const std::int32_t index = mesh.F(f, k);
      out.append(reinterpret_cast<const char*>(&index), 4);
    }
  }
  return out;
}

std::string write_drc(const TriMesh& mesh, const EncodeOptions& options) {
  draco::Mesh dm;
  dm.set_num_points(static_cast<std::uint32_t>(mesh.V.rows()));
  draco::GeometryAttribute position;
  position.Init(draco::GeometryAttribute::POSITION, nullptr, 3, draco::DT_FLOAT32, false, sizeof(float) * 3, 0);
  const int id = dm.AddAttribute(position, true, static_cast<std::uint32_t>(mesh.V.rows()));
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i) {
    const float value[3] = {float(mesh.V(i, 0)), float(mesh.V(i, 1)), float(mesh.V(i, 2))};
    dm.attribute(id)->SetAttributeValue(draco::AttributeValueIndex(static_cast<std::uint32_t>(i)), value);
  }
  dm.SetNumFaces(static_cast<std::size_t>(mesh.F.rows()));
  for (Eigen::Index f = 0; f < mesh.F.rows(); ++f) {
    draco::Mesh::Face face;
    for (int k = 0; k < 3; ++k) face[k] = draco::PointIndex(static_cast<std::uint32_t>(mesh.F(f, k)));
    dm.SetFace(draco::FaceIndex(static_cast<std::uint32_t>(f)), face);
  }
  return draco_encode(dm, options);
}

Encoded encode_plain(const std::vector<TriMesh>& surfaces, Format format, const EncodeOptions& options) {
  if (format == Format::Ply || format == Format::Stl || format == Format::Glb || format == Format::Gltf)
    check_float_coordinates(surfaces, format);
  CancelPoll(options.cancel).check();  // the writers below are linear in the (limited) mesh size
  switch (format) {
    case Format::Off: return {write_off(concatenate(surfaces)), Compression::None};
    case Format::Obj: return {write_obj(concatenate(surfaces)), Compression::None};
    case Format::Ply: return {write_ply(concatenate(surfaces)), Compression::None};
    case Format::Drc: return {write_drc(concatenate(surfaces), options), Compression::Draco};
    case Format::Stl: return {write_stl_binary(concatenate(surfaces)), Compression::None};
    case Format::Glb:
    case Format::Gltf: return write_plain_gltf(surfaces, format, options);
  }
  throw UnsupportedError("unknown output format");
}

}  // namespace mdn::io::detail
