#include "server/http/routes/web_routes.h"

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include "server/http/transport/content_coding.h"
#include "server/http/embedded.h"
#include "server/http/problem.h"

namespace mdn::http {
namespace {

struct WebFile {
  WebFile(std::string_view b, const char* type, std::string tag) : bytes(b), media_type(type), etag(std::move(tag)) {}
  std::string_view bytes;
  const char* media_type;
  std::string etag;  // hash of the bytes
  // Compressed once, on the first request that accepts gzip (most servers never serve the page).
  std::string_view gzipped() const {
    std::call_once(gzip_once, [this] { gzip_bytes = gzip(bytes, 9); });  // zlib's best: once per file
    return gzip_bytes;
  }

 private:
  mutable std::once_flag gzip_once;
  mutable std::string gzip_bytes;
};

const char* media_type_of(std::string_view path) {
  static constexpr std::pair<std::string_view, const char*> kTypes[] = {
      {".html", "text/html; charset=utf-8"},   {".css", "text/css; charset=utf-8"},
      {".js", "text/javascript; charset=utf-8"}, {".svg", "image/svg+xml"},
      {".wasm", "application/wasm"},
  };
  for (const auto& [ext, type] : kTypes)
    if (path.size() > ext.size() && path.substr(path.size() - ext.size()) == ext) return type;
  return "text/plain; charset=utf-8";  // three's LICENSE
}

// 64-bit FNV-1a of the bytes, in hex: the ETags' base, changed whenever a build changes the file.
std::string etag_of(std::string_view bytes) {
  std::uint64_t h = 1469598103934665603ull;
  for (unsigned char c : bytes) h = (h ^ c) * 1099511628211ull;
  char buf[24];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

// Every embedded file by its name under /web/ ("index.html", "vendor/three/build/three.module.js").
const std::map<std::string, WebFile, std::less<>>& web_files() {
  static const auto files = [] {
    std::map<std::string, WebFile, std::less<>> out;
    for (auto table : {embedded::web_page_files(), embedded::web_vendor_files()}) {
      for (const embedded::File& f : table) {
        std::string_view name = f.path;
        name.remove_prefix(std::string_view("/web/").size());
        out.try_emplace(std::string(name), f.bytes, media_type_of(name), etag_of(f.bytes));
      }
    }
    return out;
  }();
  return files;
}

// If-None-Match: "*" or a comma-separated list of (possibly weak, W/"...") entity tags; either
// representation of the file (identity or gzip) counts.
bool etag_matches(const std::string& header, const std::string& identity, const std::string& gzip) {
  std::size_t pos = 0;
  while (pos < header.size()) {
    std::size_t end = header.find(',', pos);
    if (end == std::string::npos) end = header.size();
    std::string_view tag(header.data() + pos, end - pos);
    while (!tag.empty() && (tag.front() == ' ' || tag.front() == '\t')) tag.remove_prefix(1);
    while (!tag.empty() && (tag.back() == ' ' || tag.back() == '\t')) tag.remove_suffix(1);
    if (tag.substr(0, 2) == "W/") tag.remove_prefix(2);
    if (tag == "*" || tag == identity || tag == gzip) return true;
    pos = end + 1;
  }
  return false;
}

}  // namespace

void serve_web_file(const Request& req, Response& res, std::string_view name) {
  const auto& files = web_files();
  const auto it = files.find(name);
  if (it == files.end())
    throw HttpError(make_problem(ProblemType::NotFound, "no page file /web/" + std::string(name)));
  const WebFile& file = it->second;
  // Strong ETags, one per representation (RFC 9110 8.8.3: the gzip bytes are another one).
  const std::string identity_tag = "\"" + file.etag + "\"", gzip_tag = "\"" + file.etag + "-gzip\"";
  const bool gzip = accepts_gzip(req.get_header_value("Accept-Encoding"));
  res.set_header("ETag", gzip ? gzip_tag : identity_tag);
  res.set_header("Vary", "Accept-Encoding");
  res.set_header("Cache-Control", "no-cache");
  res.set_header("Content-Security-Policy", kWebContentSecurityPolicy);
  res.set_header("X-Content-Type-Options", "nosniff");
  res.set_header("Referrer-Policy", "no-referrer");
  if (etag_matches(req.get_header_value("If-None-Match"), identity_tag, gzip_tag)) {
    res.status = 304;
    return;
  }
  res.status = 200;
  std::string_view body = file.bytes;
  if (gzip) {
    body = file.gzipped();
    res.set_header("Content-Encoding", "gzip");
  }
  // A content provider of known length: cpp-httplib 0.11.4 would otherwise compress a text/* body
  // itself on every request, with Brotli at quality 11 when the browser accepts it (10 s for
  // three.core.js on a loaded 2-core machine); the bytes here are compressed once.
  res.set_content_provider(body.size(), file.media_type,
                           [body](std::size_t offset, std::size_t length, DataSink& sink) {
                             return sink.write(body.data() + offset, length);
                           });
}

}  // namespace mdn::http
