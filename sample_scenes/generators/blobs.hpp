#pragma once
// The "blobs" scene: many deforming blobs squeezed through a narrowing, swirling funnel
// (the paper's "200 objects through a funnel" benchmark, section 6).
#include "sample_scenes/generators/det_math.hpp"
#include "sample_scenes/generators/geodesic_sphere.hpp"

#include <cstdint>
#include <vector>

namespace vproxq::gen {

struct BlobsOptions {
  int objects = 200;
  int frequency = 3;  ///< geodesic frequency: 20 f^2 triangles per blob
  int frames = 5;
  std::uint64_t seed = 1;
};

/// One sine term of a blob's radial deformation: amplitude * sin(omega t + dot(wave, u) + phase)
/// for the vertex direction u.
struct RadialWave {
  double amplitude = 0;  ///< relative to the blob's radius
  double omega = 0;      ///< radians per unit of animation time
  V3 wave;               ///< spatial frequency (radians per unit of direction)
  double phase = 0;
};

/// Everything drawn for one blob; its shape and place at any time follow from these.
struct Blob {
  double radius = 1;
  std::vector<RadialWave> waves;
  V3 start;               ///< centre at t = 0
  double height = 0;      ///< start height as a fraction of the column height, in [0, 1]
  V3 wobble_amplitude;    ///< small per-axis oscillation of the centre
  V3 wobble_frequency;    ///< cycles over the whole animation
  V3 wobble_phase;
};

struct BlobsScene {
  BlobsOptions options;
  UnitSphereMesh sphere;  ///< shared topology (every blob has the same faces)
  std::vector<Blob> blobs;
  double column_height = 0;
};

/// Draws the scene from options.seed. Blobs start on a jittered lattice inside a cylinder,
/// lowest layer first, at centre spacing 2.5 (mean radius 0.9, so neighbours are about half a
/// radius apart and the largest ones already touch).
BlobsScene make_blobs(const BlobsOptions& options);

/// Animation time of frame k: t = k / (frames - 1) in [0, 1] (t = 0 for a single frame), so
/// every frame count shows the whole squeeze.
double frame_time(const BlobsOptions& options, int frame);

/// Vertex positions of blob `b` at time t in [0, 1], in the sphere's vertex order.
/// The centre sinks by one lattice spacing, is squeezed towards the axis (lower blobs more:
/// lateral scale 1 - 0.3 t (1 - 0.5 h) for start height h) while the column shortens by 10%
/// and the layers swirl at different rates; each vertex sits at radius
/// r (1 + sum of the waves) along its direction (at most +-18%, so the blob stays star-shaped
/// and never intersects itself).
std::vector<V3> blob_positions(const BlobsScene& scene, std::size_t b, double t);

}  // namespace vproxq::gen
