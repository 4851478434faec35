// A job's output as files: one rule for every path that writes or names one, so they all give
// the same files. The command-line tool's single run (IN OUT) and its --out-dir batch write
// output_files(); the server names its result with output_file_name().
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "core/io/document.h"

namespace mdn::service {

// A result's file name from its input's: the input's name with the extension of `format` when
// one is asked for ("scan.ply" to glb: "scan.glb"), else the input's name unchanged; an empty
// input name (the server's request bodies) gives "denoised.<format>".
std::string output_file_name(std::string_view input_name, std::optional<io::Format> format);

// Whether a .gltf references files (a buffer or image uri that is not a data: URI).
bool has_external_uris(std::string_view gltf_text);

struct OutputFile {
  std::string path;
  std::string bytes;
};

// The files a job's encoded output makes at `path`. A .gltf output whose input kept its data
// beside it (`data_beside`: a .gltf input with has_external_uris) keeps that layout: each
// embedded buffer and image becomes `path`'s stem + "_<i>.bin" / "_image<i>.<ext>" in its
// folder, referenced by that relative name. Every other output is the one file. The main file
// comes last, so whoever finds it finds its data already written.
std::vector<OutputFile> output_files(std::string bytes, io::Format format, const std::string& path, bool data_beside);

}  // namespace mdn::service
