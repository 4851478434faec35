#include "core/io/meshopt_codec.h"

#include <meshoptimizer.h>

#include <algorithm>
#include <cstring>
#include <stdexcept>

#include "core/io/document.h"

namespace mdn::io::detail {

void check_meshopt_view(const MeshoptView& view, const std::string& where) {
  const auto fail = [&](const std::string& rule) { throw FormatError(where + ": EXT_meshopt_compression " + rule); };
  const std::int64_t stride = view.byte_stride;
  if (view.count < 0) fail("count is negative");
  if (view.mode == MeshoptMode::Attributes) {
    if (stride <= 0 || stride % 4 != 0 || stride > 256)
      fail("byteStride " + std::to_string(stride) + " must be a multiple of 4 in [4, 256] for ATTRIBUTES");
  } else {
    if (stride != 2 && stride != 4) fail("byteStride " + std::to_string(stride) + " must be 2 or 4 for TRIANGLES and INDICES");
    if (view.filter != MeshoptFilter::None) fail("filter must be NONE for TRIANGLES and INDICES");
    if (view.mode == MeshoptMode::Triangles && view.count % 3 != 0)
      fail("count " + std::to_string(view.count) + " must be a multiple of 3 for TRIANGLES");
  }
  if (view.filter == MeshoptFilter::Octahedral && stride != 4 && stride != 8) fail("OCTAHEDRAL needs byteStride 4 or 8");
  if (view.filter == MeshoptFilter::Quaternion && stride != 8) fail("QUATERNION needs byteStride 8");
}

std::vector<unsigned char> meshopt_decode(std::string_view compressed, const MeshoptView& view, const std::string& where) {
  check_meshopt_view(view, where);
  const auto count = static_cast<std::size_t>(view.count);
  const auto stride = static_cast<std::size_t>(view.byte_stride);
  std::vector<unsigned char> out(count * stride);
  const auto* source = reinterpret_cast<const unsigned char*>(compressed.data());
  int status = 0;
  switch (view.mode) {
    case MeshoptMode::Attributes: status = meshopt_decodeVertexBuffer(out.data(), count, stride, source, compressed.size()); break;
    case MeshoptMode::Triangles: status = meshopt_decodeIndexBuffer(out.data(), count, stride, source, compressed.size()); break;
    case MeshoptMode::Indices: status = meshopt_decodeIndexSequence(out.data(), count, stride, source, compressed.size()); break;
  }
  if (status != 0)
    throw FormatError(where + ": the EXT_meshopt_compression data does not decode to " + std::to_string(count) + " elements of " +
                      std::to_string(stride) + " bytes (meshoptimizer error " + std::to_string(status) + ")");
  switch (view.filter) {
    case MeshoptFilter::None: break;
    case MeshoptFilter::Octahedral: meshopt_decodeFilterOct(out.data(), count, stride); break;
    case MeshoptFilter::Quaternion: meshopt_decodeFilterQuat(out.data(), count, stride); break;
    case MeshoptFilter::Exponential: meshopt_decodeFilterExp(out.data(), count, stride); break;
  }
  return out;
}

std::string meshopt_encode(std::string_view plain, const MeshoptView& view) {
  check_meshopt_view(view, "meshopt_encode");
  const auto count = static_cast<std::size_t>(view.count), stride = static_cast<std::size_t>(view.byte_stride);
  if (plain.size() != count * stride) throw std::invalid_argument("meshopt_encode: the data is not count x byteStride bytes");
  std::vector<unsigned char> out;
  if (view.mode == MeshoptMode::Attributes) {
    out.resize(meshopt_encodeVertexBufferBound(count, stride));
    out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), plain.data(), count, stride));
  } else {
    std::vector<unsigned int> indices(count);
    unsigned int largest = 0;
    for (std::size_t i = 0; i < count; ++i) {
      if (stride == 2) {
        std::uint16_t v;
        std::memcpy(&v, plain.data() + 2 * i, 2);
        indices[i] = v;
      } else {
        std::memcpy(&indices[i], plain.data() + 4 * i, 4);
      }
      largest = std::max(largest, indices[i]);
    }
    const std::size_t vertices = count ? std::size_t{largest} + 1 : 0;
    if (view.mode == MeshoptMode::Triangles) {
      out.resize(meshopt_encodeIndexBufferBound(count, vertices));
      out.resize(meshopt_encodeIndexBuffer(out.data(), out.size(), indices.data(), count));
    } else {
      out.resize(meshopt_encodeIndexSequenceBound(count, vertices));
      out.resize(meshopt_encodeIndexSequence(out.data(), out.size(), indices.data(), count));
    }
  }
  return std::string(out.begin(), out.end());
}

std::string meshopt_encode_filter(const float* data, const MeshoptView& view, int bits) {
  check_meshopt_view(view, "meshopt_encode_filter");
  const auto count = static_cast<std::size_t>(view.count), stride = static_cast<std::size_t>(view.byte_stride);
  std::string out(count * stride, '\0');
  switch (view.filter) {
    case MeshoptFilter::None: throw std::invalid_argument("meshopt_encode_filter: no filter");
    case MeshoptFilter::Octahedral: meshopt_encodeFilterOct(out.data(), count, stride, bits, data); break;
    case MeshoptFilter::Quaternion: meshopt_encodeFilterQuat(out.data(), count, stride, bits, data); break;
    case MeshoptFilter::Exponential: meshopt_encodeFilterExp(out.data(), count, stride, bits, data); break;
  }
  return out;
}

}  // namespace mdn::io::detail
