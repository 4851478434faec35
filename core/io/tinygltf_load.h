// Internal to mdn_io: tinygltf, compiled once in tinygltf_impl.cpp with its file system and
// image decoding switched off (Debian's libtinygltf is not linked; see README.md).
#pragma once

#include <tiny_gltf.h>

#include <string>
#include <string_view>

namespace mdn::io::detail {

// Parses glTF JSON (binary = false) or a GLB container. The file-system callbacks refuse
// every external URI without touching the file system; images are not decoded. Throws
// UnsupportedError for an external URI and FormatError for anything tinygltf rejects.
tinygltf::Model load_tinygltf(std::string_view bytes, bool binary);

// Base64 (for data URIs in .gltf outputs), tinygltf's encoder.
std::string base64_encode(std::string_view bytes);

}  // namespace mdn::io::detail
