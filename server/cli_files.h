// The files of meshdenoise: reading and writing them ("-" is standard input or output), the
// --params / --add-noise arguments that are inline JSON or a file, and the files a .gltf keeps
// beside itself.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "core/io/document.h"

namespace mdn::cli {

// A file cannot be read or written, is malformed or not a valid mesh (exit code 3).
class FileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// "-" names standard input where a file is read (IN, GT, a --params file) and standard output
// where OUT is written, as Unix filters do; a file called "-" is "./-".
constexpr std::string_view kStdio = "-";

std::string read_file(const std::string& path);
// Writes OUT through a temporary file in the same folder and a rename, so a failure (disk
// full, Ctrl-C) never leaves a truncated OUT behind or clobbers an existing one. Special files
// (/dev/stdout, pipes) and symbolic links are written in place.
void write_file(const std::string& path, const std::string& bytes);

// --params / --add-noise take inline JSON (anything starting with '{' after blanks) or a file.
std::string json_argument(const std::string& option, const std::string& value);

// A .gltf read from a file may reference buffers and images beside it (relative URIs inside
// its folder); from standard input, or in any other format, nothing outside the bytes is read.
std::optional<std::string> resource_dir(const std::string& path, io::Format format);
// Whether a .gltf references files (a buffer or image uri that is not a data: URI).
bool has_external_uris(const std::string& gltf_text);
// The files a .gltf output writes beside itself when its input had its data beside it: each
// embedded buffer and image becomes OUT's stem + "_<i>.bin" / "_image<i>.<ext>" in OUT's
// folder, referenced by that relative name. Returns the rewritten .gltf and the files.
std::string externalize(const std::string& gltf_text, const std::string& out_path,
                        std::vector<std::pair<std::string, std::string>>& files);

}  // namespace mdn::cli
