// Format detection (sniff_format) and the decode() dispatcher of document.h, over the
// per-format decoders (detail.h). Apart from document.cpp so that detail.h, which includes
// document.h, is never included back by document's own files.
#include <array>
#include <cctype>
#include <memory>
#include <string>
#include <string_view>

#include "core/io/detail.h"
#include "core/io/document.h"

namespace mdn::io {

namespace {

bool starts_with_keyword(std::string_view text, std::string_view keyword) {
  if (text.substr(0, keyword.size()) != keyword) return false;
  if (text.size() == keyword.size()) return true;
  const char next = text[keyword.size()];
  return next == ' ' || next == '\t' || next == '\r' || next == '\n' || std::isdigit(static_cast<unsigned char>(next));
}

}  // namespace

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

std::unique_ptr<MeshDocument> decode(std::string_view bytes, Format format, const DecodeOptions& options) {
  if (format == Format::Glb || format == Format::Gltf)
    return detail::decode_gltf(bytes, format, options.limits, options.resource_dir ? &*options.resource_dir : nullptr);
  return decode(bytes, format, options.limits);
}

std::unique_ptr<MeshDocument> decode_owned(std::string&& bytes, Format format, const DecodeOptions& options) {
  std::string owned = std::move(bytes);
  bytes.clear();
  if (format == Format::Gltf)  // its data URIs are decoded first, then the body is freed (decision 82)
    return detail::decode_gltf(owned, format, options.limits, options.resource_dir ? &*options.resource_dir : nullptr, &owned);
  return decode(owned, format, options);
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
