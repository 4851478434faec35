#include "server/http/routes/job_resource.h"

#include <algorithm>
#include <memory>
#include <utility>
#include <vector>

#include "server/http/transport/content_coding.h"
#include "service/job_json.h"
#include "service/output_files.h"
#include "service/params_json.h"

namespace mdn::http {

using nlohmann::json;

namespace {

// Results of at least this size in a text format are gzip-encoded for clients that accept it;
// below it the header costs more than it saves.
constexpr std::size_t kGzipMinBytes = 1024;

// Text results shrink about threefold; glb, Draco, binary PLY and STL barely do. PLY keeps the
// input's encoding, so an ascii one is text too.
bool is_text(io::Format format, std::string_view bytes) {
  if (format == io::Format::Ply) return bytes.substr(0, 64).find("\nformat ascii ") != std::string_view::npos;
  return format == io::Format::Off || format == io::Format::Obj || format == io::Format::Gltf;
}

}  // namespace

json reports_json(const JobSnapshot& s) {
  if (s.reports) return *s.reports;
  return service::reports_to_json(s.output->reports);
}

json output_summary(const JobSnapshot& s) { return service::output_to_json(*s.output, s.output_bytes, reports_json(s)); }

std::string server_timing(const JobSnapshot& s) {
  std::vector<std::pair<std::string_view, double>> groups;
  for (const service::TimingField& f : service::kTimingFields) {
    if (f.server_timing.empty()) continue;
    auto it = std::find_if(groups.begin(), groups.end(), [&](const auto& g) { return g.first == f.server_timing; });
    if (it == groups.end()) it = groups.insert(groups.end(), {f.server_timing, 0.0});
    it->second += s.output->timings.*f.member;
  }
  std::string out = "queue;dur=" + format_ms(s.queue_wait_s * 1000);
  for (const auto& [name, ms] : groups) out += ", " + std::string(name) + ";dur=" + format_ms(ms);
  return out + ", total;dur=" + format_ms((s.queue_wait_s + s.run_s) * 1000);
}

void write_result(Context& ctx, const JobSnapshot& s) {
  const service::JobOutput& out = *s.output;
  Response& res = ctx.res;
  // A single byte range of a result is honoured (resumable downloads): offset and length as
  // cpp-httplib computes them (a suffix range counts from the end, an open one runs to it),
  // the last byte clamped to the result's (RFC 9110, 14.1.2).
  const Ranges& ranges = request_ranges();
  std::size_t offset = 0, length = out.bytes.size();
  if (ranges.size() == 1) {
    auto [first, last] = ranges.front();
    const auto size = std::int64_t(out.bytes.size());
    const bool ok = (first >= 0 && first < size && (last < 0 || last >= first)) || (first < 0 && last > 0);
    if (!ok) {
      replace_header(res, "Content-Range", "bytes */" + std::to_string(size));
      throw HttpError(make_problem(ProblemType::RangeNotSatisfiable, "the result has " + std::to_string(size) + " bytes"));
    }
    if (first < 0) {
      first = std::max<std::int64_t>(0, size - last);
      last = size - 1;
    }
    if (last < 0 || last >= size) last = size - 1;
    offset = std::size_t(first);
    length = std::size_t(last - first + 1);
    res.status = 206;
    res.set_header("Content-Range", "bytes " + std::to_string(first) + "-" + std::to_string(last) + "/" + std::to_string(size));
  } else {
    res.status = 200;
  }
  // The body goes out through a content provider of known length, never res.set_content():
  // cpp-httplib 0.11.4 would Brotli-encode a text/plain (OFF) body at quality 11 on every
  // request (11 s for a 4.4 MB OFF). Text formats are gzipped at the fastest level instead, when
  // the client accepts gzip and the whole body is asked for (content_coding.h); binary ones
  // (glb, Draco, binary PLY, STL) would not shrink and go as they are.
  const auto output = s.output;  // keeps the bytes alive while they are written
  std::shared_ptr<const std::string> body(output, &output->bytes);
  if (res.status == 200 && is_text(out.format, *body) && body->size() >= kGzipMinBytes &&
      accepts_gzip(ctx.req.get_header_value("Accept-Encoding"))) {
    body = std::make_shared<const std::string>(gzip(*body, 1));
    res.set_header("Content-Encoding", "gzip");
  }
  res.set_header("Vary", "Accept-Encoding");
  if (res.status == 200) {
    offset = 0;
    length = body->size();  // gzipped or not
  }
  res.set_content_provider(length, out.media_type,
                           [body, offset](std::size_t at, std::size_t n, DataSink& sink) {
                             return sink.write(body->data() + offset + at, n);
                           });
  res.set_header("Content-Disposition", "attachment; filename=\"" + service::output_file_name({}, out.format) + "\"");
  res.set_header("X-Denoise-Params", service::to_json(out.effective).dump());
  res.set_header("X-Denoise-Input-Bytes", std::to_string(s.input_bytes));
  res.set_header("X-Denoise-Output-Bytes", std::to_string(out.bytes.size()));
  res.set_header("X-Denoise-Vertices", std::to_string(out.vertices));
  res.set_header("X-Denoise-Faces", std::to_string(out.faces));
  // The job's JSON always has the reports; the header only when it stays small.
  if (std::string report = reports_json(s).dump(); report.size() <= 8192)
    res.set_header("X-Denoise-Report", report);
  if (!out.notes.empty()) {
    std::string notes;
    for (const auto& n : out.notes) notes += (notes.empty() ? "" : "; ") + n;
    res.set_header("X-Denoise-Notes", header_safe(notes));
  }
  // Server-Timing (W3C): per-stage milliseconds, shown by browsers' developer tools.
  res.set_header("Server-Timing", server_timing(s));
}

json job_json(const JobSnapshot& s, const std::string& request_id) {
  const std::string self = "/v1/jobs/" + s.id;
  json j = {{"id", s.id},
            {"state", to_string(s.state)},
            {"progress", {{"stage", s.stage}, {"fraction", s.fraction}}},
            {"cancel_requested", s.cancel_requested},
            {"created_at", iso8601(s.created_wall)},
            {"timings_s", {{"queue_wait", s.queue_wait_s}, {"run", s.run_s}}},
            {"input_bytes", s.input_bytes},
            {"links", {{"self", self}, {"result", self + "/result"}}}};
  if (s.jobs_ahead) j["progress"]["jobs_ahead"] = *s.jobs_ahead;
  if (s.output) j["result"] = output_summary(s);
  if (s.attempts > 1) j["attempts"] = s.attempts;
  if (s.error) j["error"] = s.error->to_json(self, request_id);
  return j;
}

}  // namespace mdn::http
