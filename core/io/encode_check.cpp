#include "core/io/encode_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace mdn::io {
namespace {

struct BitsSetting {
  const char* name;
  int EncodeOptions::*field;
  int min;  // 0: "stored losslessly" allowed
};
// Positions below 8 bits wreck any mesh; the others may be 0 (lossless) or 1..30.
constexpr BitsSetting kBits[] = {{"position_bits", &EncodeOptions::position_bits, 8},
                                 {"normal_bits", &EncodeOptions::normal_bits, 0},
                                 {"texcoord_bits", &EncodeOptions::texcoord_bits, 0},
                                 {"color_bits", &EncodeOptions::color_bits, 0},
                                 {"generic_bits", &EncodeOptions::generic_bits, 0}};
constexpr int kMaxBits = 30;  // Draco's quantisation takes at most 30 bits

std::string bytes_text(std::int64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g GB", double(bytes) / 1e9);
  return text;
}

}  // namespace

std::int64_t draco_encode_bytes(const EncodeOptions& options, std::int64_t faces) {
  int bits = 0;
  for (const BitsSetting& s : kBits) bits = std::max(bits, std::clamp(options.*s.field, 0, kMaxBits));
  const std::int64_t tables = kDracoBytesPerSymbol << bits;  // at most 16 x 2^30, no overflow
  const std::int64_t cap = std::numeric_limits<std::int64_t>::max() / 2;
  const std::int64_t per_face = faces > cap / kDracoBytesPerFace ? cap : std::max<std::int64_t>(faces, 0) * kDracoBytesPerFace;
  return tables + per_face;
}

bool writes_draco(Format output, Compression compression) {
  if (output == Format::Drc) return true;
  return (output == Format::Glb || output == Format::Gltf) && compression == Compression::Draco;
}

void check_encode_options(const EncodeOptions& options) {
  for (const BitsSetting& s : kBits) {
    const int bits = options.*s.field;
    if (bits > kMaxBits || bits < s.min || (s.min > 0 && bits == 0))
      throw InvalidParamsError(std::string("output.") + s.name,
                               std::string(s.name) + " must be " + (s.min > 0 ? "in [8, 30]" : "0 (lossless) or in [1, 30]") +
                                   ", not " + std::to_string(bits));
  }
  if (options.compression_level < 0 || options.compression_level > 10)
    throw InvalidParamsError("output.compression_level", "compression_level must be in [0, 10], not " +
                                                              std::to_string(options.compression_level));
}

void check_encode(MeshDocument& doc, const EncodeOptions& options, const Limits& limits) {
  check_encode_options(options);
  std::int64_t faces = 0;
  for (const TriMesh& s : doc.surfaces()) {
    faces += s.num_faces();
    if (s.V.size() > 0 && !s.V.allFinite())
      throw UnsupportedError("the mesh cannot be written: a vertex position is not a finite number");
  }
  const Format output = options.format.value_or(doc.format());
  const Compression compression =
      (output == Format::Glb || output == Format::Gltf) ? resolve_compression(options, doc.compression()) : Compression::None;
  if (!writes_draco(output, compression)) return;
  const std::int64_t need = draco_encode_bytes(options, faces);
  if (need <= limits.max_decoded_bytes) return;
  // Name the setting that drives the tables, and the most bits the limit allows.
  const BitsSetting* top = &kBits[0];
  for (const BitsSetting& s : kBits)
    if (options.*s.field > options.*top->field) top = &s;
  const std::int64_t faces_bytes = need - (kDracoBytesPerSymbol << options.*top->field);
  int allowed = 0;
  while (allowed < kMaxBits && (kDracoBytesPerSymbol << (allowed + 1)) + faces_bytes <= limits.max_decoded_bytes) ++allowed;
  if (allowed < 8)
    throw UnsupportedError("Draco output of " + std::to_string(faces) + " faces would need about " + bytes_text(need) +
                           " of encoder memory, more than the limit of " + std::to_string(limits.max_decoded_bytes) +
                           " bytes (max_decoded_bytes); output without Draco");
  throw UnsupportedError("Draco output with output." + std::string(top->name) + " = " + std::to_string(options.*top->field) +
                         " on " + std::to_string(faces) + " faces would need about " + bytes_text(need) +
                         " of encoder memory (its tables grow as 2^bits), more than the limit of " +
                         std::to_string(limits.max_decoded_bytes) + " bytes (max_decoded_bytes); use at most " +
                         std::to_string(allowed) + " bits, or output without Draco");
}

}  // namespace mdn::io
