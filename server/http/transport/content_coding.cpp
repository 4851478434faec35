#include "server/http/transport/content_coding.h"

#include <zlib.h>

#include <cctype>
#include <cstdlib>
#include <stdexcept>

namespace mdn::http {

std::string gzip(std::string_view bytes, int level) {
  z_stream z{};
  if (deflateInit2(&z, level, Z_DEFLATED, 15 + 16, 9, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib: deflateInit2 failed");
  std::string out(deflateBound(&z, uLong(bytes.size())), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  z.avail_in = uInt(bytes.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = uInt(out.size());
  const int rc = deflate(&z, Z_FINISH);
  out.resize(z.total_out);
  deflateEnd(&z);
  if (rc != Z_STREAM_END) throw std::runtime_error("zlib: deflate did not finish");
  return out;
}

bool accepts_gzip(const std::string& header) {
  std::size_t pos = 0;
  while (pos < header.size()) {
    std::size_t end = header.find(',', pos);
    if (end == std::string::npos) end = header.size();
    std::string entry;
    for (char c : header.substr(pos, end - pos))
      if (c != ' ' && c != '\t') entry += char(std::tolower(static_cast<unsigned char>(c)));
    pos = end + 1;
    const std::size_t semi = entry.find(';');
    const std::string coding = entry.substr(0, semi);
    if (coding != "gzip" && coding != "*") continue;
    const std::size_t q = entry.find("q=", semi == std::string::npos ? entry.size() : semi);
    if (q == std::string::npos || std::strtod(entry.c_str() + q + 2, nullptr) > 0) return true;
  }
  return false;
}

}  // namespace mdn::http
