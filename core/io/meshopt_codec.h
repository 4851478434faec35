// Internal to mdn_io: EXT_meshopt_compression buffer views, decoded with Debian's
// libmeshoptimizer (meshopt_decodeVertexBuffer / IndexBuffer / IndexSequence and the
// octahedral, quaternion and exponential filters).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace mdn::io::detail {

enum class MeshoptMode { Attributes, Triangles, Indices };
enum class MeshoptFilter { None, Octahedral, Quaternion, Exponential };

// The bufferView extension object (EXT_meshopt_compression, "JSON schema updates").
struct MeshoptView {
  std::int64_t byte_stride = 0;
  std::int64_t count = 0;
  MeshoptMode mode = MeshoptMode::Attributes;
  MeshoptFilter filter = MeshoptFilter::None;
};

// Checks the extension's validity rules (stride against mode and filter, TRIANGLES count a
// multiple of 3) so that libmeshoptimizer's own asserts can never fire; FormatError naming
// `where` otherwise.
void check_meshopt_view(const MeshoptView& view, const std::string& where);

// Decodes `compressed` into count x byte_stride bytes (the caller has bounded that size) and
// applies the filter. FormatError naming `where` if the stream does not decode to that layout.
std::vector<unsigned char> meshopt_decode(std::string_view compressed, const MeshoptView& view, const std::string& where);

// The encoders (for test fixtures and seeds, and the writer once there is one):
// `plain` is count x byte_stride bytes; the filter is not applied (see meshopt_encode_filter).
std::string meshopt_encode(std::string_view plain, const MeshoptView& view);
// Filter encoding of `data` (4 floats per element for OCTAHEDRAL and QUATERNION,
// byte_stride / 4 for EXPONENTIAL) with `bits` of precision: count x byte_stride bytes.
std::string meshopt_encode_filter(const float* data, const MeshoptView& view, int bits);

}  // namespace mdn::io::detail
