// Writes the fuzzers' seed corpora, all generated here (no third-party files): for each format
// a directory of small valid files in its variants, written by mdn_io itself from procedural
// meshes and the glTF test fixtures (the meshopt one through libmeshoptimizer's encoders), plus
// parameter texts.
//   fuzz_seeds OUT_DIR   ->  OUT_DIR/{off,obj,ply,drc,glb,gltf,stl,params}/seed-N
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "core/io/document.h"
#include "io/gltf_fixtures.h"
#include "io/meshopt_fixture.h"
#include "support/shapes.h"

namespace {

using namespace mdn;
namespace fs = std::filesystem;

void write(const fs::path& dir, const std::string& bytes) {
  fs::create_directories(dir);
  const auto n = std::distance(fs::directory_iterator(dir), fs::directory_iterator{});
  std::ofstream(dir / ("seed-" + std::to_string(n)), std::ios::binary) << bytes;
}

std::string encode(const std::string& off, io::Format format, bool draco, int position_bits = 16) {
  io::EncodeOptions options;
  options.format = format;
  options.compression = draco ? mdn::io::Compression::Draco : mdn::io::Compression::None;
  options.position_bits = position_bits;
  return io::decode(off, io::Format::Off)->encode(options).bytes;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_seeds OUT_DIR\n");
    return 2;
  }
  const fs::path out = argv[1];
  const std::vector<std::string> meshes = {test::off_text(test::sphere(0)), test::off_text(test::cube(1)),
                                           test::off_text(test::plane(2))};
  for (const std::string& off : meshes) {
    write(out / "off", off);
    write(out / "obj", encode(off, io::Format::Obj, false));
    write(out / "ply", encode(off, io::Format::Ply, false));
    write(out / "drc", encode(off, io::Format::Drc, true));
    write(out / "drc", encode(off, io::Format::Drc, true, 8));
    write(out / "glb", encode(off, io::Format::Glb, true));
    write(out / "glb", encode(off, io::Format::Glb, false));
    write(out / "gltf", encode(off, io::Format::Gltf, false));
    write(out / "gltf", encode(off, io::Format::Gltf, true));
    const std::string stl = encode(off, io::Format::Stl, false);  // binary
    write(out / "stl", stl);
    std::string solid_header = stl;  // binary whose header starts with "solid" (the sniffing trap)
    solid_header.replace(0, 11, "solid trap ");
    write(out / "stl", solid_header);
  }
  // Text variants the writers above do not produce.
  write(out / "off", "COFF\n3 1 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n3 0 1 2 9 9 9\n");
  write(out / "off", "NOFF 3 1 0\n# comment\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n");
  write(out / "obj", "# obj\nmtllib a.mtl\no quad\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvn 0 0 1\n"
                     "usemtl m\nf 1/1/1 2/2/1 3/3/1\nf -4//1 -2//1 -1//1\ns off\n");
  write(out / "ply", "ply\nformat ascii 1.0\ncomment c\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                     "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nelement face 1\n"
                     "property list uchar int vertex_indices\nelement extra 1\nproperty int value\nend_header\n"
                     "0 0 0 0 0 1 255\n1 0 0 0 0 1 0\n0 1 0 0 0 1 9\n3 0 1 2\n7\n");
  write(out / "ply", "ply\nformat binary_big_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                     "property double z\nelement face 1\nproperty list uchar uint vertex_indices\nend_header\n" +
                         std::string(72, '\0') + std::string("\x03\0\0\0\0\0\0\0\x01\0\0\0\x02", 13));
  write(out / "stl", "solid tri\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n"
                     "  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n   vertex 1 0 0\n   vertex 1 1 0\n"
                     "   vertex 0 1 0\n  endloop\n endfacet\nendsolid tri\nsolid second\nendsolid second\n");
  // The glTF fixture scene: two primitives, a texture, instancing, extras; quantized, sparse,
  // strips and fans.
  const test_io::SphereFixture fixture = test_io::make_sphere();
  for (const auto variant : {test_io::Variant::Plain, test_io::Variant::Quantized, test_io::Variant::Sparse}) {
    const std::string glb = test_io::sphere_scene_glb(fixture, variant);
    write(out / "glb", glb);
    write(out / "glb", io::decode(glb, io::Format::Glb)->encode({}).bytes);  // its Draco output
    io::EncodeOptions gltf;
    gltf.format = io::Format::Gltf;
    gltf.compression = mdn::io::Compression::None;
    write(out / "gltf", io::decode(glb, io::Format::Glb)->encode(gltf).bytes);
  }
  write(out / "glb", test_io::strip_and_fan_glb(3));
  // EXT_meshopt_compression (every mode and filter, KHR_mesh_quantization positions).
  write(out / "glb", test_io::meshopt_sphere_glb(fixture, true));
  // Parameters.
  for (const char* text :
       {"{}", R"({"mode":"manual"})", R"({"n_normal":30,"n_vertex":20,"output":{"position_bits":14}})",
        R"({"mode":"manual","alpha":0.2,"sigma_theta":40,"n_aniso":6,"sigma_gamma":30,"n_normal":50,"n_vertex":40,"region_mode":"auto","output":{"format":"glb","draco":true,"position_bits":14,"normal_bits":10}})",
        R"({"region_mode":"off","output":{"format":"ply","draco":false,"compression_level":3}})"})
    write(out / "params", text);
  // The job path (fuzz_job): the container's byte, the parameters, '\n', the mesh. Every format
  // with the default and the paper's parameters, Draco at each end of its levels, and the mesh
  // whose coincident vertices crashed Draco's encoder at levels 9-10 (issue 49, item 0).
  const char* job_params[] = {"{}", R"({"mode":"manual","n_normal":5,"n_vertex":5})",
                              R"({"mode":"none","output":{"compression":"draco","compression_level":10}})",
                              R"({"mode":"manual","output":{"format":"drc","compression_level":0,"position_bits":8}})"};
  const std::string off = test::off_text(test::sphere(0));
  for (std::size_t f = 0; f < 7; ++f) {
    const io::Format formats[] = {io::Format::Off, io::Format::Obj, io::Format::Ply, io::Format::Drc,
                                  io::Format::Glb, io::Format::Gltf, io::Format::Stl};
    const std::string mesh = formats[f] == io::Format::Off ? off : encode(off, formats[f], formats[f] == io::Format::Drc);
    for (std::size_t p = 0; p < std::size(job_params); p += f % 2 ? 2 : 1)
      write(out / "job", std::string(1, static_cast<char>(f)) + job_params[p] + "\n" + mesh);
  }
  write(out / "job", std::string(1, 4) + R"({"mode":"none","output":{"compression":"draco","compression_level":9}})" +
                         "\nOFF\n3 1 0\n1 1 1\n1 1 1\n1 1 1\n3 0 1 2\n");
  // The HTTP request reader (fuzz_http_framing): the piece size's byte, then what a connection
  // sends: plain and pipelined requests, a Content-Length body, chunked bodies with extensions
  // and trailers, and the shapes of issue 49's attacks (a line that never ends, "0x" and "+"
  // chunk sizes, Transfer-Encoding: gzip, chunked).
  for (const char* http :
       {"\x07GET /healthz HTTP/1.1\r\nHost: x\r\n\r\n",
        "\x01GET /healthz HTTP/1.1\r\nHost: x\r\n\r\nGET /readyz?x=1 HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\r\n",
        "\x10\r\nPOST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Length: 5\r\n\r\nOFF\n0GET / HTTP/1.0\r\n\r\n",
        "\x03POST /v1/denoise HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n4;name=value\r\nOFF\n\r\n"
        "1c\r\n0123456789abcdef0123456789ab\r\n0\r\nX-Trailer: 1\r\n\r\n",
        "\x05POST /v1/denoise HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n0x1c\r\n",
        "\x05POST /v1/denoise HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: chunked\r\n\r\n+1c\r\n",
        "\x05POST /v1/denoise HTTP/1.1\r\nHost: x\r\nTransfer-Encoding: gzip, chunked\r\n\r\n0\r\n\r\n",
        "\x40GET /aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
        "\x02GET / HTTP/1.1\r\nX-Long: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaaa",
        "\x02OPTIONS * HTTP/1.1\r\nHost: x\r\n folded\r\n\r\n"})
    write(out / "http_framing", http);
  return 0;
}
