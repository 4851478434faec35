// The training corpus of the trained parameter choice (core/auto/): clean shapes and the noise
// put on them. A case is named "SHAPE/NOISE" and is rebuilt from its name alone (shapes are
// made in code or read from CGAL's demo data, noise is seeded by a hash of the name), so the
// label and descriptor tables can be computed separately and resumed.
//
// Rules (issue 31): no shape of the field's standard test sets and no mesh that tune_bench
// treats as validation is ever a training shape; splits are by shape.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/mesh.h"

namespace mdn::train {

struct Shape {
  std::string name;
  std::string family;  // "cad", "organic", "rough", "cgal"
  TriMesh mesh;
};

// Every shape name of the corpus, in a fixed order (CGAL names only if `cgal_dir` has them).
std::vector<std::string> shape_names(const std::filesystem::path& cgal_dir);
// Builds one shape (throws std::invalid_argument for an unknown name).
Shape make_shape(const std::string& name, const std::filesystem::path& cgal_dir);

// The noise configurations, e.g. "clean", "along:0.3", "iso:0.2", "dir:0.15",
// "impulse:0.1:0.6" (fraction, sigma), "scan:0.2", "mix:0.1:0.1" (along sigma, impulse share).
// Levels are in mean edge lengths. Then the depth-camera kinds of scan_noise_names().
std::vector<std::string> noise_names();
// The depth-camera kinds (issue 48; decision 60): "scan_sl:SIZE:DIST" (structured light,
// Kinect v1 class) and "scan_tof:SIZE:DIST" (time of flight, Kinect v2 class), optionally
// ":POSE" (another pose at the same distance): the shape scaled to SIZE metres (its bounding
// box's longest side), seen from DIST metres by one view of range_scan.h's sensor. The case's
// clean mesh is the scan's, not the shape's. "fused_sl:SIZE:DIST" and "fused_tof:SIZE:DIST"
// (a turntable's six views fused, fuse_scans) are built by make_noisy_case and scan_case but
// are not in the list (decisions 60 and 99).
std::vector<std::string> scan_noise_names();
// The fused turntable kinds tune_bench's "fused" set measures (one per sensor).
std::vector<std::string> fused_noise_names();
bool is_scan_noise(const std::string& noise);
// The configurations a shape gets: all of them, or every fifth of the others and every
// depth-camera kind for shapes over 12,000 faces (a scan resamples the shape, so its cost does
// not grow with the shape's faces).
std::vector<std::string> noise_names_for(const Shape& shape);
// The noisy positions of `clean` under `noise`, seeded by `seed` (not the depth-camera kinds,
// whose mesh is not the shape's: make_noisy_case).
Vertices apply_noise(const TriMesh& clean, const std::string& noise, std::uint64_t seed);

// One case's pair: the clean mesh and the noisy positions of its vertices (same faces, same
// order). The shape's mesh and apply_noise's positions, or for a depth-camera kind the scan's
// noise-free and reported vertices. Seeded by `seed` (the case's name hashed).
struct NoisyCase {
  TriMesh clean;
  Vertices noisy;
};
NoisyCase make_noisy_case(const Shape& shape, const std::string& noise, std::uint64_t seed);
// The depth-camera case of any mesh: the same scan as make_noisy_case's (tune_bench's "scans"
// set builds its cases here).
NoisyCase scan_case(const TriMesh& mesh, const std::string& noise, std::uint64_t seed);

// True for the CGAL demo meshes the corpus trains on (tests/bench/tune_bench keeps the others
// for validation).
bool is_training_cgal_mesh(const std::string& name);

// FNV-1a of a string: the noise seed of a case and the split of a shape.
std::uint64_t hash_name(const std::string& text);
// "train" or "holdout" (about one shape in five, by a hash of the name): never mixed.
std::string split_of(const std::string& shape);

}  // namespace mdn::train
