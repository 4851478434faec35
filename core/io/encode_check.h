// The validation step between decode and encode: what an encoder will quantise or pack, and
// what it will cost, is checked before any encoder runs (core/io/README.md, "Encoders never
// crash"). The service calls check_encode() right after decoding, before any denoising work
// (service/job_runner.cpp), so a job whose output cannot be written fails in milliseconds; the
// encoders repeat the checks that depend on their exact input (check_draco_encodable).
#pragma once

#include <cstdint>
#include <vector>

#include "core/io/document.h"

namespace mdn::io {

// Draco's encoder builds its entropy coder's frequency and probability tables over every
// symbol a quantised attribute can take, 2^bits of them: measured 2.3 to 12.8 bytes per
// 2^bits on 4 to 60,000 faces (most at compression level 10, whose prediction schemes keep
// more), so 16 bytes per 2^bits bounds it. Plus what the encoder holds per face.
inline constexpr std::int64_t kDracoBytesPerSymbol = 16;
inline constexpr std::int64_t kDracoBytesPerFace = 192;

// The Draco encoder's working memory for `faces` triangles with `options`: the tables of the
// largest quantisation setting in use (positions always; the others when not 0) and the
// per-face state. Saturates instead of overflowing.
std::int64_t draco_encode_bytes(const EncodeOptions& options, std::int64_t faces);

// Whether `output` (a container, and for glTF the compression resolved by
// resolve_compression) is written by Draco's encoder.
bool writes_draco(Format output, Compression compression);

// Checks that `doc` can be encoded with `options` (its format resolved) within `limits`; the
// settings' ranges were checked where the request was parsed (output_settings.h):
//  - every surface position finite (a non-finite one would be written as text "nan" or "inf"
//    that no reader takes back), UnsupportedError;
//  - if the output is Draco: draco_encode_bytes over every surface's faces against
//    limits.max_decoded_bytes (the same bound as decoding), UnsupportedError (HTTP 422) that
//    names the setting to lower.
// What each writer's number types can hold is checked by the writer itself, before it writes.
void check_encode(MeshDocument& doc, const EncodeOptions& options, const Limits& limits);

}  // namespace mdn::io
