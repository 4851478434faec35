#include "core/io/draco_codec.h"

#include <draco/compression/decode.h>
#include <draco/compression/encode.h>
#include <draco/compression/mesh/mesh_edgebreaker_decoder.h>
#include <draco/compression/mesh/mesh_sequential_decoder.h>
#include <draco/core/varint_decoding.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>

#include "core/errors.h"
#include "core/io/detail.h"
#include "core/io/encode_check.h"

namespace mdn::io::detail {

namespace {

// Draco sizes its buffers from counts declared in the bitstream (an edgebreaker header of a
// few bytes can declare a billion faces; a sequential one 4 billion points, which every
// attribute then allocates). Draco's own decoders are run here through subclasses that read
// those counts where the bitstream declares them and refuse them against Limits before Draco
// allocates anything for them: the connectivity counts before DecodeConnectivity, and the
// attribute sizes (points x components x bytes, every attribute) before DecodeAllAttributes.
// The memory Draco needs is bounded by what the limits allow (core/io/README.md, "Limits").
struct DracoBudget {
  const Limits& limits;
  std::string refused;  // why a declared size was refused ("" if none was)

  // Checks the counts an edgebreaker or sequential header declares. Bytes charged are what
  // Draco's decoder holds per face and per vertex (corner table, traversal state).
  bool connectivity(std::uint64_t faces, std::uint64_t vertices) {
    if (faces > static_cast<std::uint64_t>(limits.max_faces))
      return refuse("the Draco payload declares " + std::to_string(faces) + " faces, more than the limit of " +
                    std::to_string(limits.max_faces) + " (max_faces)");
    if (vertices > static_cast<std::uint64_t>(limits.max_vertices))
      return refuse("the Draco payload declares " + std::to_string(vertices) + " vertices, more than the limit of " +
                    std::to_string(limits.max_vertices) + " (max_vertices)");
    return charge(static_cast<std::int64_t>(faces) * 96 + static_cast<std::int64_t>(vertices) * 48);
  }
  // Every attribute's values for every point, plus Draco's portable (integer) copy of each.
  bool attributes(const draco::PointCloud& cloud) {
    const auto points = static_cast<std::int64_t>(cloud.num_points());
    if (points > limits.max_vertices * 3)  // a point per corner at most
      return refuse("the Draco payload declares " + std::to_string(points) + " points, more than the limit of " +
                    std::to_string(limits.max_vertices * 3) + " (3 x max_vertices)");
    std::int64_t per_point = 0;
    for (int i = 0; i < cloud.num_attributes(); ++i) {
      const draco::PointAttribute* a = cloud.attribute(i);
      if (a == nullptr) continue;
      per_point += static_cast<std::int64_t>(a->num_components()) * (std::max(draco::DataTypeLength(a->data_type()), 1) + 4);
    }
    return charge(points * per_point * 2 + static_cast<std::int64_t>(cloud.num_attributes()) * 256);
  }
  bool charge(std::int64_t bytes) {
    if (bytes > limits.max_decoded_bytes)
      return refuse("decoding the Draco payload would take about " + std::to_string(bytes) + " bytes, more than the limit of " +
                    std::to_string(limits.max_decoded_bytes) + " (max_decoded_bytes)");
    return true;
  }
  bool refuse(std::string why) {
    refused = std::move(why);
    return false;
  }
};

// Reads a count as the bitstream stores it: 32-bit before version 2.0 (2.2 for sequential
// meshes), a varint after.
bool read_count(draco::DecoderBuffer& buffer, bool fixed, std::uint32_t& value) {
  return fixed ? buffer.Decode(&value) : draco::DecodeVarint(&value, &buffer);
}

class BoundedEdgebreakerDecoder final : public draco::MeshEdgebreakerDecoder {
 public:
  explicit BoundedEdgebreakerDecoder(DracoBudget& budget) : budget_(budget) {}

 protected:
  // Bitstream (Draco spec, ParseEdgebreakerConnectivityData): [num_new_vertices before 2.2],
  // num_encoded_vertices, num_faces, num_attribute_data (u8), num_encoded_symbols,
  // num_encoded_split_symbols. The traversal type byte was read by InitializeDecoder.
  bool DecodeConnectivity() override {
    draco::DecoderBuffer peek(*buffer());
    const std::uint16_t version = bitstream_version();
    const bool fixed = version < DRACO_BITSTREAM_VERSION(2, 0);
    std::uint32_t skip = 0, vertices = 0, faces = 0, split = 0, symbols = 0;
    std::uint8_t attribute_data = 0;
    if (version < DRACO_BITSTREAM_VERSION(2, 2) && !read_count(peek, fixed, skip)) return false;
    if (!read_count(peek, fixed, vertices) || !read_count(peek, fixed, faces) || !peek.Decode(&attribute_data) ||
        !read_count(peek, fixed, symbols) || !read_count(peek, fixed, split))
      return false;
    if (!budget_.connectivity(faces, std::uint64_t{vertices} + split)) return false;
    return draco::MeshEdgebreakerDecoder::DecodeConnectivity();
  }
  bool DecodeAllAttributes() override {
    return budget_.attributes(*point_cloud()) && draco::MeshEdgebreakerDecoder::DecodeAllAttributes();
  }

 private:
  DracoBudget& budget_;
};

class BoundedSequentialDecoder final : public draco::MeshSequentialDecoder {
 public:
  explicit BoundedSequentialDecoder(DracoBudget& budget) : budget_(budget) {}

 protected:
  // Bitstream (Draco spec, ParseSequentialConnectivityData): num_faces, num_points.
  bool DecodeConnectivity() override {
    draco::DecoderBuffer peek(*buffer());
    const bool fixed = bitstream_version() < DRACO_BITSTREAM_VERSION(2, 2);
    std::uint32_t faces = 0, points = 0;
    if (!read_count(peek, fixed, faces) || !read_count(peek, fixed, points)) return false;
    if (!budget_.connectivity(faces, points)) return false;
    return draco::MeshSequentialDecoder::DecodeConnectivity();
  }
  bool DecodeAllAttributes() override {
    return budget_.attributes(*point_cloud()) && draco::MeshSequentialDecoder::DecodeAllAttributes();
  }

 private:
  DracoBudget& budget_;
};

}  // namespace

std::unique_ptr<draco::Mesh> draco_decode(std::string_view bytes, const std::string& what, const Limits& limits) {
  draco::DecoderBuffer buffer;
  buffer.Init(bytes.data(), bytes.size());
  draco::DecoderBuffer peek(buffer);
  draco::DracoHeader header;
  const draco::Status status = draco::PointCloudDecoder::DecodeHeader(&peek, &header);
  if (!status.ok()) throw FormatError(what + ": not a Draco payload (" + status.error_msg_string() + ")");
  if (header.encoder_type != draco::TRIANGULAR_MESH)
    throw UnsupportedError(what + ": the Draco payload is a point cloud, not a triangle mesh");
  DracoBudget budget{limits, {}};
  std::unique_ptr<draco::MeshDecoder> decoder;
  if (header.encoder_method == draco::MESH_EDGEBREAKER_ENCODING) decoder = std::make_unique<BoundedEdgebreakerDecoder>(budget);
  else if (header.encoder_method == draco::MESH_SEQUENTIAL_ENCODING) decoder = std::make_unique<BoundedSequentialDecoder>(budget);
  else throw FormatError(what + ": unknown Draco encoding method " + std::to_string(header.encoder_method));
  auto mesh = std::make_unique<draco::Mesh>();
  const draco::DecoderOptions options;
  // Draco's decoder cannot be interrupted: the job's cancellation is asked before and after,
  // and its work in between is bounded by the declared sizes checked above (DracoBudget).
  CancelPoll cancel(limits.cancel);
  cancel.check();
  const draco::Status decoded = decoder->Decode(options, &buffer, mesh.get());
  cancel.check();
  if (!budget.refused.empty()) throw LimitError(what + ": " + budget.refused);
  if (!decoded.ok()) throw FormatError(what + ": corrupt Draco payload (" + decoded.error_msg_string() + ")");
  check_count(mesh->num_faces(), limits.max_faces, "faces");
  check_count(mesh->num_points(), limits.max_vertices, "vertices");
  if (mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION) == nullptr)
    throw FormatError(what + ": the Draco mesh has no POSITION attribute");
  const auto* position = mesh->GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position->num_components() != 3) throw FormatError(what + ": Draco POSITION must have 3 components");
  // Read through ConvertValue, which loads each component as its declared type: a bool byte
  // other than 0 or 1 is undefined behaviour there (found by fuzz_drc under UBSan).
  if (position->data_type() == draco::DT_BOOL || position->data_type() == draco::DT_INVALID)
    throw FormatError(what + ": Draco POSITION must have a numeric type");
  for (draco::FaceIndex f(0); f < mesh->num_faces(); ++f)
    for (int k = 0; k < 3; ++k)
      if (mesh->face(f)[k].value() >= mesh->num_points()) throw FormatError(what + ": a Draco face references a missing point");
  return mesh;
}

namespace {

// The bits Draco quantises an attribute of this type with (0: stored losslessly). Only float32
// attributes are quantised; the others are packed as they are.
int quantization_bits(const draco::PointAttribute& a, const EncodeOptions& options) {
  if (a.data_type() != draco::DT_FLOAT32) return 0;
  switch (a.attribute_type()) {
    case draco::GeometryAttribute::POSITION: return options.position_bits;
    case draco::GeometryAttribute::NORMAL: return options.normal_bits;
    case draco::GeometryAttribute::TEX_COORD: return options.texcoord_bits;
    case draco::GeometryAttribute::COLOR: return options.color_bits;
    case draco::GeometryAttribute::GENERIC: return options.generic_bits;
    default: return 0;
  }
}

const char* attribute_name(const draco::PointAttribute& a) {
  switch (a.attribute_type()) {
    case draco::GeometryAttribute::POSITION: return "POSITION";
    case draco::GeometryAttribute::NORMAL: return "NORMAL";
    case draco::GeometryAttribute::TEX_COORD: return "TEXCOORD";
    case draco::GeometryAttribute::COLOR: return "COLOR";
    default: return "a generic attribute";
  }
}

// Draco quantises an attribute on a float grid over the values' range (over all components):
// a value or a range past the float range makes that grid infinite, and the encoder then
// crashes (SIGSEGV; found for POSITION, TEXCOORD_0 and COLOR_0 at +-3e38). Normals go through
// an octahedral map that sums the components' magnitudes first. So every quantised value must
// be finite, positions may span at most kMaxDracoSpan, and other attributes' values lie within
// +-kMaxDracoSpan / 4 (their sum over 4 components and their range stay finite).
void check_quantized_values(const draco::PointAttribute& a) {
  const bool position = a.attribute_type() == draco::GeometryAttribute::POSITION;
  const int n = a.num_components();
  if (n < 1 || n > 4)
    throw UnsupportedError(std::string("the mesh cannot be written as Draco: ") + attribute_name(a) +
                           " has " + std::to_string(n) + " components (Draco quantises 1 to 4)");
  const double bound = position ? std::numeric_limits<float>::max() : kMaxDracoSpan / 4;
  double lo[4], hi[4];
  std::fill(lo, lo + 4, std::numeric_limits<double>::infinity());
  std::fill(hi, hi + 4, -std::numeric_limits<double>::infinity());
  for (draco::AttributeValueIndex i(0); i < static_cast<std::uint32_t>(a.size()); ++i) {
    float value[4] = {0, 0, 0, 0};
    if (!a.ConvertValue<float>(i, n, value))
      throw UnsupportedError(std::string("the mesh cannot be written as Draco: unreadable ") + attribute_name(a));
    for (int k = 0; k < n; ++k) {
      if (!std::isfinite(value[k]) || std::abs(double(value[k])) > bound) {
        if (position)
          throw UnsupportedError("the mesh cannot be written as Draco: a coordinate is outside the float range (|x| > 3.4e38)");
        char text[64];
        std::snprintf(text, sizeof text, "%.3g, outside +-%.3g", double(value[k]), bound);
        throw UnsupportedError(std::string("the mesh cannot be written as Draco: ") + attribute_name(a) + " has a value of " +
                               text + " (Draco quantises it on a float grid; store it losslessly with 0 bits)");
      }
      lo[k] = std::min(lo[k], double(value[k]));
      hi[k] = std::max(hi[k], double(value[k]));
    }
  }
  for (int k = 0; k < n; ++k)
    if (hi[k] - lo[k] > kMaxDracoSpan) {
      char text[96];
      std::snprintf(text, sizeof text, "its values span %.3g, more than Draco's float grid can hold (%.3g)", hi[k] - lo[k],
                    kMaxDracoSpan);
      throw UnsupportedError(std::string("the mesh cannot be written as Draco: ") + attribute_name(a) + ": " + text);
    }
}

std::string encode_with_speed(draco::Encoder& encoder, const draco::Mesh& mesh, int speed) {
  encoder.SetSpeedOptions(speed, speed);
  draco::EncoderBuffer buffer;
  const draco::Status status = encoder.EncodeMeshToBuffer(mesh, &buffer);
  // Whatever else Draco's encoder refuses is a property of this mesh, not a fault of ours.
  if (!status.ok()) throw UnsupportedError("the mesh cannot be written as Draco: " + status.error_msg_string());
  return std::string(buffer.data(), buffer.size());
}

bool decodes(const std::string& payload) {
  draco::DecoderBuffer buffer;
  buffer.Init(payload.data(), payload.size());
  draco::Decoder decoder;
  return decoder.DecodeMeshFromBuffer(&buffer).ok();
}

}  // namespace

void check_draco_encodable(const draco::Mesh& mesh, const EncodeOptions& options) {
  const auto* position = mesh.GetNamedAttribute(draco::GeometryAttribute::POSITION);
  if (position == nullptr || position->num_components() != 3)
    throw UnsupportedError("the mesh cannot be written as Draco: no 3-component POSITION");
  for (int i = 0; i < mesh.num_attributes(); ++i) {
    const draco::PointAttribute* a = mesh.attribute(i);
    if (a != nullptr && (a == position || quantization_bits(*a, options) > 0)) check_quantized_values(*a);
  }
  // Draco drops faces that repeat a corner and fails on a mesh with none left.
  bool any = mesh.num_faces() == 0;
  for (draco::FaceIndex f(0); !any && f < mesh.num_faces(); ++f) {
    const auto a = position->mapped_index(mesh.face(f)[0]), b = position->mapped_index(mesh.face(f)[1]),
               c = position->mapped_index(mesh.face(f)[2]);
    any = a != b && b != c && a != c;
  }
  if (!any)
    throw UnsupportedError("the mesh cannot be written as Draco: all of its " + std::to_string(mesh.num_faces()) +
                           " triangles are degenerate (a corner repeated)");
}

std::string draco_encode(const draco::Mesh& mesh, const EncodeOptions& options, const std::optional<QuantizationBox>& box) {
  // The request's ranges were checked where it was parsed (output_settings.h); this guards only
  // against what Draco's quantiser cannot take at all.
  for (const int bits : {options.normal_bits, options.texcoord_bits, options.color_bits, options.generic_bits})
    if (bits < 0 || bits > 30) throw std::invalid_argument("draco_encode: quantisation bits outside [0, 30]");
  if (options.position_bits < 1 || options.position_bits > 30 || options.compression_level < 0 || options.compression_level > 10)
    throw std::invalid_argument("draco_encode: position_bits outside [1, 30] or compression_level outside [0, 10]");
  CancelPoll(options.cancel).check();  // the encoder itself runs to its end
  check_draco_encodable(mesh, options);
  // The tables of the largest setting in use (encode_check.h), against the same bound as decoding.
  if (const std::int64_t need = draco_encode_bytes(options, mesh.num_faces()); need > options.max_memory_bytes)
    throw UnsupportedError("the mesh cannot be written as Draco with these quantisation bits: about " + std::to_string(need) +
                           " bytes of encoder memory, more than the limit of " + std::to_string(options.max_memory_bytes) +
                           " (max_decoded_bytes)");
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
  // Speeds 0 and 1 (levels 10 and 9) predict positions with Draco's constrained
  // multi-parallelogram scheme, which writes out of bounds (SIGSEGV, the whole process) on an
  // explicit position grid narrower than about 1e-6 (a mesh collapsed to a point, or a tiny
  // one; issue 49, item 0). Such a grid takes the plain parallelogram prediction instead; the
  // other settings stay as asked (decision 77).
  if (speed <= 1 && box && box->range < kMinConstrainedPredictionRange)
    encoder.SetAttributePredictionScheme(draco::GeometryAttribute::POSITION, draco::MESH_PREDICTION_PARALLELOGRAM);
  std::string out = encode_with_speed(encoder, mesh, speed);
  // What is written must read back. Draco's speed 10 (sequential encoding) writes a payload
  // its own decoder refuses when a point is not used by any face (found by fuzz_off with
  // fuzzed output settings): every payload is decoded once here, and one that does not decode
  // is written again with the edgebreaker (speed 9) before giving up with a 422.
  if (!decodes(out) && speed == 10) out = encode_with_speed(encoder, mesh, 9);
  if (!decodes(out)) throw UnsupportedError("the mesh cannot be written as Draco: Draco's encoder wrote a payload it cannot read back");
  return out;
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
