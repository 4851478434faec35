// glTF 2.0 (.glb and .gltf): in progress, see the next commit.
#include "core/io/detail.h"
#include "core/io/plain.h"

namespace mdn::io::detail {

std::unique_ptr<MeshDocument> decode_gltf(std::string_view, Format, const Limits&) {
  throw UnsupportedError("glTF input is not implemented yet");
}

std::string write_plain_gltf(const std::vector<TriMesh>&, Format, const EncodeOptions&) {
  throw UnsupportedError("glTF output is not implemented yet");
}

}  // namespace mdn::io::detail
