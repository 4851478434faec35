// POST /v1/compare: a mesh against a reference, the figures of `meshdenoise --metrics` (MSAE
// where the faces match, E_v always) and each vertex's deviation, computed by the service's
// comparison (service/reference.h over core/metrics), for the web page's reference view.
#pragma once

#include "core/io/document.h"
#include "server/http/config.h"
#include "server/http/metrics.h"
#include "server/http/routes/http_support.h"
#include "server/http/routes/request_body.h"

namespace mdn::http {

// Thread-safe: it keeps no state but its settings.
class CompareRoutes {
 public:
  CompareRoutes(const ServerConfig& config, Metrics& metrics);

  // A multipart form with the files `reference` and `mesh` (any format the service reads; each
  // document as its scene shows it). 200 with the comparison's JSON; 400 for a form without
  // both, 413/415/422 as POST /v1/jobs answers for a file it cannot take.
  void compare(Context& ctx);

 private:
  BodyReader bodies_;
  io::Limits limits_;
};

}  // namespace mdn::http
