// The contract files of proto/, embedded into the binary at build time (embed_files.cmake),
// so the server serves exactly the document it was built with and never reads the source tree.
#pragma once

#include <string_view>

namespace mdn::http::embedded {

std::string_view openapi_yaml();        // proto/openapi.yaml
std::string_view params_schema_json();  // proto/params.schema.json

}  // namespace mdn::http::embedded
