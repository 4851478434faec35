#include "server/http/routes/request_body.h"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <optional>
#include <utility>

#include "server/http/transport/gate_types.h"
#include "service/params_json.h"

namespace mdn::http {

namespace {

// Media types accepted for mesh bodies; nullopt means "recognise the bytes" (sniffing).
struct InputMediaType {
  std::string_view media_type;
  std::optional<io::Format> format;
};
constexpr InputMediaType kInputMediaTypes[] = {
    {"model/gltf-binary", io::Format::Glb},
    {"model/gltf+json", io::Format::Gltf},
    {"model/x-off", io::Format::Off},
    {"model/obj", io::Format::Obj},
    {"model/x-ply", io::Format::Ply},
    {"model/x-draco", io::Format::Drc},
    {"model/stl", io::Format::Stl},
    {"application/octet-stream", std::nullopt},  // .drc, or any format recognised by content
    {"text/plain", std::nullopt},                // OFF/OBJ/PLY ASCII recognised by content
};

}  // namespace

std::string accepted_media_types() {
  std::string out;
  for (const auto& t : kInputMediaTypes) out += (out.empty() ? "" : ", ") + std::string(t.media_type);
  return out;
}

Problem unsupported_media_type(const std::string& detail) {
  Problem p = make_problem(ProblemType::UnsupportedMediaType, detail);
  p.extensions["accepted"] = accepted_media_types();
  return p;
}

// The container of a mesh body: from its declared media type, else from its bytes.
io::Format resolve_format(const std::string& content_type, std::string_view bytes, const std::string& filename) {
  const std::string type = base_media_type(content_type);
  bool sniff = type.empty();
  for (const auto& t : kInputMediaTypes) {
    if (type == t.media_type) {
      if (t.format) return *t.format;
      sniff = true;
    }
  }
  if (!sniff) {
    // Whatever media type the io adapters emit is accepted too (a result can be sent back).
    for (io::Format f : {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Stl, io::Format::Drc,
                         io::Format::Glb, io::Format::Gltf}) {
      if (type == io::media_type(f)) {
        if (type == "application/octet-stream" || type == "text/plain") break;
        return f;
      }
    }
    throw HttpError(unsupported_media_type("media type '" + type + "' is not a mesh format this service reads"));
  }
  // An explicit text/plain says the body is text (OFF, OBJ, ASCII PLY or STL, glTF JSON): a
  // binary body under it is mislabelled, and refused rather than guessed (issue 32).
  if (type == "text/plain" &&
      std::any_of(bytes.begin(), bytes.begin() + std::ptrdiff_t(std::min<std::size_t>(bytes.size(), 65536)),
                  [](char c) { return static_cast<unsigned char>(c) < 0x09; })) {
    const auto sniffed = io::sniff_format(bytes);
    throw HttpError(unsupported_media_type("the body is binary" +
                                           (sniffed ? " (it looks like " + std::string(io::to_string(*sniffed)) + ")" : std::string()) +
                                           ", not text/plain; declare its media type or send application/octet-stream"));
  }
  if (!filename.empty())
    if (auto f = io::format_from_extension(filename)) return *f;
  if (auto f = io::sniff_format(bytes)) return *f;
  throw HttpError(unsupported_media_type(
      "the body is not recognisable as glTF, GLB, Draco, OFF, OBJ, PLY or STL; declare its media type"));
}

// Reads the body through the ContentReader, counting bytes ourselves: cpp-httplib 0.11.4
// applies set_payload_max_length to Content-Length bodies only, not to chunked uploads.
std::string BodyReader::read_body(Context& ctx, const ContentReader& reader) {
  std::string body;
  check_declared_length(ctx);
  // One allocation of the declared size: growing by doubling left the smaller buffers behind in
  // the allocator's arenas (decision 79).
  if (const auto declared = declared_length(ctx.req)) body.reserve(std::size_t(*declared));
  bool over = false;
  auto last_byte = std::chrono::steady_clock::now();
  const bool ok = reader([&](const char* data, std::size_t n) {
    last_byte = std::chrono::steady_clock::now();
    if (std::int64_t(body.size() + n) > max_body_bytes_) {
      over = true;
      return false;
    }
    body.append(data, n);
    return true;
  });
  metrics_.add_bytes_in(std::int64_t(body.size()));
  if (over) throw_too_large(ctx);
  ctx.body_consumed = ok;
  if (!ok) check_stall(ctx, last_byte);
  if (!ok) throw HttpError(make_problem(ProblemType::BadBody, "the request body could not be read"));
  return body;
}

void BodyReader::check_stall(Context& ctx, std::chrono::steady_clock::time_point last_byte) {
  // The gate's stream says why a read gave up: the body's total deadline, or a gap longer than
  // the read timeout (or, outside the gate, a failure that long after the last byte).
  const BodyReadTimeout why = last_body_read_timeout();
  if (why == BodyReadTimeout::BadFraming) {
    close_after_response(ctx.res);  // what follows cannot be framed: never read it
    throw HttpError(make_problem(ProblemType::BadBody,
                                 "the request body's chunked coding is invalid (RFC 9112 7.1: a chunk size is 1 to 16 "
                                 "hexadecimal digits, its line at most 4096 bytes, each chunk followed by CRLF)"));
  }
  if (why == BodyReadTimeout::TooSlow) {
    close_after_response(ctx.res);
    throw HttpError(make_problem(ProblemType::RequestTimeout, "the request body arrived slower than the server's minimum rate"));
  }
  // A 408 naming the limit that ran out; the rest of the body may still come: never read it.
  auto throw_timeout = [&](const char* what, double limit_s, const char* extension) {
    close_after_response(ctx.res);
    char seconds[32];
    std::snprintf(seconds, sizeof seconds, "%g", limit_s);
    Problem p = make_problem(ProblemType::RequestTimeout, std::string(what) + seconds + " s");
    p.extensions[extension] = limit_s;
    throw HttpError(std::move(p));
  };
  if (why == BodyReadTimeout::BodyDeadline)
    throw_timeout("the request body did not arrive within ", body_timeout_s_, "body_timeout_s");
  const double idle_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - last_byte).count();
  if (why != BodyReadTimeout::Stall && idle_s < 0.9 * stall_timeout_s_) return;
  throw_timeout("the request body sent nothing for ", stall_timeout_s_, "body_stall_timeout_s");
}

void BodyReader::throw_too_large(Context& ctx) {
  close_after_response(ctx.res);  // the rest of the body stays unread
  throw HttpError(make_problem(ProblemType::TooLarge, "the body exceeds the limit of " + std::to_string(max_body_bytes_) + " bytes"));
}

void BodyReader::check_declared_length(Context& ctx) {
  const bool chunked = lower(ctx.req.get_header_value("Transfer-Encoding")).find("chunked") != std::string::npos;
  if (chunked) return;
  if (!ctx.req.has_header("Content-Length")) {
    close_after_response(ctx.res);
    throw HttpError(make_problem(ProblemType::LengthRequired, "send Content-Length or Transfer-Encoding: chunked"));
  }
  const std::string text = ctx.req.get_header_value("Content-Length");
  std::uint64_t n = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec == std::errc::result_out_of_range) throw_too_large(ctx);
  if (ec != std::errc() || ptr != text.data() + text.size() || text.empty()) {
    close_after_response(ctx.res);
    throw HttpError(make_problem(ProblemType::BadRequest, "Content-Length is not a number"));
  }
  if (n > std::uint64_t(max_body_bytes_)) throw_too_large(ctx);
}

std::optional<std::int64_t> BodyReader::declared_length(const Request& req) {
  if (lower(req.get_header_value("Transfer-Encoding")).find("chunked") != std::string::npos) return std::nullopt;
  if (!req.has_header("Content-Length")) return std::nullopt;
  const std::string text = req.get_header_value("Content-Length");
  std::int64_t n = 0;
  auto [ptr, ec] = std::from_chars(text.data(), text.data() + text.size(), n);
  if (ec != std::errc() || ptr != text.data() + text.size() || text.empty() || n < 0) return std::nullopt;
  return n;
}

// Body, container and parameters of a job, from a raw body or a multipart form.
std::map<std::string, BodyReader::FormFile> BodyReader::read_form(Context& ctx, const std::vector<std::string>& names) {
  check_declared_length(ctx);
  std::map<std::string, FormFile> form;
  FormFile* current = nullptr;
  bool over = false, unexpected = false;
  std::string unexpected_name;
  std::int64_t total = 0;
  auto last_byte = std::chrono::steady_clock::now();
  const bool ok = (*ctx.reader)(
      [&](const FormPart& part) {
        last_byte = std::chrono::steady_clock::now();
        if (std::find(names.begin(), names.end(), part.name) == names.end()) return unexpected = true, unexpected_name = part.name, false;
        if (form.count(part.name)) return unexpected = true, unexpected_name = part.name + " (twice)", false;
        current = &form[part.name];
        current->content_type = part.content_type;
        current->filename = part.filename;
        return true;
      },
      [&](const char* data, std::size_t n) {
        last_byte = std::chrono::steady_clock::now();
        total += std::int64_t(n);
        if (total > max_body_bytes_) return over = true, false;
        if (current) current->bytes.append(data, n);
        return true;
      });
  metrics_.add_bytes_in(total);
  if (over) throw_too_large(ctx);
  ctx.body_consumed = ok && !unexpected;
  if (!ok && !unexpected) check_stall(ctx, last_byte);
  if (unexpected) {
    std::string expected;
    for (std::size_t i = 0; i < names.size(); ++i)
      expected += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + ("'" + names[i] + "'");
    throw HttpError(make_problem(ProblemType::BadForm, "unexpected form field '" + unexpected_name + "'; expected " + expected));
  }
  if (!ok) throw HttpError(make_problem(ProblemType::BadForm, "the multipart body could not be parsed"));
  return form;
}

service::JobInput BodyReader::read_job_input(Context& ctx) {
  const Request& req = ctx.req;
  std::optional<std::string> params_text;
  auto set_params = [&](std::string text, const char* where) {
    if (params_text)
      throw HttpError(make_problem(ProblemType::InvalidParams, std::string("parameters given twice (") + where +
                                       "); use one of ?params=, X-Denoise-Params or the params form field"));
    params_text = std::move(text);
  };
  if (req.has_param("params")) set_params(req.get_param_value("params"), "query");
  if (req.has_header("X-Denoise-Params")) set_params(req.get_header_value("X-Denoise-Params"), "header");

  service::JobInput input;
  if (req.is_multipart_form_data()) {
    auto form = read_form(ctx, {"mesh", "params"});
    if (!form.count("mesh")) throw HttpError(make_problem(ProblemType::BadForm, "the form has no 'mesh' field"));
    if (form.count("params")) set_params(std::move(form["params"].bytes), "form field");
    FormFile& mesh = form["mesh"];
    if (mesh.bytes.empty())  // said as it is, not as a file of no format (issue 50, item 7)
      throw HttpError(make_problem(ProblemType::EmptyBody, "the form's 'mesh' file" + (mesh.filename.empty() ? std::string() : " (" + mesh.filename + ")") +
                                                               " is empty: 0 bytes, no mesh in it"));
    input.format = resolve_format(mesh.content_type, mesh.bytes, mesh.filename);
    input.bytes = std::move(mesh.bytes);
  } else {
    std::string content_type = req.get_header_value("Content-Type");
    if (base_media_type(content_type) == "application/x-www-form-urlencoded")
      throw HttpError(unsupported_media_type(
          "application/x-www-form-urlencoded is not a mesh (curl -d sets it: use --data-binary with "
          "-H 'Content-Type: ...')"));
    input.bytes = read_body(ctx, *ctx.reader);
    if (input.bytes.empty()) throw HttpError(make_problem(ProblemType::EmptyBody, "the request body is empty"));
    input.format = resolve_format(content_type, input.bytes);
  }
  input.params = params_text ? service::job_params_from_text(*params_text) : service::JobParams{};
  return input;
}

}  // namespace mdn::http
