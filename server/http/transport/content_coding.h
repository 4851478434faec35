// Content codings (RFC 9110 8.4) this server writes itself: gzip only, and never through
// cpp-httplib's own compression, which in 0.11.4 Brotli-encodes every text/* or JSON body at
// quality 11 on every request (seconds per megabyte on a loaded machine). The page's files are
// gzipped once at the best level (web_routes.cpp); job results, when their format is text,
// at the fastest level per request (job_resource.cpp): 4 MB of OFF in tens of milliseconds,
// about a third of the bytes on the wire.
#pragma once

#include <string>
#include <string_view>

namespace mdn::http {

// gzip (RFC 1952) of the bytes at zlib `level` (1 fastest .. 9 smallest). Throws
// std::runtime_error if zlib fails (it does not for in-memory input).
std::string gzip(std::string_view bytes, int level);

// Accept-Encoding (RFC 9110 12.5.3): a list of codings with optional weights; gzip is accepted
// when it (or "*") is listed with a weight other than 0.
bool accepts_gzip(const std::string& header);

}  // namespace mdn::http
