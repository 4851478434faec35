// The web page for people (server/web/): GET / is the page, GET /web/{path} its files and the
// parts of three.js it imports, all embedded at build time (server/web/web.cmake), so the
// server needs no file system and the page no network beyond this server. --web off (MDN_WEB)
// turns both routes into 404s for API-only deployments.
#pragma once

#include <string_view>

#include "server/http/transport/http_message.h"

namespace mdn::http {

// Content-Security-Policy of every page response: scripts, styles, fonts and connections from
// this origin only. 'wasm-unsafe-eval' lets Draco's WebAssembly decoder compile (it compiles
// bytes fetched from this origin; no string is ever evaluated), blob: workers are the ones
// DRACOLoader builds from that decoder, and data:/blob: URLs are what three.js makes of a glTF's
// embedded buffers and images: all are made in the page, none reaches another host.
inline constexpr const char* kWebContentSecurityPolicy =
    "default-src 'self'; script-src 'self' 'wasm-unsafe-eval'; worker-src 'self' blob:; "
    "connect-src 'self' data: blob:; img-src 'self' data: blob:; style-src 'self'; object-src 'none'; "
    "base-uri 'none'; form-action 'none'; frame-ancestors 'none'";

// Answers GET of one page file: `name` is "index.html" for GET / and the {path} of GET /web/{path}.
// Sets the body (gzip-encoded, compressed once, when Accept-Encoding allows), its media type, a
// strong ETag per representation (a hash of the bytes), Vary: Accept-Encoding, Cache-Control:
// no-cache (a browser revalidates and gets 304 while the build is the same), the CSP and nosniff;
// answers 304 with no body when If-None-Match names an ETag of the file. Throws HttpError (404)
// for a name that is not embedded.
void serve_web_file(const Request& req, Response& res, std::string_view name);

}  // namespace mdn::http
