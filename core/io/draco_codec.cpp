#include "core/io/draco_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>

#include <algorithm>
#include <cmath>

#include "core/errors.h"
#include "core/io/detail.h"

namespace mdn::io::detail {

std::unique_ptr<draco::Mesh> draco_decode(std::string_view bytes, const std::string& what, const Limits& limits) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  auto type = draco::Decoder::GetEncodedGeometryType(&buffer);
  if (!type.ok()) throw FormatError(what + ": not a Draco payload (" + type.status().error_msg_string() + ")");
  if (type.value() != draco::TRIANGULAR_MESH)
    throw UnsupportedError(what + ": the Draco payload is a point cloud, not a triangle mesh");
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&buffer);
  if (!decoded.ok()) throw FormatError(what + ": corrupt Draco payload (" + decoded.status().error_msg_string() + ")");
  std::unique_ptr<draco::Mesh> mesh = std::move(decoded).value();
  if (!mesh) throw FormatError(what + ": the Draco payload decoded to nothing");
  // Draco sizes its buffers from the payload's header while decoding; what it produced is
  // checked here against the limits before any further copy is made.
  check_count(mesh->num_faces(), limits.max_faces, "faces");
  check_count(mesh->num_points(), limits.max_vertices, "vertices");
  if (mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION) == nullptr)
    throw FormatError(what + ": the Draco mesh has no POSITION attribute");
  const auto* position = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position->num_components() != 3) throw FormatError(what + ": Draco POSITION must have 3 components");
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh->face(f)[k].value() >= mesh->num_points()) throw FormatError(what + ": a Draco face references a missing point");
  return mesh;
}

std::string draco_encode(const draco::Mesh& mesh, const EncodeOptions& options, const std::optional<QuantizationBox>& box) {
  auto check_bits = [](int bits, const char* name) {
    if (bits < 0 || bits > 30) throw InvalidParamsError(name, std::string(name) + " must be 0 (lossless) or in [1, 30]");
  };
  if (options.position_bits < 8 || options.position_bits > 30)
    throw InvalidParamsError("position_bits", "position_bits must be in [8, 30]");
  check_bits(options.normal_bits, "normal_bits");
  check_bits(options.texcoord_bits, "texcoord_bits");
  check_bits(options.color_bits, "color_bits");
  check_bits(options.generic_bits, "generic_bits");
  if (options.compression_level < 0 || options.compression_level > 10)
    throw InvalidParamsError("compression_level", "compression_level must be in [0, 10]");
  draco::Encoder encoder;
  if (box) encoder.SetAttributeExplicitQuantization(draco::GeometryAttribute::POSITION, options.position_bits, 3, box->origin, box->range);
  else encoder.SetAttributeQuantization(draco::GeometryAttribute::POSITION, options.position_bits);
  // Attributes without quantisation bits are stored losslessly by Draco.
  const std::pair<draco::GeometryAttribute::Type, int> others[] = {
      {draco::GeometryAttribute::NORMAL, options.normal_bits},
      {draco::GeometryAttribute::TEX_COORD, options.texcoord_bits},
      {draco::GeometryAttribute::COLOR, options.color_bits},
      {draco::GeometryAttribute::GENERIC, options.generic_bits}};
  for (const auto& [type, bits] : others)
    if (bits > 0) encoder.SetAttributeQuantization(type, bits);
  // Draco's speed is the inverse of the compression level (0 = best compression).
  const int speed = 10 - options.compression_level;
  encoder.SetSpeedOptions(speed, speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  if (!status.ok()) throw std::runtime_error("Draco encoding failed: " + status.error_msg_string());
  return std::string(buffer.data(), buffer.size());
}

Vertices draco_positions(const draco::Mesh& mesh) {
  const auto* position = mesh.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  Vertices P(mesh.num_points(), 3);
  for (draco::PointIndex p(0); p < mesh.num_points(); ++p) {
    float value[3] = {0, 0, 0};
    if (!position->ConvertValue<float>(position->mapped_index(p), 3, value))
      throw FormatError("Draco POSITION has a type that cannot be read");
    for (int k = 0; k < 3; ++k) {
      if (!std::isfinite(value[k])) throw FormatError("Draco POSITION has a non-finite coordinate");
      P(p.value(), k) = value[k];
    }
  }
  return P;
}

Triangles draco_faces(const draco::Mesh& mesh) {
  Triangles F(mesh.num_faces(), 3);
  for (draco::FaceIndex f(0); f < mesh.num_faces(); ++f)
    for (int k = 0; k < 3; ++k) F(f.value(), k) = static_cast<std::int32_t>(mesh.face(f)[k].value());
  return F;
}

void draco_update_geometry(draco::Mesh& mesh, const Vertices& welded, const std::vector<std::int32_t>& point_to_weld) {
  auto* position = mesh.attribute(mesh.GetNamedAttributeId(draco::GeometryAttribute::POSITION));
  if (position->data_type() != draco::DT_FLOAT32)
    throw UnsupportedError("Draco POSITION attributes other than float32 cannot be rewritten");
  // Points that share a position value had the same position, hence the same welded vertex.
  for (draco::PointIndex p(0); p < mesh.num_points(); ++p) {
    const Eigen::Vector3f v = welded.row(point_to_weld[p.value()]).cast<float>();
    const float value[3] = {v.x(), v.y(), v.z()};
    position->SetAttributeValue(position->mapped_index(p), value);
  }
  const int normal_id = mesh.GetNamedAttributeId(draco::GeometryAttribute::NORMAL);
  if (normal_id < 0) return;
  auto* normal = mesh.attribute(normal_id);
  if (normal->data_type() != draco::DT_FLOAT32 || normal->num_components() != 3)
    throw UnsupportedError("Draco NORMAL attributes other than float32 x 3 cannot be rewritten");
  const Triangles F = draco_faces(mesh);
  Triangles FW(F.rows(), 3);
  std::vector<std::int64_t> slot(static_cast<std::size_t>(F.rows()) * 3);
  for (Eigen::Index f = 0; f < F.rows(); ++f)
    for (int k = 0; k < 3; ++k) {
      FW(f, k) = point_to_weld[static_cast<std::size_t>(F(f, k))];
      slot[static_cast<std::size_t>(f * 3 + k)] = normal->mapped_index(draco::PointIndex(F(f, k))).value();
    }
  const Vertices N = accumulate_normals(welded, FW, slot, static_cast<std::int64_t>(normal->size()));
  for (draco::AttributeValueIndex a(0); a < static_cast<std::uint32_t>(normal->size()); ++a) {
    const Eigen::Index row = a.value();
    if (N.row(row).squaredNorm() == 0) continue;  // unused value: unchanged
    const float value[3] = {float(N(row, 0)), float(N(row, 1)), float(N(row, 2))};
    normal->SetAttributeValue(a, value);
  }
}

}  // namespace mdn::io::detail
