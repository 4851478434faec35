#include "cli/files.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>

#include "cli/options.h"
#include "service/output_files.h"

namespace mdn::cli {
namespace {

std::string too_large(const std::string& what, std::int64_t max_bytes) {
  return "cannot read " + what + ": it holds more than " + std::to_string(max_bytes) +
         " bytes (the limit of --max-input)";
}

// Reads fd to its end straight into the string (a regular file's size is known up front, so it
// is one read of the whole file), never holding more than max_bytes + 1 bytes: one byte past
// the limit is enough to refuse the input. `what` names the source in errors.
std::string read_all(int fd, const std::string& what, std::size_t size_hint, std::int64_t max_bytes) {
  const auto cap = static_cast<std::size_t>(max_bytes) + 1;
  std::string bytes(std::min(std::max<std::size_t>(size_hint + 1, 1 << 16), cap), '\0');
  std::size_t length = 0;
  for (;;) {
    if (length == bytes.size()) {
      if (length >= cap) throw FileError(too_large(what, max_bytes));
      bytes.resize(std::min(bytes.size() * 2, cap));
    }
    const ssize_t n = ::read(fd, bytes.data() + length, bytes.size() - length);
    if (n == 0) break;
    if (n < 0) {
      if (errno == EINTR) continue;
      throw FileError("cannot read " + what + ": " + std::strerror(errno));
    }
    length += static_cast<std::size_t>(n);
  }
  if (length > static_cast<std::size_t>(max_bytes)) throw FileError(too_large(what, max_bytes));
  bytes.resize(length);
  return bytes;
}

void write_bytes(const std::string& path, const std::string& bytes, const std::string& shown) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.close();
  if (!out) throw FileError("cannot write " + shown + ": " + std::strerror(errno));
}

}  // namespace

std::string read_file(const std::string& path, std::int64_t max_bytes) {
  if (path == kStdio) return read_all(STDIN_FILENO, "standard input", 0, max_bytes);
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) throw FileError("cannot read " + path + ": " + std::strerror(errno));
  struct stat info {};
  if (::fstat(fd, &info) == 0 && S_ISDIR(info.st_mode)) {
    ::close(fd);
    throw FileError("cannot read " + path + ": it is a directory");
  }
  const std::size_t size_hint = S_ISREG(info.st_mode) ? static_cast<std::size_t>(info.st_size) : 0;
  if (S_ISREG(info.st_mode) && info.st_size > max_bytes) {
    ::close(fd);
    throw FileError(too_large(path, max_bytes));
  }
  try {
    std::string bytes = read_all(fd, path, size_hint, max_bytes);
    ::close(fd);
    return bytes;
  } catch (...) {
    ::close(fd);
    throw;
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
  const fs::file_status link = fs::symlink_status(path, ec);
  const fs::file_status status = fs::status(path, ec);  // what a link leads to
  if (fs::is_directory(status)) throw FileError("cannot write " + path + ": it is a directory");
  if (fs::exists(link) && !fs::is_regular_file(status)) {
    write_bytes(path, bytes, path);  // a device, a pipe, a link that leads nowhere yet
    return;
  }
  // Decision 61: a link is replaced at its final target, never truncated through.
  ec.clear();
  const fs::path target = fs::is_symlink(link) ? fs::canonical(path, ec) : fs::path(path);
  if (ec) throw FileError("cannot write " + path + ": " + ec.message());
  const std::string partial = target.string() + ".partial-" + std::to_string(::getpid());
  try {
    write_bytes(partial, bytes, path);
    if (fs::exists(status)) fs::permissions(partial, status.permissions(), fs::perm_options::replace);
    fs::rename(partial, target);
  } catch (const fs::filesystem_error& e) {
    fs::remove(partial, ec);
    throw FileError("cannot write " + path + ": " + e.code().message());
  } catch (...) {
    fs::remove(partial, ec);
    throw;
  }
}

std::string json_argument(const std::string& option, const std::string& value, std::int64_t max_bytes) {
  const auto first = value.find_first_not_of(" \t\r\n");
  if (first != std::string::npos && value[first] == '{') return value;
  try {
    return read_file(value, max_bytes);
  } catch (const FileError& e) {
    throw UsageError(option + ": not inline JSON, and " + e.what());
  }
}

std::optional<std::string> resource_dir(const std::string& path, io::Format format) {
  if (format != io::Format::Gltf || path == kStdio) return std::nullopt;
  const std::filesystem::path parent = std::filesystem::path(path).parent_path();
  return parent.empty() ? std::string(".") : parent.string();
}

bool same_file(const std::string& a, const std::string& b) {
  namespace fs = std::filesystem;
  if (a == kStdio || b == kStdio) return false;
  std::error_code ec;
  if (fs::exists(a, ec) && fs::exists(b, ec)) return fs::equivalent(a, b, ec);
  auto key = [](const std::string& path) {
    std::error_code error;
    const fs::path canonical = fs::weakly_canonical(fs::absolute(path), error);
    return error ? fs::absolute(path).lexically_normal() : canonical;
  };
  return key(a) == key(b);
}

void check_not_input(const std::string& in_path, const std::string& out_path, bool in_place, const std::string& where) {
  if (in_place || !same_file(in_path, out_path)) return;
  throw UsageError(where + out_path + " is the input " + in_path +
                   ": it would be overwritten; give --in-place to replace it (written to a temporary file, then "
                   "renamed), or choose another output");
}

void write_output(const std::string& in_path, bool in_data_beside, const std::string& out_path, std::string out_bytes,
                  io::Format out_format) {
  namespace fs = std::filesystem;
  const bool data_beside = out_path != kStdio && in_path != kStdio && in_data_beside;
  if (out_path != kStdio) {
    const fs::path folder = fs::path(out_path).parent_path();
    std::error_code ec;
    if (!folder.empty() && !fs::is_directory(folder)) {
      fs::create_directories(folder, ec);
      if (!fs::is_directory(folder))
        throw FileError("cannot create the folder " + folder.string() + " for " + out_path + ": " +
                        (ec ? ec.message() : std::string("it is not a directory")));
    }
  }
  for (auto& file : service::output_files(std::move(out_bytes), out_format, out_path, data_beside))
    write_file(file.path, file.bytes);
}

}  // namespace mdn::cli
