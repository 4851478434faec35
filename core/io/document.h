// Format adapters: bytes <-> meshes to denoise. The algorithms never include this folder.
//
// A MeshDocument is a decoded asset. It exposes the triangle surfaces to denoise (for glTF:
// one welded surface per mesh, whatever its instancing; for OFF/OBJ/PLY/DRC/STL: one surface)
// and re-encodes the asset after their positions were replaced, keeping everything else.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "core/errors.h"
#include "core/mesh.h"
#include "core/progress.h"

namespace mdn::io {

enum class Format { Off, Obj, Ply, Drc, Glb, Gltf, Stl };
std::string_view to_string(Format format);  // "off", "obj", "ply", "drc", "glb", "gltf", "stl"
std::optional<Format> format_from_string(std::string_view name);  // inverse of to_string, any case
std::optional<Format> format_from_extension(std::string_view path);  // by file name ending
std::optional<Format> sniff_format(std::string_view bytes);       // by content (magic numbers / keywords)
std::string_view media_type(Format format);  // model/gltf-binary, model/gltf+json, application/octet-stream ...

// The bytes are not a valid file of the format (truncated, inconsistent counts, bad JSON, ...).
// Maps to HTTP 400.
class FormatError : public InvalidMeshError {
 public:
  using InvalidMeshError::InvalidMeshError;
};
// Valid, but uses something we do not support (an extension, a primitive mode, an external
// URI). what() names it. Maps to HTTP 422.
class UnsupportedError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Declared or decoded sizes exceed Limits; what() names the limit. Maps to HTTP 413.
class LimitError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// glTF output compression. A decoded document records its input's (MeshDocument::compression:
// None, Draco or Meshopt); AsInput asks for that one again.
enum class Compression { AsInput, None, Draco, Meshopt };
std::string_view to_string(Compression compression);                      // "as_input", "none", "draco", "meshopt"
std::optional<Compression> compression_from_string(std::string_view name);  // inverse of to_string

struct Limits {
  std::int64_t max_faces = 5'000'000;
  std::int64_t max_vertices = 5'000'000;
  std::int64_t max_decoded_bytes = std::int64_t{1} << 30;  // total bytes any decoder may allocate
  // glTF: the scene's size, checked before tinygltf parses it (its JSON walk is recursive and
  // a node costs it about 1 KB, so 10^6 nodes in 12 MB of JSON would take 700 MB).
  int max_json_depth = 64;             // nesting of JSON objects and arrays (extras included)
  std::int64_t max_nodes = 100'000;    // entries of "nodes"
  std::int64_t max_accessors = 1'000'000;  // entries of "accessors" + "bufferViews"; primitives

  // Not a size: the job's time limit and DELETE. Polled (cancel_requested()) every
  // kCancelStride items of the decoders' loops (text lines, PLY rows, accessor elements, the
  // weld); true makes decode() throw CancelledError. Null: never cancelled. Draco's own
  // decoder cannot be interrupted: its work is bounded by the declared-size check instead.
  ProgressObserver* cancel = nullptr;
};

struct EncodeOptions {
  std::optional<Format> format;  // default: the input's container
  // glTF output compression: Draco (the library's default), None, Meshopt
  // (EXT_meshopt_compression with KHR_mesh_quantization, decision 70) or AsInput (the input's,
  // as glTF-Transform keeps what it read; the service's default). DRC is always Draco. What an
  // encode wrote comes back in Encoded::compression. The settings: output_settings.h.
  Compression compression = Compression::Draco;
  // Draco quantisation bits. Positions: [8, 30] (11 bits costs about 0.8 mm on a 2 m scan).
  // The other attributes: [1, 30], or 0 = stored losslessly. UVs, colours, joints and weights
  // default to 0, so they come back bit for bit (the assets' other data is untouched, and
  // so are they); NORMAL is recomputed from the denoised surface, so it is quantised.
  int position_bits = 16;
  int normal_bits = 10;
  int texcoord_bits = 0;
  int color_bits = 0;
  int generic_bits = 0;
  int compression_level = 7;     // Draco encoder speed/size trade-off, [0, 10] (10 = smallest)
  // Not a parameter: the job's time limit and DELETE, polled like Limits::cancel by the
  // encoders' loops (the Draco encoder itself runs to its end). Null: never cancelled.
  ProgressObserver* cancel = nullptr;
  // Not a parameter: the bound on the encoder's working memory (Draco's tables grow as 2^bits,
  // core/io/encode_check.h), the same as decoding's: the service sets Limits::max_decoded_bytes.
  std::int64_t max_memory_bytes = std::int64_t{1} << 30;
};

// What an encode wrote: the bytes, and the compression they hold (glTF: resolve_compression's
// choice; DRC: Draco; every other format: None). Callers read the compression here, nowhere else.
struct Encoded {
  std::string bytes;
  Compression compression = Compression::None;
  // glTF: what each surface's POSITION became ("mesh 0: POSITION written as unsigned short on
  // a 14-bit grid ..."), when it is not plain float32 or Draco.
  std::vector<std::string> notes = {};
};

class MeshDocument {
 public:
  virtual ~MeshDocument() = default;
  virtual Format format() const = 0;
  // Surfaces to denoise, in a stable order. Callers may replace their V (same #V).
  virtual std::vector<TriMesh>& surfaces() = 0;
  // Re-encodes the asset with the current surface positions.
  virtual Encoded encode(const EncodeOptions& options) const = 0;
  // Notes for the caller about what was changed besides positions (e.g. "TANGENT dropped").
  virtual std::vector<std::string> notes() const { return {}; }
  // Where each surface shows in the asset's scene: the matrices (4x4, homogeneous) that take
  // its coordinates to the scene's. glTF: the world matrix of every node of the default scene
  // (of every root node when the asset has no scene) that instances its mesh, in depth-first
  // order; EXT_mesh_gpu_instancing and skins are not applied. Empty for a surface that nothing
  // places and for formats without a scene (the default): those show as they are.
  virtual std::vector<std::vector<Eigen::Matrix4d>> placements() const { return {}; }
  // The input's compression (glTF: Draco if a primitive used KHR_draco_mesh_compression,
  // Meshopt if a buffer view used EXT_meshopt_compression; DRC: Draco; others None).
  virtual Compression compression() const { return Compression::None; }
};

// The glTF compression an encode writes, given the options and the input's compression:
// `compression` (AsInput: `input`). The glTF writer calls it; a caller that must know before
// encoding (a check of the encoder's memory) may too.
Compression resolve_compression(const EncodeOptions& options, Compression input);

// How to decode, beyond the format. The service uses the defaults: nothing outside the bytes
// is ever read.
struct DecodeOptions {
  Limits limits;
  // glTF: the folder that buffers and images referenced by relative URI are read from (the
  // command-line tool sets it to the .gltf's folder). Unset, every external URI is an
  // UnsupportedError. Set, a URI with a scheme, an absolute path or one that leads out of the
  // folder ("..") is still an UnsupportedError, and the files read count against
  // limits.max_decoded_bytes. What was read is embedded: encode() writes data URIs.
  std::optional<std::string> resource_dir;
};

// Decodes bytes of the given format. Throws FormatError, UnsupportedError or LimitError.
std::unique_ptr<MeshDocument> decode(std::string_view bytes, Format format, const Limits& limits = {});
std::unique_ptr<MeshDocument> decode(std::string_view bytes, Format format, const DecodeOptions& options);
// The same, for a caller that is done with the bytes (every job: service::run_job): they are
// freed as soon as the decoder has read what it needs from them, at the latest before it
// returns. `bytes` is left empty, whether decoding succeeds or throws.
std::unique_ptr<MeshDocument> decode_owned(std::string&& bytes, Format format, const DecodeOptions& options);

}  // namespace mdn::io
