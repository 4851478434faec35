#include "core/io/output_settings.h"

#include <string>

namespace mdn::io {
namespace {

// The names of enumeration values (Format, Compression), as the JSON spells them.
template <class Enum>
std::vector<std::string> names(std::initializer_list<Enum> values) {
  std::vector<std::string> out;
  for (const Enum v : values) out.emplace_back(to_string(v));
  return out;
}

// Decision 69: the ranges. Draco quantises with 1 to 30 bits; positions below 8 bits wreck any
// mesh worth denoising. Normals are recomputed from the denoised surface, so storing them
// losslessly buys nothing: [1, 30]. UVs, colours and generic attributes take 0 = as they came.
// meshopt (decision 70) reads the same settings: KHR_mesh_quantization holds at most 16 bits,
// so more than 16 keeps float32.
const std::vector<OutputSetting>& table() {
  static const std::vector<OutputSetting> settings = {
      {"format", SettingKind::Choice, nullptr, 0, 0,
       names({Format::Off, Format::Obj, Format::Ply, Format::Stl, Format::Drc, Format::Glb, Format::Gltf}), true, false,
       "Output container; null keeps the input's"},
      {"compression", SettingKind::Choice, nullptr, 0, 0,
       names({Compression::AsInput, Compression::None, Compression::Draco, Compression::Meshopt}), false, false,
       "glTF output compression: as_input (the default) writes what the input used (KHR_draco_mesh_compression in gives "
       "draco, EXT_meshopt_compression in gives meshopt, any other input none), none writes plain accessors, draco "
       "KHR_draco_mesh_compression, meshopt EXT_meshopt_compression with KHR_mesh_quantization. Other containers ignore "
       "it (DRC is always Draco). The result says what was written (compression)"},
      {"draco", SettingKind::Flag, nullptr, 0, 0, {}, false, true,
       "The older switch, still accepted: true is compression \"draco\", false is \"none\"; given with compression, the "
       "two must agree. Not echoed (params.output.compression is)"},
      {"position_bits", SettingKind::Integer, &EncodeOptions::position_bits, 8, 30, {}, false, false,
       "Quantisation bits of positions. Draco: its grid. meshopt: up to 16 bits, 16-bit integers on the mesh's box "
       "(KHR_mesh_quantization; a node carries the scale), more keeps float32. A quantized input keeps its own types"},
      {"normal_bits", SettingKind::Integer, &EncodeOptions::normal_bits, 1, 30, {}, false, false,
       "Quantisation bits of the recomputed normals. Draco: its octahedral grid. meshopt: the octahedral filter in "
       "8-bit components up to 8 bits, 16-bit up to 16, more keeps float32. A quantized input keeps its own types"},
      {"texcoord_bits", SettingKind::Integer, &EncodeOptions::texcoord_bits, 0, 30, {}, false, false,
       "Quantisation bits of texture coordinates; 0 = lossless (default: UVs come back bit for bit). meshopt: 1 to 16 "
       "store float UVs within [0, 1] as normalized 16-bit integers on a grid of that many bits"},
      {"color_bits", SettingKind::Integer, &EncodeOptions::color_bits, 0, 30, {}, false, false,
       "Draco quantisation bits of colours; 0 = lossless (default). meshopt stores colours as they came"},
      {"generic_bits", SettingKind::Integer, &EncodeOptions::generic_bits, 0, 30, {}, false, false,
       "Draco quantisation bits of other attributes (joints, weights, custom); 0 = lossless (default). meshopt stores "
       "them as they came"},
      {"compression_level", SettingKind::Integer, &EncodeOptions::compression_level, 0, 10, {}, false, false,
       "Draco speed/size trade-off (10 = smallest); meshopt has no level"},
  };
  return settings;
}

}  // namespace

std::span<const OutputSetting> output_settings() { return table(); }

const OutputSetting* find_output_setting(std::string_view name) {
  for (const OutputSetting& s : table())
    if (s.name == name) return &s;
  return nullptr;
}

EncodeOptions request_defaults() {
  EncodeOptions o;
  o.compression = Compression::AsInput;
  return o;
}

int OutputSetting::default_integer() const { return field ? request_defaults().*field : 0; }

std::string OutputSetting::default_choice() const {
  const EncodeOptions d = request_defaults();
  if (name == "format") return d.format ? std::string(to_string(*d.format)) : std::string();
  if (name == "compression") return std::string(to_string(d.compression));
  return {};
}

std::string OutputSetting::range_text() const {
  switch (kind) {
    case SettingKind::Integer: {
      std::string text = "[";  // appended piecewise: GCC 12's -Wrestrict misfires on "[" + std::string&&
      text += std::to_string(min);
      text += ", ";
      text += std::to_string(max);
      text += "]";
      return text;
    }
    case SettingKind::Flag: return "true|false";
    case SettingKind::Choice: break;
  }
  std::string text;
  for (const std::string& c : choices) {
    text += text.empty() ? "\"" : "|\"";
    text += c;
    text += "\"";
  }
  if (nullable) text += "|null";
  return text;
}

void check_output_options(const EncodeOptions& options) {
  for (const OutputSetting& s : table()) {
    if (s.kind != SettingKind::Integer || s.accepts(options.*s.field)) continue;
    const std::string path = "output." + std::string(s.name);
    throw InvalidParamsError(path, path + " must be an integer in " + s.range_text() + ", got " +
                                       std::to_string(options.*s.field));
  }
}

}  // namespace mdn::io
