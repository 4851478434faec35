// meshdenoise-server client in C++ with cpp-httplib (build with pkg-config's flags:
//   g++ -std=c++20 denoise_client.cpp $(pkg-config --cflags --libs cpp-httplib)).
// Usage: denoise_client <host> <port> <input> <output> [params-json]
// Sends the mesh as an asynchronous job, waits for it (long polls), downloads the result.
#include <httplib.h>

#include <fstream>
#include <iostream>
#include <sstream>
#include <string>

namespace {

std::string media_type(const std::string& path) {
  const auto dot = path.rfind('.');
  const std::string ext = dot == std::string::npos ? "" : path.substr(dot);
  if (ext == ".glb") return "model/gltf-binary";
  if (ext == ".gltf") return "model/gltf+json";
  if (ext == ".drc") return "model/x-draco";
  if (ext == ".off") return "model/x-off";
  if (ext == ".obj") return "model/obj";
  if (ext == ".ply") return "model/x-ply";
  return "application/octet-stream";
}

// The "state" value of the job JSON (a tiny scan keeps this example dependency-free).
std::string job_state(const std::string& json) {
  const auto key = json.find("\"state\":\"");
  if (key == std::string::npos) return "";
  const auto begin = key + 9;
  return json.substr(begin, json.find('"', begin) - begin);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::cerr << "usage: denoise_client <host> <port> <input> <output> [params-json]\n";
    return 2;
  }
  const std::string input = argv[3], output = argv[4], params = argc > 5 ? argv[5] : "{}";
  std::ifstream in(input, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();

  httplib::Client client(argv[1], std::stoi(argv[2]));
  client.set_read_timeout(600, 0);
  httplib::Headers headers = {{"X-Denoise-Params", params}};
  if (const char* token = std::getenv("MDN_TOKEN")) headers.emplace("Authorization", std::string("Bearer ") + token);

  auto created = client.Post("/v1/jobs", headers, bytes.str(), media_type(input).c_str());
  if (!created) return std::cerr << "connection failed: " << httplib::to_string(created.error()) << "\n", 1;
  if (created->status != 202) return std::cerr << created->status << " " << created->body << "\n", 1;
  const std::string location = created->get_header_value("Location");

  // Long polls: each GET answers when the job finishes, or after 30 s with it still running.
  for (;;) {
    auto job = client.Get((location + "?wait=30").c_str(), headers);
    if (!job || job->status != 200) return std::cerr << "polling failed\n", 1;
    const std::string state = job_state(job->body);
    if (state == "succeeded") break;
    if (state == "failed" || state == "cancelled") return std::cerr << job->body << "\n", 1;
  }
  auto result = client.Get((location + "/result").c_str(), headers);
  if (!result || result->status != 200) return std::cerr << "download failed\n", 1;
  std::ofstream(output, std::ios::binary) << result->body;
  return 0;
}
