// The framing limits the gate enforces itself, before cpp-httplib's parser sees a byte (issue
// 49, items 2, 3 and 8; decision 63). cpp-httplib 0.11.4 reads a line into a string that grows
// until its end arrives, so a request line, a header line, a chunk-size line or a chunk
// extension streamed without a line end took one connection to 1.5 GB; it reads chunk sizes
// with strtoul, so "0x1c" and "+1c" were accepted; and a request line that could not be one
// was handed to a thread to wait for the rest. Pure functions over bytes: no sockets, no
// cpp-httplib (tests/fuzz/fuzz_http_framing drives them).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include "server/http/problem.h"

namespace mdn::http::framing {

inline constexpr std::size_t kMaxLineBytes = 8192;       // the request line, each header line (CRLF excluded)
inline constexpr std::size_t kMaxHeadBytes = 65536;      // every header line together, the request line included
inline constexpr std::size_t kMaxChunkLineBytes = 4096;  // a chunk-size line, extensions included

struct Refusal {
  ProblemType type;  // 414 uri-too-long, 431 too-many-headers, 400 bad-request
  std::string detail;
};

// What the gate knows of a request head as it arrives (`buffered`: the connection's unread
// bytes, starting at the request line; blank lines before it, which RFC 9112 2.2 allows, are
// skipped by cpp-httplib and here alike).
struct HeadState {
  bool complete = false;           // the empty line that ends the head has arrived
  std::size_t head_bytes = 0;      // the head's length with its final CRLF CRLF (when complete)
  bool chunked = false;            // Transfer-Encoding: chunked (the only coding accepted)
  std::optional<Refusal> refusal;  // answer this and close: the head breaks a limit or cannot be framed
};

// Reads a head as far as it has arrived. A refusal comes as soon as it is certain (a line past
// its limit before its end arrives, a request line that cannot be one), so nothing waits for
// the rest of a head that will be refused.
HeadState inspect_head(std::string_view buffered);

// The chunked coding (RFC 9112 7.1) of one request body, checked as its bytes go by: each
// chunk size is 1 to 16 hexadecimal digits (no sign, no "0x"), optionally followed by
// whitespace and extensions, its line at most kMaxChunkLineBytes; each chunk's data ends with
// CRLF; the trailer section's lines obey the head's limits. feed() returns false at the first
// byte that breaks the framing (error() says why); after the last chunk and its trailers
// done() is true and nothing more is checked.
class ChunkedFraming {
 public:
  bool feed(std::string_view bytes);
  bool done() const { return state_ == State::Done; }
  const std::string& error() const { return error_; }

 private:
  enum class State { Size, Data, DataCr, DataLf, Trailer, Done, Failed };
  bool fail(std::string why);
  bool end_size_line();

  State state_ = State::Size;
  std::string line_;  // the current size or trailer line, bounded
  std::uint64_t left_ = 0;
  std::size_t trailer_bytes_ = 0;
  std::string error_;
};

}  // namespace mdn::http::framing
