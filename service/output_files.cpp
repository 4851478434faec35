#include "service/output_files.h"

#include <cstdint>
#include <filesystem>

#include <nlohmann/json.hpp>

namespace mdn::service {
namespace {

using nlohmann::json;

std::string base64_decode(std::string_view text) {
  static constexpr std::string_view kAlphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (const char c : text) {
    const std::size_t v = kAlphabet.find(c);
    if (v == std::string_view::npos) continue;  // '=' padding
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out += static_cast<char>((bits >> count) & 0xFF);
    }
  }
  return out;
}

}  // namespace

std::string output_file_name(std::string_view input_name, std::optional<io::Format> format) {
  std::filesystem::path name = std::filesystem::path(input_name).filename();
  if (name.empty()) name = "denoised";
  if (format) name.replace_extension(std::string(io::to_string(*format)));
  return name.string();
}

namespace {

// Whether every "uri" key of the text names a data: URI, found without parsing: parsing a
// .gltf with a 250 MiB data URI took 4x its size (the lexer's buffer and the string). Without
// \u escapes a key can only be spelled "uri" literally, and a quote inside a string is escaped.
bool only_data_uris(std::string_view text) {
  if (text.find("\\u") != std::string_view::npos) return false;
  for (std::size_t at = text.find("\"uri\""); at != std::string_view::npos; at = text.find("\"uri\"", at + 5)) {
    std::size_t i = text.find_first_not_of(" \t\r\n", at + 5);
    if (i == std::string_view::npos || text[i] != ':') continue;  // a value, not a key
    i = text.find_first_not_of(" \t\r\n", i + 1);
    if (i == std::string_view::npos || text.compare(i, 6, "\"data:") != 0) return false;
  }
  return true;
}

}  // namespace

bool has_external_uris(std::string_view gltf_text) {
  if (only_data_uris(gltf_text)) return false;
  const json j = json::parse(gltf_text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return false;
  for (const char* key : {"buffers", "images"})
    for (const auto& item : j.value(key, json::array()))
      if (item.is_object() && item.contains("uri") && item["uri"].is_string() &&
          !item["uri"].get<std::string>().starts_with("data:"))
        return true;
  return false;
}

std::vector<OutputFile> output_files(std::string bytes, io::Format format, const std::string& path, bool data_beside) {
  namespace fs = std::filesystem;
  std::vector<OutputFile> files;
  if (format == io::Format::Gltf && data_beside) {
    json j = json::parse(bytes);
    const fs::path out(path);
    const std::string stem = out.stem().string();
    for (const char* key : {"buffers", "images"}) {
      if (!j.contains(key)) continue;
      for (std::size_t i = 0; i < j[key].size(); ++i) {
        json& item = j[key][i];
        if (!item.contains("uri") || !item["uri"].is_string()) continue;
        const std::string uri = item["uri"].get<std::string>();
        const std::size_t comma = uri.find(',');
        if (!uri.starts_with("data:") || comma == std::string::npos) continue;
        const std::string mime = uri.substr(5, uri.find(';') - 5);
        const std::string name = stem + (std::string(key) == "buffers" ? "_" + std::to_string(i) + ".bin"
                                                                       : "_image" + std::to_string(i) +
                                                                             (mime == "image/jpeg"   ? ".jpg"
                                                                              : mime == "image/webp" ? ".webp"
                                                                                                     : ".png"));
        files.push_back({(out.parent_path() / name).string(), base64_decode(std::string_view(uri).substr(comma + 1))});
        item["uri"] = name;
      }
    }
    bytes = j.dump(2);
  }
  files.push_back({path, std::move(bytes)});
  return files;
}

}  // namespace mdn::service
