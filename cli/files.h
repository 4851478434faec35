// The files of meshdenoise: reading and writing them ("-" is standard input or output), the
// --params / --add-noise arguments that are inline JSON or a file, and the files a .gltf keeps
// beside itself.
#pragma once

#include <cstdint>
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

// Reads a whole file, or standard input, of at most `max_bytes` (decision 61): a regular file
// larger than that is refused before it is read, anything else (a FIFO, /dev/zero, a pipe) as
// soon as it sends one byte more. Throws FileError naming the limit (--max-input).
std::string read_file(const std::string& path, std::int64_t max_bytes);
// Writes OUT through a temporary file and a rename, so a failure (disk full, Ctrl-C) never
// leaves a truncated OUT behind or clobbers an existing one. A symbolic link to a regular file
// is followed: the temporary file goes beside the link's final target and is renamed over it,
// so the link stays a link and its target is replaced whole (decision 61). Special files
// (/dev/stdout, pipes) are written in place, and so is a link that leads nowhere yet.
void write_file(const std::string& path, const std::string& bytes);

// --params / --add-noise take inline JSON (anything starting with '{' after blanks) or a file
// (read up to max_bytes).
std::string json_argument(const std::string& option, const std::string& value, std::int64_t max_bytes);

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
