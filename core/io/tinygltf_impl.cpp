// The one translation unit that compiles tinygltf's implementation.
//
// No file system (TINYGLTF_NO_FS): tinygltf's default callbacks would read any path a file
// names, "../../etc/hostname" included. No image decoding: images pass through as bytes.
// Draco payloads (KHR_draco_mesh_compression) are decoded by gltf_read.cpp with Draco's core
// Decoder, so tinygltf's own Draco path is not compiled in either.
#include <fstream>  // tiny_gltf.h 2.7 uses std::ofstream even with TINYGLTF_NO_FS

#define TINYGLTF_IMPLEMENTATION
#define TINYGLTF_NO_FS
#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include "core/io/tinygltf_load.h"

#include "core/io/document.h"

namespace mdn::io::detail {
namespace {

struct RefusedUri {
  std::string uri;
};

bool refuse_exists(const std::string&, void*) { return false; }
std::string keep_path(const std::string& path, void*) { return path; }
bool refuse_read(std::vector<unsigned char>*, std::string* err, const std::string& path, void* user) {
  static_cast<RefusedUri*>(user)->uri = path;
  if (err) *err += "external URI refused: " + path;
  return false;
}
bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "writing files is disabled";
  return false;
}
// Images are carried through untouched; nothing decodes them.
bool keep_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

}  // namespace

tinygltf::Model load_tinygltf(std::string_view bytes, bool binary) {
  tinygltf::TinyGLTF loader;
  RefusedUri refused;
  loader.SetFsCallbacks(tinygltf::FsCallbacks{&refuse_exists, &keep_path, &refuse_read, &refuse_write, &refused});
  loader.SetImageLoader(&keep_image, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  const bool ok =
      binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, reinterpret_cast<const unsigned char*>(bytes.data()),
                                           static_cast<unsigned int>(bytes.size()), "")
             : loader.LoadASCIIFromString(&model, &err, &warn, bytes.data(), static_cast<unsigned int>(bytes.size()), "");
  if (!refused.uri.empty()) throw UnsupportedError("external URI '" + refused.uri.substr(0, 200) + "' refused: only embedded data is read");
  if (!ok) throw FormatError("glTF: " + (err.empty() ? std::string("tinygltf could not parse the asset") : err.substr(0, 500)));
  return model;
}

std::string base64_encode(std::string_view bytes) {
  return tinygltf::base64_encode(reinterpret_cast<const unsigned char*>(bytes.data()), static_cast<unsigned int>(bytes.size()));
}

}  // namespace mdn::io::detail
