// Wall-clock milliseconds of one job's steps, and the one table that names them. Everything
// that shows timings (the job's JSON, the Server-Timing header, the stored summary in Redis)
// loops over kTimingFields, so a new timing is one member and one row here.
#pragma once

#include <string_view>

#include "core/auto/denoise.h"

namespace mdn::service {

// Summed over the document's surfaces; they vary between runs.
struct JobTimings {
  double decode_ms = 0;       // bytes -> document
  double setup_ms = 0;        // validation, normalisation, topology
  double measure_ms = 0;      // auto / search modes: measuring the input and choosing parameters
  double initial_ms = 0;      // Eq. 1
  double region_ms = 0;       // Sec. 4.2 detection, K-means and Eq. 2
  double anisotropic_ms = 0;  // Eq. 3-4
  double normal_ms = 0;       // Eq. 6-7
  double vertex_ms = 0;       // Eq. 8
  double denoise_ms = 0;      // every surface's whole pipeline (the stages above and the rest)
  double encode_ms = 0;       // document -> bytes
};

struct TimingField {
  std::string_view name;  // key in "timings_ms" (proto/report.schema.json)
  double JobTimings::*member;
  double StageTimings::*stage;     // the core pipeline's figure summed into it; nullptr if none
  std::string_view server_timing;  // the Server-Timing metric it adds to; empty if not shown
};

// In the order the steps run.
inline constexpr TimingField kTimingFields[] = {
    {"decode", &JobTimings::decode_ms, nullptr, "decode"},
    {"setup", &JobTimings::setup_ms, &StageTimings::setup_ms, "prefilter"},
    {"measure", &JobTimings::measure_ms, &StageTimings::measure_ms, ""},
    {"initial_prefilter", &JobTimings::initial_ms, &StageTimings::initial_ms, "prefilter"},
    {"region_prefilter", &JobTimings::region_ms, &StageTimings::region_ms, "prefilter"},
    {"anisotropic_prefilter", &JobTimings::anisotropic_ms, &StageTimings::anisotropic_ms, "prefilter"},
    {"normal_filter", &JobTimings::normal_ms, &StageTimings::normal_ms, "normal"},
    {"vertex_update", &JobTimings::vertex_ms, &StageTimings::vertex_ms, "vertex"},
    {"denoise", &JobTimings::denoise_ms, nullptr, ""},
    {"encode", &JobTimings::encode_ms, nullptr, "encode"},
};

// Adds one surface's pipeline figures.
inline void add_stage_timings(JobTimings& sum, const StageTimings& stage) {
  for (const TimingField& f : kTimingFields)
    if (f.stage) sum.*f.member += stage.*f.stage;
}

}  // namespace mdn::service
