#include "server/http/routes/compare_routes.h"

#include <algorithm>
#include <utility>

#include "core/mesh.h"
#include "service/reference.h"

namespace mdn::http {

CompareRoutes::CompareRoutes(const ServerConfig& config, Metrics& metrics)
    : bodies_(config.max_body_bytes, std::min(config.read_timeout_s, config.body_stall_timeout_s), config.body_timeout_s, metrics),
      limits_(decode_limits(config)) {}

void CompareRoutes::compare(Context& ctx) {
  if (!ctx.req.is_multipart_form_data())
    throw HttpError(make_problem(ProblemType::BadForm, "send a multipart form with the files 'reference' and 'mesh'"));
  auto form = bodies_.read_form(ctx, {"reference", "mesh"});
  for (const char* name : {"reference", "mesh"})
    if (!form.count(name) || form[name].bytes.empty())
      throw HttpError(make_problem(ProblemType::BadForm, std::string("the form has no '") + name + "' file (or it is empty)"));
  // Each document as one mesh in its scene's frame, as `meshdenoise --metrics` measures it.
  auto scene = [&](BodyReader::FormFile& file) {
    const auto document = io::decode(file.bytes, resolve_format(file.content_type, file.bytes, file.filename), limits_);
    TriMesh mesh = service::scene_mesh(document->surfaces(), document->placements());
    validate_mesh(mesh);
    return mesh;
  };
  const TriMesh reference = scene(form["reference"]);
  const TriMesh mesh = scene(form["mesh"]);
  nlohmann::json out = service::comparison_json(service::compare_with_reference(reference, mesh));
  out["reference"] = {{"vertices", reference.num_vertices()}, {"faces", reference.num_faces()}};
  out["mesh"] = {{"vertices", mesh.num_vertices()}, {"faces", mesh.num_faces()}};
  set_json(ctx.res, out);
}

}  // namespace mdn::http
