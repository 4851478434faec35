// Format and compression names, extensions and media types (document.h); detection and the
// decode() dispatcher are in decode.cpp.
#include "core/io/document.h"

#include <algorithm>
#include <array>
#include <cctype>
#include <string>
#include <utility>

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

}  // namespace mdn::io
