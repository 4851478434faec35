// Internal to mdn_io: the per-format decoders behind mdn::io::decode() and small text helpers
// shared by the OFF/OBJ/PLY adapters. Not installed, not included outside core/io.
#pragma once

#include <charconv>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>

#include "core/io/document.h"

namespace mdn::io::detail {

std::unique_ptr<MeshDocument> decode_off(std::string_view bytes, const Limits& limits);
std::unique_ptr<MeshDocument> decode_obj(std::string_view bytes, const Limits& limits);
std::unique_ptr<MeshDocument> decode_ply(std::string_view bytes, const Limits& limits);
std::unique_ptr<MeshDocument> decode_drc(std::string_view bytes, const Limits& limits);
// resource_dir: null refuses external URIs; else the folder they are read from (DecodeOptions).
// release: the string `bytes` views, if the caller is done with it (decode_owned): freed once a
// .gltf's data URIs are decoded from it.
std::unique_ptr<MeshDocument> decode_gltf(std::string_view bytes, Format format, const Limits& limits,
                                          const std::string* resource_dir = nullptr, std::string* release = nullptr);
std::unique_ptr<MeshDocument> decode_stl(std::string_view bytes, const Limits& limits);

// STL detection (sniff_format and decode_stl): the binary size identity 84 + 50 n, and ASCII
// text that really reads "solid [name] facet normal" (or an empty "solid ... endsolid").
bool is_binary_stl_size(std::string_view bytes);
bool looks_like_ascii_stl(std::string_view bytes);

// Shortest decimal text that reads back to exactly the same double (std::to_chars), so the
// text outputs are deterministic and lose nothing.
inline void append_number(std::string& out, double value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}
inline void append_number(std::string& out, std::int64_t value) {
  char buffer[24];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}
inline void append_number(std::string& out, float value) {
  char buffer[32];
  const auto result = std::to_chars(buffer, buffer + sizeof buffer, value);
  out.append(buffer, result.ptr);
}

// Splits off the next whitespace-separated token of `line` (advancing it); empty at the end.
inline std::string_view next_token(std::string_view& line) {
  std::size_t begin = 0;
  while (begin < line.size() && (line[begin] == ' ' || line[begin] == '\t' || line[begin] == '\r')) ++begin;
  std::size_t end = begin;
  while (end < line.size() && line[end] != ' ' && line[end] != '\t' && line[end] != '\r') ++end;
  const std::string_view token = line.substr(begin, end - begin);
  line.remove_prefix(end);
  return token;
}

// Parses a whole token as a number; false if it is not one (trailing garbage included).
inline bool parse_number(std::string_view token, double& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size();
}
inline bool parse_integer(std::string_view token, std::int64_t& value) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  const auto result = std::from_chars(token.data(), token.data() + token.size(), value);
  return result.ec == std::errc() && result.ptr == token.data() + token.size();
}

// Reads lines one at a time, tracking the 1-based line number for error messages.
class LineReader {
 public:
  explicit LineReader(std::string_view text) : text_(text) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const std::size_t end = text_.find('\n', pos_);
    const std::size_t stop = end == std::string_view::npos ? text_.size() : end;
    line = text_.substr(pos_, stop - pos_);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    pos_ = end == std::string_view::npos ? text_.size() : end + 1;
    ++number_;
    return true;
  }
  std::int64_t line_number() const { return number_; }
  std::size_t position() const { return pos_; }

 private:
  std::string_view text_;
  std::size_t pos_ = 0;
  std::int64_t number_ = 0;
};

// The text formats' one shape of parse error: "OFF line 12: <message>".
[[noreturn]] inline void fail_at_line(const char* where, const LineReader& reader, const std::string& message) {
  throw FormatError(std::string(where) + " line " + std::to_string(reader.line_number()) + ": " + message);
}

// Cooperative cancellation in the decode and encode loops: poll() asks the observer every
// kCancelStride calls (a few hundred microseconds of text parsing) and throws CancelledError
// when it wants to stop. A null observer costs one branch per call.
inline constexpr std::uint32_t kCancelStride = 4096;
class CancelPoll {
 public:
  explicit CancelPoll(ProgressObserver* observer) : observer_(observer) {}
  void poll() {
    if (observer_ && ++count_ % kCancelStride == 0) check();
  }
  // Asks at once (before and after a step that cannot be interrupted).
  void check() {
    if (observer_ && observer_->cancel_requested()) throw CancelledError();
  }

 private:
  ProgressObserver* observer_;
  std::uint32_t count_ = 0;
};

// Checks a declared element count against a limit before anything is allocated.
void check_count(std::int64_t count, std::int64_t limit, const char* what);

}  // namespace mdn::io::detail
