#include "core/io/encode_check.h"

#include "core/io/output_settings.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

namespace mdn::io {
namespace {

// The quantisation settings (every "*_bits" row of the one table, decision 69).
std::vector<const OutputSetting*> bits_settings() {
  std::vector<const OutputSetting*> out;
  for (const OutputSetting& s : output_settings())
    if (s.kind == SettingKind::Integer && s.name.ends_with("_bits")) out.push_back(&s);
  return out;
}
constexpr int kMaxBits = 30;  // Draco's quantisation takes at most 30 bits

std::string bytes_text(std::int64_t bytes) {
  char text[32];
  std::snprintf(text, sizeof text, "%.3g GB", double(bytes) / 1e9);
  return text;
}

}  // namespace

std::int64_t draco_encode_bytes(const EncodeOptions& options, std::int64_t faces) {
  int bits = 0;
  for (const OutputSetting* s : bits_settings()) bits = std::max(bits, std::clamp(options.*s->field, 0, kMaxBits));
  const std::int64_t tables = kDracoBytesPerSymbol << bits;  // at most 16 x 2^30, no overflow
  const std::int64_t cap = std::numeric_limits<std::int64_t>::max() / 2;
  const std::int64_t per_face = faces > cap / kDracoBytesPerFace ? cap : std::max<std::int64_t>(faces, 0) * kDracoBytesPerFace;
  return tables + per_face;
}

bool writes_draco(Format output, Compression compression) {
  if (output == Format::Drc) return true;
  return (output == Format::Glb || output == Format::Gltf) && compression == Compression::Draco;
}

void check_encode(MeshDocument& doc, const EncodeOptions& options, const Limits& limits) {
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
  const std::vector<const OutputSetting*> bits = bits_settings();
  const OutputSetting* top = bits.front();
  for (const OutputSetting* s : bits)
    if (options.*s->field > options.*top->field) top = s;
  const std::int64_t faces_bytes = need - (kDracoBytesPerSymbol << std::clamp(options.*top->field, 0, kMaxBits));
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
