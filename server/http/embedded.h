// Files embedded into the binary at build time (embed_files.cmake): the contract files of
// proto/, so the server serves exactly the document it was built with and never reads the
// source tree, and the web page (server/web/, served by web_routes.cpp).
#pragma once

#include <span>
#include <string_view>

namespace mdn::http::embedded {

std::string_view openapi_yaml();        // proto/openapi.yaml
std::string_view params_schema_json();  // proto/params.schema.json
std::string_view report_schema_json();  // proto/report.schema.json

// One embedded file of a table: its URL path and its bytes.
struct File {
  std::string_view path;
  std::string_view bytes;
};
std::span<const File> web_page_files();    // server/web/*.html, *.css, *.js, *.svg at /web/<name>
std::span<const File> web_vendor_files();  // the parts of three.js the page imports, at /web/vendor/three/...

}  // namespace mdn::http::embedded
