#include "server/http/transport/request_framing.h"

#include <algorithm>
#include <cctype>

namespace mdn::http::framing {
namespace {

bool is_token_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) ||
         std::string_view("!#$%&'*+-.^_`|~").find(c) != std::string_view::npos;
}

std::string lower(std::string_view s) {
  std::string out(s);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

std::string_view without_cr(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  return line;
}

Refusal refuse(ProblemType type, std::string detail) { return Refusal{type, std::move(detail)}; }

// "METHOD SP request-target SP HTTP/x.y": false for anything else.
bool valid_request_line(std::string_view line) {
  const std::size_t sp1 = line.find(' ');
  const std::size_t sp2 = line.rfind(' ');
  if (sp1 == std::string_view::npos || sp1 == 0 || sp2 == sp1) return false;
  for (char c : line.substr(0, sp1))
    if (!is_token_char(c)) return false;
  const std::string_view target = line.substr(sp1 + 1, sp2 - sp1 - 1);
  if (target.empty() || target.find(' ') != std::string_view::npos) return false;
  const std::string_view version = line.substr(sp2 + 1);
  return version.size() == 8 && version.substr(0, 5) == "HTTP/" &&
         std::isdigit(static_cast<unsigned char>(version[5])) && version[6] == '.' &&
         std::isdigit(static_cast<unsigned char>(version[7]));
}

// A request line, as far as it has arrived, that cannot become a valid one.
bool impossible_request_line_prefix(std::string_view partial) {
  const std::size_t sp = partial.find(' ');
  for (char c : partial.substr(0, std::min(sp, partial.size())))
    if (!is_token_char(c)) return true;
  return sp == 0;
}

}  // namespace

HeadState inspect_head(std::string_view buffered) {
  HeadState state;
  std::size_t pos = 0;
  // RFC 9112 2.2: empty lines before the request line are ignored (cpp-httplib skips them too);
  // they count towards the head's size.
  while (pos < buffered.size() && (buffered[pos] == '\r' || buffered[pos] == '\n')) ++pos;
  bool first = true;
  std::optional<std::string> transfer_encoding;
  for (;;) {
    if (pos > kMaxHeadBytes) {
      state.refusal = refuse(ProblemType::TooManyHeaders,
                             "the request head is longer than " + std::to_string(kMaxHeadBytes) + " bytes");
      return state;
    }
    const std::size_t eol = buffered.find('\n', pos);
    const std::string_view partial =
        buffered.substr(pos, eol == std::string_view::npos ? std::string_view::npos : eol - pos);
    const std::size_t length = without_cr(partial).size();
    if (length > kMaxLineBytes) {
      state.refusal = first ? refuse(ProblemType::UriTooLong,
                                     "the request line is longer than " + std::to_string(kMaxLineBytes) + " bytes")
                            : refuse(ProblemType::TooManyHeaders,
                                     "a header line is longer than " + std::to_string(kMaxLineBytes) + " bytes");
      return state;
    }
    if (pos + partial.size() > kMaxHeadBytes) {
      state.refusal = refuse(ProblemType::TooManyHeaders,
                             "the request head is longer than " + std::to_string(kMaxHeadBytes) + " bytes");
      return state;
    }
    if (eol == std::string_view::npos) {
      if (first && impossible_request_line_prefix(partial))
        state.refusal = refuse(ProblemType::BadRequest, "the request line is not METHOD SP target SP HTTP-version");
      return state;  // the rest of the line has not arrived
    }
    const std::string_view line = without_cr(partial);
    pos = eol + 1;
    if (first) {
      first = false;
      if (!valid_request_line(line)) {
        state.refusal = refuse(ProblemType::BadRequest, "the request line is not METHOD SP target SP HTTP-version");
        return state;
      }
      continue;
    }
    // cpp-httplib 0.11.4 (built without CPPHTTPLIB_ALLOW_LF_AS_LINE_TERMINATOR) skips a header
    // line that ends in a bare LF, an empty one included: so does the gate, so that both agree
    // on where the head ends and which headers it holds.
    if (partial.empty() || partial.back() != '\r') continue;
    if (line.empty()) break;  // the end of the head
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos || colon == 0) {
      // A field line without a name, obs-fold (a line starting with a blank) among them: RFC
      // 9112 5.2 lets a server refuse it (400), and it never means what cpp-httplib would make of it.
      state.refusal = refuse(ProblemType::BadRequest, "a header line is not NAME: value");
      return state;
    }
    if (lower(line.substr(0, colon)) == "transfer-encoding") {
      const std::string value = lower(trim(line.substr(colon + 1)));
      transfer_encoding = transfer_encoding ? *transfer_encoding + ", " + value : value;
    }
  }
  state.complete = true;
  state.head_bytes = pos;
  if (transfer_encoding) {
    // RFC 9112 6.1, 6.3: chunked is the only coding the server decodes; a list naming any other
    // (gzip, chunked) or not ending in chunked cannot be framed: 400 and close, at once.
    if (*transfer_encoding != "chunked") {
      state.refusal = refuse(ProblemType::BadRequest, "Transfer-Encoding \"" + *transfer_encoding +
                                                          "\" is not supported: send the body as it is, with "
                                                          "Content-Length or Transfer-Encoding: chunked");
      return state;
    }
    state.chunked = true;
  }
  return state;
}

bool ChunkedFraming::fail(std::string why) {
  state_ = State::Failed;
  error_ = std::move(why);
  return false;
}

bool ChunkedFraming::end_size_line() {
  const std::string_view line = without_cr(line_);
  std::size_t digits = 0;
  std::uint64_t size = 0;
  while (digits < line.size() && std::isxdigit(static_cast<unsigned char>(line[digits]))) {
    if (digits == 16) return fail("a chunk size has more than 16 hexadecimal digits");
    const char c = static_cast<char>(std::tolower(static_cast<unsigned char>(line[digits])));
    size = size * 16 + std::uint64_t(c <= '9' ? c - '0' : c - 'a' + 10);
    ++digits;
  }
  if (digits == 0) return fail("a chunk size is not a hexadecimal number");
  const std::string_view rest = line.substr(digits);
  // RFC 9112 7.1.1: chunk-ext = *( BWS ";" BWS name [ BWS "=" BWS value ] )
  const std::string_view after = trim(rest);
  if (!after.empty() && after.front() != ';')
    return fail("a chunk size is followed by something other than an extension");
  line_.clear();
  if (size == 0) {
    state_ = State::Trailer;
  } else {
    left_ = size;
    state_ = State::Data;
  }
  return true;
}

bool ChunkedFraming::feed(std::string_view bytes) {
  std::size_t i = 0;
  while (i < bytes.size()) {
    switch (state_) {
      case State::Done:
      case State::Failed:
        return state_ == State::Done;
      case State::Size:
      case State::Trailer: {
        const std::size_t eol = bytes.find('\n', i);
        const std::size_t take = (eol == std::string_view::npos ? bytes.size() : eol) - i;
        const std::size_t limit = state_ == State::Size ? kMaxChunkLineBytes : kMaxLineBytes;
        if (line_.size() + take > limit + 1)  // + 1: the CR
          return fail(state_ == State::Size
                          ? "a chunk-size line is longer than " + std::to_string(kMaxChunkLineBytes) + " bytes"
                          : "a trailer line is longer than " + std::to_string(kMaxLineBytes) + " bytes");
        line_.append(bytes.substr(i, take));
        i += take;
        if (eol == std::string_view::npos) break;
        ++i;  // the LF
        if (state_ == State::Size) {
          if (!end_size_line()) return false;
        } else {
          trailer_bytes_ += line_.size() + 1;
          if (trailer_bytes_ > kMaxHeadBytes)
            return fail("the trailer section is longer than " + std::to_string(kMaxHeadBytes) + " bytes");
          const bool last = without_cr(line_).empty();
          line_.clear();
          if (last) state_ = State::Done;
        }
        break;
      }
      case State::Data: {
        const std::size_t take = std::size_t(std::min<std::uint64_t>(left_, bytes.size() - i));
        left_ -= take;
        i += take;
        if (left_ == 0) state_ = State::DataCr;
        break;
      }
      case State::DataCr:
        if (bytes[i] == '\n') {  // cpp-httplib accepts a bare LF after the data, as it does for lines
          ++i;
          state_ = State::Size;
          break;
        }
        if (bytes[i] != '\r') return fail("a chunk's data is not followed by CRLF");
        ++i;
        state_ = State::DataLf;
        break;
      case State::DataLf:
        if (bytes[i] != '\n') return fail("a chunk's data is not followed by CRLF");
        ++i;
        state_ = State::Size;
        break;
    }
  }
  return state_ != State::Failed;
}

}  // namespace mdn::http::framing
