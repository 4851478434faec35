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
  std::string family;  // "cad", "organic", "cgal"
  TriMesh mesh;
};

// Every shape name of the corpus, in a fixed order (CGAL names only if `cgal_dir` has them).
std::vector<std::string> shape_names(const std::filesystem::path& cgal_dir);
// Builds one shape (throws std::invalid_argument for an unknown name).
Shape make_shape(const std::string& name, const std::filesystem::path& cgal_dir);

// The noise configurations, e.g. "clean", "along:0.3", "iso:0.2", "dir:0.15",
// "impulse:0.1:0.6" (fraction, sigma), "scan:0.2", "mix:0.1:0.1" (along sigma, impulse share).
// Levels are in mean edge lengths.
std::vector<std::string> noise_names();
// The configurations a shape gets: all of them, or every fifth for shapes over 12,000 faces.
std::vector<std::string> noise_names_for(const Shape& shape);
// The noisy positions of `clean` under `noise`, seeded by `seed`.
Vertices apply_noise(const TriMesh& clean, const std::string& noise, std::uint64_t seed);

// True for the CGAL demo meshes the corpus trains on (tests/bench/tune_bench keeps the others
// for validation).
bool is_training_cgal_mesh(const std::string& name);

// FNV-1a of a string: the noise seed of a case and the split of a shape.
std::uint64_t hash_name(const std::string& text);
// "train" or "holdout" (about one shape in five, by a hash of the name): never mixed.
std::string split_of(const std::string& shape);

}  // namespace mdn::train
