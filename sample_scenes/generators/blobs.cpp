#include "sample_scenes/generators/blobs.hpp"

#include <algorithm>
#include <array>
#include <tuple>

namespace vproxq::gen {
namespace {

// Scene constants, in scene units (a mean blob radius is 0.9).
constexpr double kSpacing = 2.5;          ///< lattice spacing of the start positions
constexpr double kJitter = 0.06;          ///< start jitter per axis, fraction of kSpacing
constexpr double kRadiusMin = 0.7;        ///< blob radii are uniform in [min, max)
constexpr double kRadiusMax = 1.1;
constexpr int kWaves = 3;                 ///< sine terms of the radial deformation
constexpr double kWaveAmplitudeMin = 0.03;  ///< per term, relative to the radius: the sum
constexpr double kWaveAmplitudeMax = 0.06;  ///< stays below 0.18, so radii stay positive
constexpr double kSqueeze = 0.30;         ///< lateral shrink at t = 1 for the lowest layer
constexpr double kShorten = 0.10;         ///< vertical shrink of the column at t = 1
constexpr double kSwirl = 0.8;            ///< rotation (radians) of a mid-height layer at t = 1
constexpr double kWobbleMax = 0.10;       ///< centre oscillation amplitude per axis

/// Lattice points (ix, iy) of one layer: the smallest disc x^2 + y^2 <= R2 holding at least
/// `want` points, ordered from the axis outwards (then by iy, ix), so a partly filled top
/// layer is centred. Integer arithmetic only.
std::vector<std::array<int, 2>> layer_points(int want) {
  for (int r2 = 0;; ++r2) {
    std::vector<std::tuple<int, int, int>> pts;  // (ix^2 + iy^2, iy, ix)
    int m = 0;
    while ((m + 1) * (m + 1) <= r2) ++m;
    for (int iy = -m; iy <= m; ++iy)
      for (int ix = -m; ix <= m; ++ix)
        if (ix * ix + iy * iy <= r2) pts.emplace_back(ix * ix + iy * iy, iy, ix);
    if (static_cast<int>(pts.size()) < want) continue;
    std::sort(pts.begin(), pts.end());
    std::vector<std::array<int, 2>> out;
    for (const auto& [d2, iy, ix] : pts) out.push_back({ix, iy});
    return out;
  }
}

}  // namespace

BlobsScene make_blobs(const BlobsOptions& options) {
  BlobsScene scene;
  scene.options = options;
  scene.sphere = geodesic_sphere(options.frequency);

  // A column about as tall as it is wide: k layers of about k^2 blobs, k = ceil(cbrt(N)).
  int k = 1;
  while (k * k * k < options.objects) ++k;
  const auto slots = layer_points(k * k);
  const int per_layer = static_cast<int>(slots.size());
  const int layers = (options.objects + per_layer - 1) / per_layer;
  scene.column_height = kSpacing * layers;

  scene.blobs.resize(static_cast<size_t>(options.objects));
  for (int i = 0; i < options.objects; ++i) {
    Rng rng(options.seed, static_cast<std::uint64_t>(i));
    Blob& b = scene.blobs[static_cast<size_t>(i)];
    b.radius = rng.uniform(kRadiusMin, kRadiusMax);
    for (int w = 0; w < kWaves; ++w) {
      RadialWave wave;
      wave.amplitude = rng.uniform(kWaveAmplitudeMin, kWaveAmplitudeMax);
      wave.omega = rng.uniform(kPi, 3 * kPi);
      // Two statements: the operands of one expression may be evaluated in either order, and
      // the draws must happen in the same order with every compiler. (Braced lists, used
      // below, are evaluated left to right.)
      const double wave_number = rng.uniform(1.0, 2.5);
      wave.wave = wave_number * rng.unit_vector();
      wave.phase = rng.uniform(0, kTwoPi);
      b.waves.push_back(wave);
    }
    const auto& slot = slots[static_cast<size_t>(i % per_layer)];
    const int layer = i / per_layer;
    const V3 jitter{rng.uniform(-kJitter, kJitter), rng.uniform(-kJitter, kJitter),
                    rng.uniform(-kJitter, kJitter)};
    b.start = kSpacing * V3{slot[0] + jitter.x, slot[1] + jitter.y, (layer + 0.5) + jitter.z};
    b.height = std::clamp(b.start.z / scene.column_height, 0.0, 1.0);
    b.wobble_amplitude = {rng.uniform(0, kWobbleMax), rng.uniform(0, kWobbleMax),
                          rng.uniform(0, kWobbleMax)};
    b.wobble_frequency = {rng.uniform(0.5, 1.5), rng.uniform(0.5, 1.5), rng.uniform(0.5, 1.5)};
    b.wobble_phase = {rng.uniform(0, kTwoPi), rng.uniform(0, kTwoPi), rng.uniform(0, kTwoPi)};
  }
  return scene;
}

double frame_time(const BlobsOptions& options, int frame) {
  return options.frames > 1 ? static_cast<double>(frame) / (options.frames - 1) : 0.0;
}

std::vector<V3> blob_positions(const BlobsScene& scene, std::size_t index, double t) {
  const Blob& b = scene.blobs[index];

  // Centre: squeeze towards the axis (more at the bottom), swirl (faster higher up),
  // shorten and sink the column, plus the blob's own wobble.
  const double squeeze = 1 - kSqueeze * t * (1 - 0.5 * b.height);
  const double angle = kSwirl * t * (0.5 + b.height);
  const double c = det_cos(angle), s = det_sin(angle);
  V3 centre{squeeze * (c * b.start.x - s * b.start.y), squeeze * (s * b.start.x + c * b.start.y),
            b.start.z * (1 - kShorten * t) - kSpacing * t};
  auto wobble = [t](double amplitude, double frequency, double phase) {
    return amplitude * det_sin(kTwoPi * frequency * t + phase);
  };
  centre = centre + V3{wobble(b.wobble_amplitude.x, b.wobble_frequency.x, b.wobble_phase.x),
                       wobble(b.wobble_amplitude.y, b.wobble_frequency.y, b.wobble_phase.y),
                       wobble(b.wobble_amplitude.z, b.wobble_frequency.z, b.wobble_phase.z)};

  std::vector<V3> out;
  out.reserve(scene.sphere.directions.size());
  for (const V3& u : scene.sphere.directions) {
    double r = 1;
    for (const RadialWave& w : b.waves)
      r += w.amplitude * det_sin(w.omega * t + dot(w.wave, u) + w.phase);
    out.push_back(centre + (b.radius * r) * u);
  }
  return out;
}

}  // namespace vproxq::gen
