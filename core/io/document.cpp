// Format names, detection and the decode() dispatcher.
#include "core/io/document.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <string>
#include <utility>

#include "core/io/detail.h"

namespace mdn::io {

namespace {

struct FormatInfo {
  Format format;
  std::string_view name;
  std::string_view media_type;
};

// One table for names, extensions and media types. OFF and PLY have no registered media
// type; PLY may be binary, hence octet-stream. model/obj and model/stl are registered with IANA.
constexpr std::array<FormatInfo, 7> kFormats{{
    {Format::Off, "off", "text/plain"},
    {Format::Obj, "obj", "model/obj"},
    {Format::Ply, "ply", "application/octet-stream"},
    {Format::Drc, "drc", "application/octet-stream"},
    {Format::Glb, "glb", "model/gltf-binary"},
    {Format::Gltf, "gltf", "model/gltf+json"},
    {Format::Stl, "stl", "model/stl"},
}};

std::string lower(std::string_view text) {
  std::string out(text);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return out;
}

bool starts_with_keyword(std::string_view text, std::string_view keyword) {
  if (text.substr(0, keyword.size()) != keyword) return false;
  if (text.size() == keyword.size()) return true;
  const char next = text[keyword.size()];
  return next == ' ' || next == '\t' || next == '\r' || next == '\n' || std::isdigit(static_cast<unsigned char>(next));
}

}  // namespace

std::string_view to_string(Format format) {
  for (const auto& info : kFormats)
    if (info.format == format) return info.name;
  return "unknown";
}

std::optional<Format> format_from_string(std::string_view name) {
  const std::string key = lower(name);
  for (const auto& info : kFormats)
    if (info.name == key) return info.format;
  return std::nullopt;
}

std::optional<Format> format_from_extension(std::string_view path) {
  const std::size_t dot = path.rfind('.');
  if (dot == std::string_view::npos) return std::nullopt;
  const std::string_view ext = path.substr(dot + 1);
  if (ext.find('/') != std::string_view::npos || ext.find('\\') != std::string_view::npos) return std::nullopt;
  const std::string key = lower(ext);
  for (const auto& info : kFormats)
    if (info.name == key) return info.format;
  return std::nullopt;
}

std::optional<Format> sniff_format(std::string_view bytes) {
  if (bytes.substr(0, 4) == "glTF") return Format::Glb;
  if (bytes.substr(0, 5) == "DRACO") return Format::Drc;
  if (bytes.substr(0, 4) == "ply\n" || bytes.substr(0, 5) == "ply\r\n") return Format::Ply;
  // Binary STL has no magic (its header is free text, often "solid ..."): its size identity.
  if (detail::is_binary_stl_size(bytes) || detail::looks_like_ascii_stl(bytes)) return Format::Stl;
  // Text formats: look at the first line that is neither blank nor a comment.
  detail::LineReader reader(bytes.substr(0, 1 << 16));
  std::string_view line;
  while (reader.next(line)) {
    std::string_view rest = line;
    const std::string_view token = detail::next_token(rest);
    if (token.empty() || token.front() == '#') continue;
    if (token.front() == '{') return Format::Gltf;
    // OFF headers: [ST][C][N][4][n]OFF, optionally followed by the counts on the same line.
    const std::size_t off = token.find("OFF");
    if (off != std::string_view::npos && token.find_first_not_of("STCN4n") >= off) return Format::Off;
    static constexpr std::array<std::string_view, 11> kObjKeywords{
        "v", "vt", "vn", "vp", "f", "o", "g", "s", "mtllib", "usemtl", "l"};
    for (const auto keyword : kObjKeywords)
      if (starts_with_keyword(line.substr(line.find_first_not_of(" \t")), keyword)) return Format::Obj;
    return std::nullopt;
  }
  return std::nullopt;
}

std::string_view media_type(Format format) {
  for (const auto& info : kFormats)
    if (info.format == format) return info.media_type;
  return "application/octet-stream";
}

namespace {
constexpr std::array<std::pair<Compression, std::string_view>, 4> kCompressions{{
    {Compression::AsInput, "as_input"},
    {Compression::None, "none"},
    {Compression::Draco, "draco"},
    {Compression::Meshopt, "meshopt"},
}};
}  // namespace

std::string_view to_string(Compression compression) {
  for (const auto& [value, name] : kCompressions)
    if (value == compression) return name;
  return "unknown";
}

std::optional<Compression> compression_from_string(std::string_view name) {
  const std::string key = lower(name);
  for (const auto& [value, known] : kCompressions)
    if (known == key) return value;
  return std::nullopt;
}

Compression resolve_compression(const EncodeOptions& options, Compression input) {
  if (options.compression != Compression::AsInput) return options.compression;
  return input == Compression::AsInput ? Compression::None : input;
}

std::unique_ptr<MeshDocument> decode(std::string_view bytes, Format format, const DecodeOptions& options) {
  if (format == Format::Glb || format == Format::Gltf)
    return detail::decode_gltf(bytes, format, options.limits, options.resource_dir ? &*options.resource_dir : nullptr);
  return decode(bytes, format, options.limits);
}

std::unique_ptr<MeshDocument> decode(std::string_view bytes, Format format, const Limits& limits) {
  switch (format) {
    case Format::Off: return detail::decode_off(bytes, limits);
    case Format::Obj: return detail::decode_obj(bytes, limits);
    case Format::Ply: return detail::decode_ply(bytes, limits);
    case Format::Drc: return detail::decode_drc(bytes, limits);
    case Format::Stl: return detail::decode_stl(bytes, limits);
    case Format::Glb:
    case Format::Gltf: return detail::decode_gltf(bytes, format, limits);
  }
  throw UnsupportedError("unknown input format");
}

namespace detail {

void check_count(std::int64_t count, std::int64_t limit, const char* what) {
  if (count < 0) throw FormatError(std::string("negative ") + what + " count");
  if (count > limit)
    throw LimitError(std::string("the input declares ") + std::to_string(count) + " " + what + ", more than the limit of " +
                     std::to_string(limit));
}

}  // namespace detail
}  // namespace mdn::io
