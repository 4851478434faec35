// glTF 2.0: a .gltf's data-URI buffers decoded straight from the body (decision 82). Before,
// the base64 text was held by the body, by our JSON, by tinygltf's JSON, by the buffer's `uri`
// and a substring of it, then decoded into a string and copied into the buffer: a 250 MiB
// .gltf peaked at 7x its size. Here the JSON parsers see a short placeholder instead of each
// data URI, and every buffer's bytes are decoded once, from the body, into the vector tinygltf's
// buffer then adopts; nothing else holds them.
#include <algorithm>
#include <array>
#include <cstring>
#include <optional>
#include <string>

#include "core/io/detail.h"
#include "core/io/gltf_model.h"

namespace mdn::io::detail::gltf {
namespace {

// The placeholder of lifted literal n; a body that holds the prefix anywhere is not lifted.
constexpr std::string_view kPlaceholder = "data:mdn-lifted;";

// The media types tinygltf 2.7 reads a buffer's data URI under (DecodeDataURI): the same set is
// accepted here, so no asset that decoded before is refused for its type.
constexpr std::array<std::string_view, 7> kBufferHeaders = {
    "data:application/octet-stream;base64,", "data:application/gltf-buffer;base64,", "data:image/jpeg;base64,",
    "data:image/png;base64,",                "data:image/bmp;base64,",               "data:image/gif;base64,",
    "data:text/plain;base64,"};

// Base64's alphabet (RFC 4648, section 4) to 6-bit values; 64 marks every other byte.
constexpr std::array<unsigned char, 256> kSextets = [] {
  std::array<unsigned char, 256> table{};
  table.fill(64);
  constexpr std::string_view alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  for (std::size_t i = 0; i < alphabet.size(); ++i) table[static_cast<unsigned char>(alphabet[i])] = static_cast<unsigned char>(i);
  return table;
}();

// The content of a lifted literal: JSON text whose only escape is "\/" (a solidus, as some
// writers escape it).
struct Content {
  std::string_view raw;
  std::size_t escapes = 0;  // how many "\/"
  std::size_t size() const { return raw.size() - escapes; }
  std::string unescaped() const {
    std::string out;
    out.reserve(size());
    for (std::size_t i = 0; i < raw.size(); ++i)
      if (raw[i] != '\\') out += raw[i];
    return out;
  }
};

// The base64 payload of a content: its characters from the `skip`-th (unescaped) on.
std::string_view payload_of(const Content& content, std::size_t skip) {
  std::size_t i = 0;
  for (std::size_t seen = 0; i < content.raw.size() && seen < skip; ++i)
    if (content.raw[i] != '\\') ++seen;
  return content.raw.substr(i);
}

// The bytes a base64 payload decodes to, once its alphabet and padding are checked ('=' only
// at the end, at most two, to a multiple of 4 characters; none is accepted too, as tinygltf
// did). Nothing is allocated.
std::size_t base64_size(std::string_view payload, const std::string& where) {
  std::size_t chars = 0, pad = 0;
  for (const char c : payload) {
    if (c == '\\') continue;
    if (c == '=') {
      ++pad;
    } else if (pad > 0 || kSextets[static_cast<unsigned char>(c)] == 64) {
      throw FormatError("glTF: " + where + "'s data URI is not valid base64 (character " + std::to_string(chars + 1) +
                        " of its payload)");
    }
    ++chars;
  }
  const std::size_t data = chars - pad;
  if (pad > 2 || data % 4 == 1 || (pad > 0 && chars % 4 != 0))
    throw FormatError("glTF: " + where + "'s data URI is not valid base64 (truncated or wrongly padded: " +
                      std::to_string(chars) + " characters)");
  return data / 4 * 3 + (data % 4 == 0 ? 0 : data % 4 - 1);
}

// A payload base64_size accepted, decoded into `out` (sized to it).
void decode_base64(std::string_view payload, std::vector<unsigned char>& out) {
  std::uint32_t group = 0;
  int held = 0;
  std::size_t w = 0;
  for (const char c : payload) {
    if (c == '\\' || c == '=') continue;
    group = (group << 6) | kSextets[static_cast<unsigned char>(c)];
    if (++held == 4) {
      out[w++] = static_cast<unsigned char>(group >> 16);
      out[w++] = static_cast<unsigned char>(group >> 8);
      out[w++] = static_cast<unsigned char>(group);
      group = 0;
      held = 0;
    }
  }
  if (held >= 2) out[w++] = static_cast<unsigned char>(group >> (6 * held - 8));
  if (held == 3) out[w++] = static_cast<unsigned char>(group >> 2);
}

// Lifted literal n, if `value` is its placeholder.
std::optional<std::size_t> placeholder_index(const Json& value, std::size_t count) {
  if (!value.is_string()) return std::nullopt;
  const auto& text = value.get_ref<const std::string&>();
  if (text.rfind(kPlaceholder, 0) != 0) return std::nullopt;
  const std::size_t n = std::stoul(text.substr(kPlaceholder.size()));
  if (n >= count) throw FormatError("glTF: a data URI placeholder out of range");  // cannot happen: the body held none
  return n;
}

// Every placeholder left in `json` (not a buffer's uri: an image's, an extra's) gets its literal
// back, so the JSON is the input's.
void restore(Json& json, std::string_view body, const std::vector<LiftedLiteral>& literals) {
  if (json.is_structured()) {
    for (auto& item : json) restore(item, body, literals);
  } else if (const auto n = placeholder_index(json, literals.size())) {
    json = Content{body.substr(literals[*n].offset, literals[*n].length), literals[*n].escapes}.unescaped();
  }
}

}  // namespace

LiftedJson lift_data_uris(std::string_view text) {
  LiftedJson out;
  if (text.find(kPlaceholder) != std::string_view::npos) return out;
  std::size_t copied = 0;  // text[0, copied) is in out.text
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '"') continue;
    const std::size_t open = i;
    std::size_t escapes = 0;
    bool liftable = text.compare(open + 1, 5, "data:") == 0;
    for (++i; i < text.size() && text[i] != '"'; ++i) {
      if (text[i] != '\\') continue;
      if (i + 1 < text.size() && text[i + 1] == '/') ++escapes;
      else liftable = false;
      ++i;
    }
    if (i >= text.size()) break;  // unterminated: the JSON parser says so
    if (!liftable) continue;
    std::size_t next = i + 1;  // a key ("data:...": value) keeps its text
    while (next < text.size() && (text[next] == ' ' || text[next] == '\t' || text[next] == '\n' || text[next] == '\r')) ++next;
    if (next < text.size() && text[next] == ':') continue;
    if (out.literals.empty()) out.text.reserve(1024);
    out.text.append(text.substr(copied, open + 1 - copied));
    out.text.append(kPlaceholder);
    out.text.append(std::to_string(out.literals.size()));
    out.literals.push_back({open + 1, i - open - 1, escapes});
    copied = i;  // the closing quote is copied with what follows
  }
  if (out.literals.empty()) return out;
  out.text.append(text.substr(copied));
  return out;
}

std::vector<std::vector<unsigned char>> decode_lifted(Json& json, std::string_view body, const LiftedJson& lifted,
                                                      const Limits& limits, std::int64_t& charged) {
  std::vector<std::vector<unsigned char>> buffers;
  if (lifted.literals.empty()) return buffers;
  std::size_t decoded = 0;
  if (json.contains("buffers")) {  // an array of objects (check_shape)
    Json& list = json["buffers"];
    buffers.resize(list.size());
    for (std::size_t b = 0; b < list.size(); ++b) {
      Json& buffer = list[b];
      const auto found = buffer.find("uri");
      if (found == buffer.end()) continue;
      const auto n = placeholder_index(*found, lifted.literals.size());
      if (!n) continue;
      const std::string where = "buffer " + std::to_string(b);
      const LiftedLiteral& literal = lifted.literals[*n];
      const Content content{body.substr(literal.offset, literal.length), literal.escapes};
      const auto length = buffer.find("byteLength");
      if (length == buffer.end() || !length->is_number_unsigned() || length->get<std::uint64_t>() > (std::uint64_t{1} << 53))
        throw FormatError("glTF: " + where + " has no byteLength (a non-negative integer)");
      const auto declared = static_cast<std::int64_t>(length->get<std::uint64_t>());
      // The media type: what tinygltf reads a buffer under (its header list).
      std::string_view header;
      const std::string start = Content{content.raw.substr(0, std::min<std::size_t>(content.raw.size(), 64)), 0}.unescaped();
      for (const auto candidate : kBufferHeaders)
        if (start.rfind(candidate, 0) == 0) header = candidate;
      if (header.empty()) {
        const std::string type = start.substr(0, start.find(','));
        throw FormatError("glTF: " + where + "'s data URI '" + type.substr(0, 60) +
                          ",...' is not base64 of a buffer's media type (application/octet-stream or application/gltf-buffer)");
      }
      // Sizes are checked before allocating: the payload's against the declared, then the limit.
      const std::string_view payload = payload_of(content, header.size());
      const std::size_t size = base64_size(payload, where);
      if (size == 0) throw FormatError("glTF: " + where + "'s data URI holds no bytes");
      if (static_cast<std::int64_t>(size) != declared)
        throw FormatError("glTF: " + where + " declares a byteLength of " + std::to_string(declared) +
                          " but its data URI holds " + std::to_string(size) + " bytes");
      charged += declared;
      if (charged > limits.max_decoded_bytes)
        throw LimitError("glTF: the buffers' data URIs come to more than " + std::to_string(limits.max_decoded_bytes) +
                         " bytes (max_decoded_bytes)");
      buffers[b].resize(size);
      decode_base64(payload, buffers[b]);
      *found = std::string(header);  // the bytes are in the model's buffer b (load_model)
      ++decoded;
    }
  }
  if (decoded < lifted.literals.size()) restore(json, body, lifted.literals);
  return buffers;
}

}  // namespace mdn::io::detail::gltf
