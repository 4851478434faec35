// A virtual depth camera (issue 48, item 1): range images of a clean shape with the published
// noise of two consumer sensor kinds, meshed as scanners mesh them, with a per-vertex ground
// truth. The corpus (corpus.h, the "scan_sl" and "scan_tof" noise kinds) and tune_bench's
// "scans" set build their depth-camera cases here.
//
// Frame: the camera looks along +z from the origin, x to the right, y down (image rows); a
// pixel's ray is ((u - cx) / f, (v - cy) / f, 1), so the parameter along it is the depth z.
// Units are metres: the noise terms are the sensors' own, so a shape must first be scaled to
// a real object's size (ScanPose).
//
// Ground truth (decision 58): a vertex of the clean mesh is its pixel's ray on the clean
// surface (the noise-free depth); the noisy vertex is the same ray at the depth the sensor
// reports. Noisy and clean therefore share faces, vertex order and lateral position.
#pragma once

#include <cstdint>
#include <vector>

#include "core/mesh.h"

namespace mdn::train {

enum class SensorKind {
  StructuredLight,  // Kinect v1 class: projected pattern, disparity by block matching
  TimeOfFlight,     // Kinect v2 class: continuous-wave phase measurement
};

// The native sensor and how it is sampled. Both presets are the sensors' published
// intrinsics; `stride` samples every stride-th native pixel in both directions (the noise
// stays the native sensor's: the disparity is quantised at native resolution).
struct RangeSensor {
  SensorKind kind = SensorKind::StructuredLight;
  int width = 640, height = 480;  // native pixels
  double focal_px = 580;          // native focal length, pixels
  int stride = 2;                 // 1..4: sampled image is width/stride x height/stride
  double baseline_m = 0.075;      // projector-camera baseline (structured light only), metres
  double max_incidence_deg = 75;  // pixels seen at a larger angle of incidence are lost
};
// Kinect v1: 640x480, f = 580 px, 7.5 cm baseline; sampled at 320x240 (stride 2), the
// resolution the two shared cores afford for a corpus of thousands of cases (the corpus's
// "scan_sl640" kinds set stride 1: real scans are meshed at 640x480, decision 93). Its disparity
// errors are correlated over the 9x9 native pixels of its matching window (decision 84).
RangeSensor kinect_v1();
// Kinect v2: 512x424, f = 365 px; sampled at its native resolution (stride 1).
RangeSensor kinect_v2();

// The published axial noise (standard deviation of the reported depth, metres) at depth z
// (metres) and angle of incidence theta (radians). Structured light: Nguyen, Izadi, Lovell
// 2012, sigma = 0.0012 + 0.0019 (z - 0.4)^2, plus 0.0001 / sqrt(z) * theta^2 / (pi/2 - theta)^2
// beyond 60 degrees of incidence.
// Time of flight: Fankhauser et al. 2015 (Kinect v2), sigma = 0.0015 - 0.0005 z + 0.0003 z^2
// + 0.0001 z^1.5 theta^2 / (pi/2 - theta)^2, about 1.3-1.7 mm from 0.5 to 2.5 m.
double axial_sigma(const RangeSensor& sensor, double z, double theta);
// The step between two adjacent depths the sensor can report at depth z (metres): structured
// light reports disparities in 1/8 pixel, so the step is z^2 / (8 b f) and grows with z^2;
// time of flight reports whole millimetres.
double depth_step(const RangeSensor& sensor, double z);
// The reported depth nearest to z (the quantisation above).
double quantise_depth(const RangeSensor& sensor, double z);

// One range image, row-major over the sampled pixels (index = row * cols + col).
struct RangeImage {
  int cols = 0, rows = 0;
  double cx = 0, cy = 0, focal = 0;  // of the sampled image, pixels
  std::vector<double> clean_depth;   // the pixel's ray on the clean surface; NaN: no surface
  std::vector<double> depth;         // what the sensor reports; NaN: pixel lost
  std::vector<double> incidence;     // angle of incidence at the clean hit, radians (NaN: none)
  // The ray of a sampled pixel at depth z (camera frame).
  Vec3 point(int col, int row, double z) const;
};

struct CaptureOptions {
  std::uint64_t seed = 1;
  // A wall facing the camera at this depth (metres) behind the object, as in a scanning
  // booth: it returns light (time-of-flight mixed pixels at silhouettes) but its own pixels
  // are cut away as background, the way a station segments the object. 0: no wall.
  double wall_depth_m = 0;
};

// Captures `scene` (a triangle mesh in the camera frame, metres). Deterministic: the same
// scene, sensor and options give the same image bit for bit. Structured light's axial and
// lateral draws are white noise on the native grid summed over a 9x9 window (decision 84):
// neighbouring pixels err together, the reported depth's deviation is still axial_sigma();
// time of flight's draws are independent per pixel.
RangeImage capture(const TriMesh& scene, const RangeSensor& sensor, const CaptureOptions& options);

// A meshed range image: clean and noisy positions of the same vertices and faces.
struct RangeScan {
  TriMesh clean;                    // vertices on their rays at the noise-free depth
  Vertices noisy;                   // the same vertices at the reported depth
  std::vector<std::int32_t> pixel;  // per vertex, its pixel in the image (row * cols + col)
};

// Meshes an image as scanners do (decision 59): two triangles per 2x2 block of reported
// pixels, split along the diagonal of smaller depth difference; no triangle with an edge
// across a depth jump (the depth difference exceeds jump_threshold(), on the reported or the
// noise-free depths); then components of fewer than max(20, 2% of the faces) faces dropped
// and unused vertices removed. Faces face the camera (counter-clockwise seen from it).
RangeScan mesh_range_image(const RangeImage& image, const RangeSensor& sensor);
// The largest depth difference (metres) an edge between neighbouring sampled pixels at mean
// depth z may span: four pixel footprints (a surface up to about 76 degrees from the view
// direction) plus four standard deviations of the noise and one quantisation step.
double jump_threshold(const RangeSensor& sensor, double z);

// Where the object is and how large (metres), and the seed of its orientation and the noise.
struct ScanPose {
  double object_size_m = 0.5;  // the longest side of the shape's bounding box after scaling
  double distance_m = 1.2;     // from the camera to the bounding box's centre, along the axis
  std::uint64_t seed = 1;      // a uniformly random rotation of the shape, and the noise draws
};

// One view of `shape` (any units; scaled to the pose's size) by `sensor`: placed, captured
// in front of a wall and meshed. Throws std::runtime_error if fewer than 100 faces remain.
RangeScan scan_shape(const TriMesh& shape, const RangeSensor& sensor, const ScanPose& pose);

// A turntable station's output (issue 48's fused variant): `views` captures of the shape turning
// about the camera's vertical axis in equal steps, seen from `elevation_deg` above, fused into
// a truncated signed distance volume (Curless and Levoy 1996, as KinectFusion does) and meshed
// by surface nets (decision 58). Noisy vertices are the fused surface's; there is no pixel to
// share, so each clean vertex is where the noisy one, moving along its smoothed normal, meets
// the same fusion of the noise-free depths (decision 99); `pixel` is empty.
// Positions in metres around the object's centre. The bottom, never seen, stays open.
struct FusedOptions {
  int views = 6;              // captures around the turntable, >= 1
  double elevation_deg = 25;  // the sensor above the turntable's plane
  int voxels_across = 48;     // voxel = object size / this, at least one pixel footprint
};
RangeScan fuse_scans(const TriMesh& shape, const RangeSensor& sensor, const ScanPose& pose,
                     const FusedOptions& options = {});

}  // namespace mdn::train
