// Writes a CGAL demo mesh subdivided LEVELS times by tests/bench/subdivide.h's rule, as OFF: the
// large inputs of the web page's drawing bench (scripts/bench-web-draw.sh), made the way the
// other benchmarks make theirs.
//   build/release/tests/bench/subdivide_mesh IN.off OUT.off LEVELS
#include <cstdio>
#include <fstream>
#include <string>

#include "cgal_data.h"
#include "support/shapes.h"
#include "subdivide.h"

int main(int argc, char** argv) {
  if (argc != 4) {
    std::fprintf(stderr, "usage: %s IN.off OUT.off LEVELS\n", argv[0]);
    return 2;
  }
  try {
    mdn::TriMesh mesh = mdn::bench::load_off(argv[1]);
    for (int level = std::stoi(argv[3]); level > 0; --level) mesh = mdn::bench::midpoint_subdivide(mesh);
    std::ofstream(argv[2], std::ios::binary) << mdn::test::off_text(mesh);
    std::printf("%s: %lld vertices, %lld faces\n", argv[2], static_cast<long long>(mesh.num_vertices()),
                static_cast<long long>(mesh.num_faces()));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 3;
  }
  return 0;
}
