// Peak memory of decoding a .gltf whose one buffer is a base64 data URI, against the body's
// size (issue 49, item 5: a 250 MiB .gltf peaked at 7x its size; decision 82), with the .glb
// of the same content beside it. The asset: an n x n grid (float32 positions, uint32
// indices), sized so that the .gltf is about MIB mebibytes. Asserts nothing (never part of
// ctest). Compare figures only within one run on one machine.
//
//   gltf_memory_bench [--mib 50,250] [--allocator glibc|cli] [--keep DIR]
//
//   --mib LIST      .gltf body sizes in MiB (default 50,250)
//   --allocator     glibc's defaults (the server; the default) or as meshdenoise allocates
//                   (service::keep_freed_memory, decision 52)
//   --keep DIR      also leave the files there (grid-MIB.gltf / .glb, blob-...), for a black-box run of
//                   meshdenoise under /usr/bin/time -v
//
// Assets: grid (the mesh is the whole body) and blob (a 256 x 256 grid, and filler bytes as an
// image make the body: what the container's decoding costs, apart from the mesh's).
// Rows: asset, container, how the body reaches the decoder (view: io::decode over bytes the caller
// keeps, as the compare route and --metrics do; owned: io::decode_owned, which may free them,
// as every job does through service::run_job), the body, the process's resident memory before
// the body was read, its peak (VmHWM) at the end of the decode, and (peak - start) / body.
// Each row runs in a child forked from a parent that holds nothing large, which reads the file
// as the command-line tool does.
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "io/gltf_fixtures.h"
#include "service/process_memory.h"

namespace {

using namespace mdn;

// VmHWM / VmRSS of this process in MiB (Linux).
double proc_status_mib(const char* key) {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind(key, 0) == 0) return std::strtod(line.c_str() + std::strlen(key), nullptr) / 1024.0;
  return 0;
}

// An n x n grid of vertices on z = 0 (2 (n-1)^2 triangles) as a GLB: one buffer, positions
// then indices, then `filler` bytes as an image's view (carried, never decoded).
std::string grid_glb(int n, std::size_t filler) {
  std::vector<float> positions;
  positions.reserve(static_cast<std::size_t>(n) * n * 3);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) positions.insert(positions.end(), {float(i) / float(n - 1), float(j) / float(n - 1), 0.0f});
  std::vector<std::uint32_t> indices;
  indices.reserve(static_cast<std::size_t>(n - 1) * (n - 1) * 6);
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const auto a = static_cast<std::uint32_t>(j * n + i), b = a + 1, c = a + static_cast<std::uint32_t>(n), d = c + 1;
      indices.insert(indices.end(), {a, b, d, a, d, c});
    }
  test_io::Builder b;
  b.json["asset"] = {{"version", "2.0"}};
  b.json["scene"] = 0;
  b.json["scenes"] = test_io::Json::array({{{"nodes", {0}}}});
  b.json["nodes"] = test_io::Json::array({{{"mesh", 0}}});
  const int position = b.accessor(positions, 5126, "VEC3", 3, false, 34962, true);
  std::vector<float>().swap(positions);
  const int index = b.accessor(indices, 5125, "SCALAR", 1, false, 34963);
  std::vector<std::uint32_t>().swap(indices);
  if (filler > 0) {
    std::string bytes(filler, '\0');
    std::uint64_t state = 1;
    for (char& c : bytes) c = static_cast<char>((state = state * 6364136223846793005ULL + 1442695040888963407ULL) >> 56);
    b.json["images"] = test_io::Json::array({{{"bufferView", b.view(bytes)}, {"mimeType", "image/png"}}});
  }
  b.json["meshes"] = test_io::Json::array({{{"primitives", {{{"attributes", {{"POSITION", position}}}, {"indices", index}}}}}});
  return b.glb();
}

io::Limits big_limits() {
  io::Limits limits;
  limits.max_vertices = limits.max_faces = 100'000'000;
  limits.max_decoded_bytes = std::int64_t{64} << 30;
  return limits;
}

void write_file(const std::filesystem::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  if (!out) throw std::runtime_error("cannot write " + path.string());
}

// In a child: the .glb, and the .gltf the library writes from it (compression None: the same
// accessors and bytes, one data URI).
void make_files(int n, std::size_t filler, const std::filesystem::path& glb, const std::filesystem::path& gltf) {
  std::string bytes = grid_glb(n, filler);
  write_file(glb, bytes);
  io::EncodeOptions options;
  options.format = io::Format::Gltf;
  options.compression = io::Compression::None;
  const auto doc = io::decode(bytes, io::Format::Glb, big_limits());
  std::string().swap(bytes);
  write_file(gltf, doc->encode(options).bytes);
}

// In a child: reads the file and decodes it; prints one row.
void measure(const char* asset, const std::filesystem::path& path, io::Format format, bool owned) {
  const double start = proc_status_mib("VmRSS:");
  std::string body;
  {
    std::ifstream in(path, std::ios::binary);
    body.resize(std::filesystem::file_size(path));
    in.read(body.data(), static_cast<std::streamsize>(body.size()));
  }
  const double body_mib = static_cast<double>(body.size()) / (1 << 20);
  io::DecodeOptions options;
  options.limits = big_limits();
  const std::unique_ptr<io::MeshDocument> doc =
      owned ? io::decode_owned(std::move(body), format, options) : io::decode(body, format, options);
  const double peak = proc_status_mib("VmHWM:");
  std::printf("%-5s | %-5s | %-5s | %9.1f | %8d | %9.1f | %9.1f | %5.2f\n", asset, format == io::Format::Gltf ? "gltf" : "glb",
              owned ? "owned" : "view", body_mib, static_cast<int>(doc->surfaces()[0].num_faces()), start, peak,
              (peak - start) / body_mib);
  std::fflush(stdout);
}

template <class F>
void in_child(F&& f, bool keep_freed_memory) {
  std::fflush(stdout);
  const pid_t pid = fork();
  if (pid < 0) throw std::runtime_error("fork failed");
  if (pid == 0) {
    try {
      if (keep_freed_memory) service::keep_freed_memory();
      f();
    } catch (const std::exception& e) {
      std::fprintf(stderr, "error: %s\n", e.what());
      _exit(1);
    }
    _exit(0);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("a child failed");
}

std::vector<int> parse_list(const std::string& text) {
  std::vector<int> out;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) out.push_back(std::stoi(item));
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<int> mibs = {50, 250};
  bool cli_allocator = false;
  std::filesystem::path keep;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--mib" && i + 1 < argc) mibs = parse_list(argv[++i]);
    else if (arg == "--allocator" && i + 1 < argc) cli_allocator = std::string(argv[++i]) == "cli";
    else if (arg == "--keep" && i + 1 < argc) keep = argv[++i];
    else {
      std::fprintf(stderr, "usage: gltf_memory_bench [--mib 50,250] [--allocator glibc|cli] [--keep DIR]\n");
      return 2;
    }
  }
  const std::filesystem::path dir = keep.empty() ? std::filesystem::temp_directory_path() / ("gltf_memory_bench." + std::to_string(getpid())) : keep;
  std::filesystem::create_directories(dir);
  std::printf("allocator: %s\n", cli_allocator ? "cli (keep_freed_memory)" : "glibc defaults");
  std::printf("asset | file  | body  | body MiB  | faces    | start MiB | peak MiB  | (peak-start)/body\n");
  try {
    for (const int mib : mibs)
      for (const char* asset : {"grid", "blob"}) {
        // grid: the mesh is the body; a .gltf costs about 4/3 x (12 + 24) = 48 bytes per vertex
        // (two triangles each). blob: a 256 x 256 grid and filler bytes make the body.
        const bool grid = asset == std::string("grid");
        const std::size_t body = static_cast<std::size_t>(mib) << 20;
        const int n = grid ? static_cast<int>(std::sqrt(double(body) / 48.0)) : 256;
        const std::size_t filler = grid ? 0 : body / 4 * 3 - 256 * 256 * 36;
        const std::string stem = std::string(asset) + "-" + std::to_string(mib);
        const auto glb = dir / (stem + ".glb"), gltf = dir / (stem + ".gltf");
        in_child([&] { make_files(n, filler, glb, gltf); }, false);
        for (const bool owned : {false, true}) in_child([&] { measure(asset, gltf, io::Format::Gltf, owned); }, cli_allocator);
        in_child([&] { measure(asset, glb, io::Format::Glb, false); }, cli_allocator);
        if (keep.empty()) {
          std::filesystem::remove(glb);
          std::filesystem::remove(gltf);
        }
      }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "gltf_memory_bench: %s\n", e.what());
    return 1;
  }
  if (keep.empty()) std::filesystem::remove(dir);
  return 0;
}
