// The files of meshdenoise: reading and writing them ("-" is standard input or output), the
// --params / --add-noise arguments that are inline JSON or a file, and the files a .gltf keeps
// beside itself.
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

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

// Whether two paths name one file (the same path written differently, a link to it); "-" is
// never a file.
bool same_file(const std::string& a, const std::string& b);
// Refuses (UsageError, exit 2) writing OUT over IN unless `in_place` (then the usual temporary
// file and rename replace it). `where` prefixes the message ("--out-dir: ").
void check_not_input(const std::string& in_path, const std::string& out_path, bool in_place,
                     const std::string& where = {});

// The one writer of meshdenoise's outputs, single runs and batches alike: the files
// service::output_files() makes of a job's bytes at OUT (a .gltf whose input kept its data
// beside it, `in_data_beside`, keeps that layout), each through write_file; OUT's folder is
// created if missing, as --out-dir's is.
void write_output(const std::string& in_path, bool in_data_beside, const std::string& out_path, std::string out_bytes,
                  io::Format out_format);

}  // namespace mdn::cli
