// glTF 2.0: the asset's JSON before tinygltf sees it (gltf_read.cpp's first step): the GLB
// container's JSON chunk, a parse bounded in depth and size, the shape check of what the
// decoder reads, the required extensions it understands, and a .gltf's external buffers and
// images resolved inside its folder (nothing outside the bytes without a resource folder).
#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <nlohmann/json.hpp>
#include <set>
#include <string>

#include "core/io/detail.h"
#include "core/io/gltf_model.h"

namespace mdn::io::detail::gltf {

// The JSON chunk of a GLB, with the container's lengths checked.
std::string_view glb_json(std::string_view bytes) {
  auto u32 = [&](std::size_t at) {
    std::uint32_t v;
    std::memcpy(&v, bytes.data() + at, 4);
    return v;
  };
  if (bytes.size() < 20 || bytes.substr(0, 4) != "glTF") throw FormatError("GLB: missing the 'glTF' header");
  if (u32(4) != 2) throw UnsupportedError("GLB: container version " + std::to_string(u32(4)) + " (only 2 is supported)");
  if (u32(8) > bytes.size()) throw FormatError("GLB: the header declares more bytes than the input has (truncated?)");
  const std::uint32_t length = u32(12);
  if (u32(16) != 0x4E4F534A) throw FormatError("GLB: the first chunk is not JSON");
  if (length > bytes.size() - 20) throw FormatError("GLB: the JSON chunk reaches past the end of the input");
  return bytes.substr(20, length);
}

// A relative URI reference (RFC 3986) as a path inside the resource folder: percent-decoded,
// refused with UnsupportedError if it has a scheme, is absolute, climbs out with "..", or
// holds a backslash or a NUL.
std::filesystem::path resource_path(const std::string& uri, const std::string& where) {
  const auto refuse = [&](const char* why) -> std::filesystem::path {
    throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + where + " refused: " + why);
  };
  const std::size_t colon = uri.find(':');
  if (colon != std::string::npos && uri.find_first_of("/?#") > colon) refuse("a URI with a scheme is never fetched");
  std::string decoded;
  for (std::size_t i = 0; i < uri.size(); ++i) {
    if (uri[i] == '?' || uri[i] == '#') break;  // query and fragment name no file
    if (uri[i] == '%' && i + 2 < uri.size() && std::isxdigit(static_cast<unsigned char>(uri[i + 1])) &&
        std::isxdigit(static_cast<unsigned char>(uri[i + 2]))) {
      decoded += static_cast<char>(std::stoi(uri.substr(i + 1, 2), nullptr, 16));
      i += 2;
    } else {
      decoded += uri[i];
    }
  }
  if (decoded.empty()) refuse("empty");
  if (decoded.find('\\') != std::string::npos || decoded.find('\0') != std::string::npos) refuse("a backslash or NUL in a path");
  if (decoded.front() == '/') refuse("an absolute path; only files inside the .gltf's folder are read");
  const std::filesystem::path relative = std::filesystem::path(decoded).lexically_normal();
  for (const auto& part : relative)
    if (part == "..") refuse("it leads out of the .gltf's folder");
  return relative;
}

// Buffers and images referenced by URI: refused (the service), or, with a resource folder
// (the command-line tool), read from it and embedded before anything else reads the asset, so
// the rest of the decoder and the encoder only ever see embedded data: images as data URIs,
// buffers (`buffers` given) into element i of `buffers`, as decode_lifted's. Returns how many
// were read.
int resolve_external(Json& json, const char* key, const std::string* resource_dir, const Limits& limits,
                     std::int64_t& read_bytes, std::vector<std::vector<unsigned char>>* buffers) {
  if (!json.contains(key) || !json[key].is_array()) return 0;
  int read = 0;
  for (std::size_t i = 0; i < json[key].size(); ++i) {
    Json& item = json[key][i];
    if (!item.is_object() || !item.contains("uri")) continue;
    if (!item["uri"].is_string()) throw FormatError(std::string("glTF: a uri in ") + key + " is not a string");
    const std::string uri = item["uri"].get<std::string>();
    if (uri.rfind("data:", 0) == 0) continue;
    if (!resource_dir)
      throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + key + " refused: only embedded data is read");
    const std::string where = std::string(key) + "[" + std::to_string(i) + "]";
    const std::filesystem::path file = std::filesystem::path(*resource_dir) / resource_path(uri, where);
    std::error_code ec;
    // A symbolic link inside the folder must not lead out of it either.
    const std::filesystem::path root = std::filesystem::weakly_canonical(*resource_dir, ec);
    const std::filesystem::path real = std::filesystem::weakly_canonical(file, ec);
    const auto [r, f] = std::mismatch(root.begin(), root.end(), real.begin(), real.end());
    if (r != root.end())
      throw UnsupportedError("external URI '" + uri.substr(0, 200) + "' in " + where + " refused: it leads out of the .gltf's folder");
    const auto size = std::filesystem::file_size(file, ec);
    if (ec || !std::filesystem::is_regular_file(file, ec))
      throw FormatError("glTF: " + where + " names '" + uri.substr(0, 200) + "', which cannot be read (" +
                        (ec ? ec.message() : std::string("not a regular file")) + ")");
    read_bytes += static_cast<std::int64_t>(size);
    if (read_bytes > limits.max_decoded_bytes)
      throw LimitError("glTF: the external files come to more than " + std::to_string(limits.max_decoded_bytes) + " bytes");
    std::ifstream in(file, std::ios::binary);
    if (buffers) {  // a buffer's bytes go to the model as they are, as a data URI's (decision 82)
      const auto length = item.find("byteLength");
      if (length == item.end() || !length->is_number_unsigned() || length->get<std::uint64_t>() != size)
        throw FormatError("glTF: " + where + " names '" + uri.substr(0, 200) + "', of " + std::to_string(size) +
                          " bytes, and its byteLength does not say so");
      buffers->resize(json[key].size());
      std::vector<unsigned char>& data = (*buffers)[i];
      data.resize(static_cast<std::size_t>(size));
      if (!in.read(reinterpret_cast<char*>(data.data()), static_cast<std::streamsize>(size)))
        throw FormatError("glTF: cannot read '" + uri.substr(0, 200) + "'");
      item["uri"] = "data:application/octet-stream;base64,";
      ++read;
      continue;
    }
    std::string data((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.good() && !in.eof()) throw FormatError("glTF: cannot read '" + uri.substr(0, 200) + "'");
    std::string mime = "application/octet-stream";
    if (std::string(key) == "images") {
      mime = item.value("mimeType", std::string());
      if (mime.empty()) {
        const std::string ext = file.extension().string();
        mime = ext == ".png" ? "image/png" : ext == ".jpg" || ext == ".jpeg" ? "image/jpeg" : ext == ".webp" ? "image/webp" : "application/octet-stream";
      }
    }
    item["uri"] = "data:" + mime + ";base64," + base64_encode(data);
    ++read;
  }
  return read;
}


// Required extensions this adapter reads (geometry) or that do not change what the geometry
// is (materials, textures, lights, instancing of nodes): all are carried over verbatim. A
// loader must refuse any other required extension (glTF 2.0, 3.12).
bool understood_extension(std::string_view name) {
  static constexpr std::string_view kKnown[] = {
      kDraco, kMeshopt, "KHR_mesh_quantization", "KHR_texture_transform", "KHR_texture_basisu", "KHR_lights_punctual",
      "KHR_materials_variants", "EXT_mesh_gpu_instancing", "EXT_texture_webp", "EXT_texture_avif"};
  for (const auto known : kKnown)
    if (name == known) return true;
  return name.rfind("KHR_materials_", 0) == 0;
}

// The JSON's shape where this adapter reads it: wrong types are a FormatError here instead of a
// JSON type error later (e.g. "nodes": 0).
// Entries of json[key] when it is an array (no copy), else 0.
std::size_t size_of(const Json& json, const char* key) {
  const auto it = json.find(key);
  return it != json.end() && it->is_array() ? it->size() : 0;
}

void check_shape(const Json& json) {
  const auto fail = [](const std::string& where, const char* expected) {
    throw FormatError("glTF: " + where + " must be " + expected);
  };
  const auto objects = [&](const Json& parent, const char* key, const std::string& where) {
    if (!parent.contains(key)) return;
    const Json& list = parent[key];
    if (!list.is_array()) fail(where + key, "an array");
    for (std::size_t i = 0; i < list.size(); ++i)
      if (!list[i].is_object()) fail(where + key + "[" + std::to_string(i) + "]", "an object");
  };
  const auto object = [&](const Json& parent, const char* key, const std::string& where) {
    if (parent.contains(key) && !parent[key].is_object()) fail(where + key, "an object");
  };
  const auto integer = [&](const Json& parent, const char* key, const std::string& where) {
    if (parent.contains(key) && !parent[key].is_number_integer()) fail(where + key, "an integer");
  };
  for (const char* key : {"accessors", "animations", "buffers", "bufferViews", "cameras", "images", "materials", "meshes",
                          "nodes", "samplers", "scenes", "skins", "textures"})
    objects(json, key, "");
  for (const char* key : {"extensionsUsed", "extensionsRequired"}) {
    if (!json.contains(key)) continue;
    if (!json[key].is_array()) fail(key, "an array of strings");
    for (const auto& name : json[key])
      if (!name.is_string()) fail(key, "an array of strings");
  }
  object(json, "asset", "");
  object(json, "extensions", "");
  integer(json, "scene", "");
  for (std::size_t m = 0; m < size_of(json, "meshes"); ++m) {
    const Json& mesh = json["meshes"][m];
    const std::string where = "meshes[" + std::to_string(m) + "].";
    objects(mesh, "primitives", where);
    for (std::size_t p = 0; p < size_of(mesh, "primitives"); ++p) {
      const Json& prim = mesh["primitives"][p];
      const std::string at = where + "primitives[" + std::to_string(p) + "].";
      object(prim, "attributes", at);
      object(prim, "extensions", at);
      integer(prim, "indices", at);
      integer(prim, "mode", at);
      objects(prim, "targets", at);
      if (prim.contains("attributes"))
        for (const auto& [semantic, index] : prim["attributes"].items())
          if (!index.is_number_integer()) fail(at + "attributes." + semantic, "an integer");
    }
  }
  for (std::size_t n = 0; n < size_of(json, "nodes"); ++n) {
    const Json& node = json["nodes"][n];
    const std::string where = "nodes[" + std::to_string(n) + "].";
    object(node, "extensions", where);
    if (node.contains("extensions") && node["extensions"].contains("EXT_mesh_gpu_instancing")) {
      const Json& instancing = node["extensions"]["EXT_mesh_gpu_instancing"];
      if (!instancing.is_object()) fail(where + "extensions.EXT_mesh_gpu_instancing", "an object");
      object(instancing, "attributes", where + "extensions.EXT_mesh_gpu_instancing.");
    }
  }
  for (std::size_t a = 0; a < size_of(json, "animations"); ++a)
    objects(json["animations"][a], "samplers", "animations[" + std::to_string(a) + "].");
}

// Parses the JSON with its nesting depth and size bounded before anything recursive walks it
// (tinygltf's parser overflows the stack at a depth of about 20,000), and charges what the
// parsed scene will hold: our two copies of the JSON and tinygltf's objects.
Json parse_bounded(std::string_view text, const Limits& limits, std::int64_t& bytes) {
  // One linear pass over the text (nlohmann's callback parser is quadratic on long arrays):
  // the nesting depth, and the number of values (commas and openings; exact for valid JSON).
  std::int64_t values = 1;
  int depth = 0;
  bool in_string = false;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      if (c == '\\') ++i;
      else if (c == '"') in_string = false;
    } else if (c == '"') {
      in_string = true;
    } else if (c == '{' || c == '[') {
      ++values;
      if (++depth > limits.max_json_depth)
        throw LimitError("glTF: the JSON nests deeper than the limit of " + std::to_string(limits.max_json_depth) +
                         " (max_json_depth)");
    } else if (c == '}' || c == ']') {
      --depth;
    } else if (c == ',') {
      ++values;
    }
  }
  Json json;
  try {
    json = Json::parse(text);
  } catch (const Json::exception& e) {
    throw FormatError(std::string("glTF: invalid JSON (") + e.what() + ")");
  }
  if (!json.is_object()) throw FormatError("glTF: the JSON is not an object");
  check_shape(json);
  const auto count = [&](const char* key) { return static_cast<std::int64_t>(size_of(json, key)); };
  const auto limit = [](std::int64_t n, std::int64_t max, const char* what, const char* name) {
    if (n > max)
      throw LimitError("glTF: the asset has " + std::to_string(n) + " " + what + ", more than the limit of " + std::to_string(max) +
                       " (" + name + ")");
  };
  limit(count("nodes"), limits.max_nodes, "nodes", "max_nodes");
  limit(count("accessors") + count("bufferViews"), limits.max_accessors, "accessors and buffer views", "max_accessors");
  std::int64_t primitives = 0;
  for (std::size_t m = 0; m < size_of(json, "meshes"); ++m) primitives += static_cast<std::int64_t>(size_of(json["meshes"][m], "primitives"));
  limit(primitives, limits.max_accessors, "primitives", "max_accessors");
  // About 3 x 64 bytes per JSON value (the JSON, the copy given to tinygltf, tinygltf's own).
  bytes = values * 192 + count("nodes") * static_cast<std::int64_t>(sizeof(tinygltf::Node)) +
          count("accessors") * static_cast<std::int64_t>(sizeof(tinygltf::Accessor)) +
          count("bufferViews") * static_cast<std::int64_t>(sizeof(tinygltf::BufferView)) +
          count("meshes") * static_cast<std::int64_t>(sizeof(tinygltf::Mesh)) +
          primitives * static_cast<std::int64_t>(sizeof(tinygltf::Primitive)) +
          count("materials") * static_cast<std::int64_t>(sizeof(tinygltf::Material)) + static_cast<std::int64_t>(text.size()) * 2;
  if (bytes > limits.max_decoded_bytes)
    throw LimitError("glTF: the scene would take about " + std::to_string(bytes) + " bytes of memory, more than the limit of " +
                     std::to_string(limits.max_decoded_bytes) + " (max_decoded_bytes)");
  return json;
}

}  // namespace mdn::io::detail::gltf
