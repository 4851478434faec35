// libFuzzer harness for the HTTP request reader and gate (issue 49, item 9): the framing the
// gate checks before cpp-httplib's parser sees a byte (server/http/transport/request_framing.h).
// An input is what one connection sends: pipelined requests, each head inspected as the gate
// does and, when it is whole, its body skipped by Content-Length or checked by ChunkedFraming,
// in pieces whose sizes the input's first byte picks (a head or a chunk line split anywhere).
// What must hold: no crash, sanitizer report or leak; a head is refused or complete only once,
// and the same whether it arrived whole or in pieces; a refusal comes before the limits are
// exceeded by more than one read (the gate reads at most kMaxHeadBytes); a complete head is
// within the limits; the chunked framing never accepts a line past its limit.
#include <cstdint>
#include <cstdio>
#include <algorithm>
#include <cstdlib>
#include <string>
#include <string_view>

#include "server/http/transport/request_framing.h"

namespace {

using namespace mdn::http::framing;

[[noreturn]] void finding(const char* what) {
  std::fprintf(stderr, "FINDING: %s\n", what);
  std::abort();
}

// Content-Length of a complete head, or 0 (the gate leaves the rest to cpp-httplib).
std::size_t content_length(std::string_view head) {
  std::size_t at = 0;
  for (;;) {
    const std::size_t eol = head.find('\n', at);
    if (eol == std::string_view::npos) return 0;
    std::string_view line = head.substr(at, eol - at);
    at = eol + 1;
    if (line.size() > 15 && (line.substr(0, 15) == "Content-Length:" || line.substr(0, 15) == "content-length:")) {
      std::size_t n = 0;
      for (char c : line.substr(15))
        if (c >= '0' && c <= '9') n = std::min<std::size_t>(n * 10 + std::size_t(c - '0'), 1 << 20);
      return n;
    }
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  const std::size_t piece = 1 + data[0] % 64;
  std::string_view rest(reinterpret_cast<const char*>(data) + 1, size - 1);
  for (int requests = 0; !rest.empty() && requests < 16; ++requests) {
    // The head as the gate sees it, arriving piece by piece.
    HeadState seen;
    std::size_t arrived = 0;
    while (arrived < rest.size()) {
      arrived = std::min(rest.size(), arrived + piece);
      const std::string_view buffered = rest.substr(0, std::min(arrived, kMaxHeadBytes + 1));
      seen = inspect_head(buffered);
      if (seen.refusal || seen.complete) break;
      if (buffered.size() > kMaxHeadBytes) finding("a head past kMaxHeadBytes was neither refused nor complete");
    }
    const HeadState whole = inspect_head(rest.substr(0, std::min(rest.size(), kMaxHeadBytes + 1)));
    if (seen.complete != whole.complete || bool(seen.refusal) != bool(whole.refusal))
      finding("a head read in pieces was judged unlike the same head whole");
    if (seen.complete && !seen.refusal) {
      if (seen.head_bytes == 0 || seen.head_bytes > kMaxHeadBytes + 1 || seen.head_bytes > rest.size())
        finding("a complete head has an impossible length");
      if (seen.head_bytes != whole.head_bytes) finding("a head's length depends on how it arrived");
    }
    if (!seen.complete || seen.refusal) return 0;
    const std::size_t body = content_length(rest.substr(0, seen.head_bytes));
    rest.remove_prefix(seen.head_bytes);
    if (!seen.chunked) {
      rest.remove_prefix(std::min(rest.size(), body));
      continue;
    }
    ChunkedFraming chunks;
    std::size_t used = 0;
    bool ok = true;
    while (ok && !chunks.done() && used < rest.size()) {
      const std::size_t n = std::min(piece, rest.size() - used);
      ok = chunks.feed(rest.substr(used, n));
      used += n;
    }
    if (!ok && chunks.error().empty()) finding("a framing failure without a reason");
    return 0;  // where a chunked body ends inside a piece is cpp-httplib's to find
  }
  return 0;
}
