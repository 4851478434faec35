// meshdenoise-server client in C++ with cpp-httplib and nlohmann_json (Debian's
// libcpp-httplib-dev and nlohmann-json3-dev; build with
//   g++ -std=c++20 denoise_client.cpp $(pkg-config --cflags --libs cpp-httplib)).
// Usage: denoise_client <host> <port> <input> <output> [params-json]
//   output: .off .obj .ply .stl .drc .glb or .gltf (sets the parameters' output.format)
// Sends the mesh as an asynchronous job, waits for it (long polls), downloads the result.
// Exit status: 0 done; 2 bad arguments (an input that cannot be read, an output extension that
// names no format, parameters that are not a JSON object), nothing sent; 1 the server could not
// be reached or refused the mesh (its problem+json title and detail are printed).
#include <httplib.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>
#include <string>

namespace {

using nlohmann::json;
namespace fs = std::filesystem;

const std::map<std::string, std::string> kMediaTypes = {
    {".glb", "model/gltf-binary"}, {".gltf", "model/gltf+json"}, {".drc", "model/x-draco"}, {".off", "model/x-off"},
    {".obj", "model/obj"},         {".ply", "model/x-ply"},      {".stl", "model/stl"}};

// A failure: its exit status and the one line printed.
struct Failure {
  int exit_code;
  std::string message;
};

std::string extension(const std::string& path) {
  std::string ext = fs::path(path).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext;
}

// 4xx/5xx: the body is an RFC 9457 problem+json document.
Failure problem(const httplib::Response& res) {
  const json p = json::parse(res.body, nullptr, /*allow_exceptions=*/false);
  if (!p.is_object()) return {1, "the server answered " + std::to_string(res.status) + ": " + res.body.substr(0, 200)};
  return {1, "the server answered " + std::to_string(res.status) + " " + p.value("title", std::string()) + ": " +
                 p.value("detail", std::string())};
}

int run(int argc, char** argv) {
  if (argc < 5 || argc > 6) throw Failure{2, "usage: denoise_client <host> <port> <input> <output> [params-json]"};
  const std::string host = argv[1], input = argv[3], output = argv[4];
  int port = 0;
  try {
    port = std::stoi(argv[2]);
  } catch (const std::exception&) {
  }
  if (port < 1 || port > 65535) throw Failure{2, std::string("the port must be a number in [1, 65535], got ") + argv[2]};

  // Check everything before sending anything.
  std::ifstream in(input, std::ios::binary);
  if (!in || fs::is_directory(input)) throw Failure{2, "cannot read " + input + ": no such file"};
  std::ostringstream bytes;
  bytes << in.rdbuf();
  const std::string out_ext = extension(output);
  if (!kMediaTypes.count(out_ext))
    throw Failure{2, "cannot write " + output + ": its extension names no format (use .off, .obj, .ply, .stl, .drc, .glb or .gltf)"};
  const fs::path folder = fs::path(output).parent_path();
  if (!folder.empty() && !fs::is_directory(folder))
    throw Failure{2, "cannot write " + output + ": the folder " + folder.string() + " does not exist"};
  json params = json::parse(argc > 5 ? argv[5] : "{}", nullptr, /*allow_exceptions=*/false);
  if (!params.is_object() || (params.contains("output") && !params["output"].is_object()))
    throw Failure{2, "the parameters must be a JSON object (with \"output\" an object)"};
  const std::string format = out_ext.substr(1);
  if (params.contains("output") && params["output"].contains("format") && params["output"]["format"] != format)
    throw Failure{2, "the parameters ask for output.format " + params["output"]["format"].dump() + " but " + output +
                         " is " + out_ext};
  params["output"]["format"] = format;
  const auto type = kMediaTypes.find(extension(input));
  const std::string media_type = type == kMediaTypes.end() ? "application/octet-stream" : type->second;  // else sniffed

  const std::string base = "http://" + host + ":" + std::to_string(port);
  httplib::Client client(host, port);
  client.set_read_timeout(600, 0);
  httplib::Headers headers = {{"X-Denoise-Params", params.dump()}};
  if (const char* token = std::getenv("MDN_TOKEN")) headers.emplace("Authorization", std::string("Bearer ") + token);
  // Every request: one line and exit 1 when the server cannot be reached or answers a problem.
  auto checked = [&](httplib::Result res) -> httplib::Response {
    if (!res)
      throw Failure{1, "cannot reach the server at " + base + ": " +
                           (res.error() == httplib::Error::Connection ? std::string("could not connect")
                                                                      : httplib::to_string(res.error())) +
                           " (is meshdenoise-server running?)"};
    if (res->status >= 400) throw problem(*res);
    return *res;
  };

  const httplib::Response created = checked(client.Post("/v1/jobs", headers, bytes.str(), media_type.c_str()));
  const std::string location = created.get_header_value("Location");
  // Long polls: each GET answers when the job finishes, or after 30 s with it still running.
  for (;;) {
    const json job = json::parse(checked(client.Get((location + "?wait=30").c_str(), headers)).body);
    const std::string state = job.value("state", "");
    if (state == "succeeded") break;
    if (state == "failed" || state == "cancelled")
      throw Failure{1, "the job " + state + ": " + job.value("error", json::object()).value("detail", std::string())};
  }
  const httplib::Response result = checked(client.Get((location + "/result").c_str(), headers));
  std::ofstream out(output, std::ios::binary);
  out << result.body;
  if (!out.flush()) throw Failure{1, "cannot write " + output};
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return run(argc, argv);
  } catch (const Failure& f) {
    std::cerr << "denoise_client: " << f.message << "\n";
    return f.exit_code;
  }
}
