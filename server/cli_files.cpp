#include "server/cli_files.h"

#include <unistd.h>

#include <cerrno>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <iterator>

#include <nlohmann/json.hpp>

#include "server/cli_options.h"

namespace mdn::cli {
namespace {

using nlohmann::json;

std::string read_stdin() {
  std::string bytes;
  char buffer[1 << 16];
  for (;;) {
    const ssize_t n = ::read(STDIN_FILENO, buffer, sizeof buffer);
    if (n == 0) return bytes;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileError(std::string("cannot read standard input: ") + std::strerror(errno));
    }
    bytes.append(buffer, static_cast<std::size_t>(n));
  }
}

void write_bytes(const std::string& path, const std::string& bytes, const std::string& shown) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
}

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

std::string read_file(const std::string& path) {
  if (path == kStdio) return read_stdin();
  std::error_code ec;
  if (std::filesystem::is_directory(path, ec)) throw FileError("cannot read " + path + ": it is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw FileError("cannot read " + path + ": " + std::strerror(errno));
  try {
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) throw FileError("cannot read " + path + ": " + std::strerror(errno));
    return bytes;
  } catch (const std::ios_base::failure& e) {  // libstdc++ throws from underflow on read errors
    throw FileError("cannot read " + path + ": " + e.what());
  }
}

void write_file(const std::string& path, const std::string& bytes) {
  namespace fs = std::filesystem;
  if (path == kStdio) {
    std::cout.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    std::cout.flush();
    if (!std::cout) throw FileError("cannot write standard output");
    return;
  }
  std::error_code ec;
  const fs::file_status status = fs::symlink_status(path, ec);
  if (fs::exists(status) && !fs::is_regular_file(status)) {
    if (fs::is_directory(status)) throw FileError("cannot write " + path + ": it is a directory");
    write_bytes(path, bytes, path);
    return;
  }
  const std::string partial = path + ".partial-" + std::to_string(::getpid());
  try {
    write_bytes(partial, bytes, path);
    fs::rename(partial, path);
  } catch (const fs::filesystem_error& e) {
    fs::remove(partial, ec);
    throw FileError("cannot write " + path + ": " + e.code().message());
  } catch (...) {
    fs::remove(partial, ec);
    throw;
  }
}

std::string json_argument(const std::string& option, const std::string& value) {
  const auto first = value.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && value[first] == '{') return value;
  try {
    return read_file(value);
  } catch (const FileError& e) {
    throw UsageError(option + ": not inline JSON, and " + e.what());
  }
}

std::optional<std::string> resource_dir(const std::string& path, io::Format format) {
  if (format != io::Format::Gltf || path == kStdio) return std::nullopt;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

bool has_external_uris(const std::string& gltf_text) {
  const json j = json::parse(gltf_text, nullptr, /*allow_exceptions=*/false);
  if (!j.is_object()) return false;
  for (const char* key : {"buffers", "images"})
    for (const auto& item : j.value(key, json::array()))
      if (item.is_object() && item.contains("uri") && item["uri"].is_string() &&
          !item["uri"].get<std::string>().starts_with("data:"))
        return true;
  return false;
}

std::string externalize(const std::string& gltf_text, const std::string& out_path,
                        std::vector<std::pair<std::string, std::string>>& files) {
  namespace fs = std::filesystem;
  json j = json::parse(gltf_text);
  const fs::path out(out_path);
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
      std::string name = stem + (std::string(key) == "buffers" ? "_" + std::to_string(i) + ".bin"
                                                                : "_image" + std::to_string(i) +
                                                                      (mime == "image/jpeg" ? ".jpg" : mime == "image/webp" ? ".webp" : ".png"));
      files.emplace_back((out.parent_path() / name).string(), base64_decode(std::string_view(uri).substr(comma + 1)));
      item["uri"] = name;
    }
  }
  return j.dump(2);
}

}  // namespace mdn::cli
