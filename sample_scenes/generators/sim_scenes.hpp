#pragma once
// The paper's five benchmarks (section 6.2, Table 1) as simulated scenes: skirt, cloth on a
// ball, letters in a bowl, 200 letters through a funnel onto a ramp, breaking objects. Each is
// a position-based dynamics run (pbd.hpp) sampled into frames; the same options give the same
// bytes everywhere. Frame k of F is taken at substep floor(k S / (F - 1)) of the scene's S
// substeps, so every frame count shows the same motion, and --frames 1 (the rest state at
// t = 0) costs no simulation.
#include "sample_scenes/generators/scene_files.hpp"

#include <cstdint>

namespace vproxq::gen {

/// A skirt: a flared tube of cloth hanging from a waist ring on a body that twists and sways,
/// over two swinging legs (capsules, written as objects too).
struct SkirtOptions {
  int segments = 120;  ///< vertices around the skirt
  int rings = 51;      ///< vertex rings from waist to hem: 2 segments (rings - 1) triangles
  int frames = 40;
  std::uint64_t seed = 1;
};

/// A square cloth falling onto a moving, spinning ball (written as an object) over the ground
/// (static): it drapes, wraps the ball and folds onto itself.
struct ClothBallOptions {
  int resolution = 88;  ///< vertices per side: 2 (resolution - 1)^2 triangles
  int frames = 40;
  std::uint64_t seed = 1;
};

/// Soft letter-like shapes (swept tubes, "siggraph06") falling into a bowl (static).
struct BowlOptions {
  int objects = 10;
  int around = 8;   ///< vertices around each tube
  int along = 28;   ///< rings along each stroke: 2 around along triangles per letter
  int frames = 40;
  std::uint64_t seed = 1;
};

/// Soft letters crowding through a funnel onto a ramp (funnel, ramp and floor static).
struct FunnelOptions {
  int objects = 200;
  int around = 6;
  int along = 15;
  int frames = 40;
  std::uint64_t seed = 1;
};

/// Box-shaped objects pre-cut into box pieces, dropped onto the ground (static); each breaks
/// into its pieces when it first touches the ground.
struct BreakingOptions {
  int objects = 14;
  int cells = 4;  ///< grid cells along each side of a piece
  int frames = 40;
  std::uint64_t seed = 1;
};

void generate_skirt(const SkirtOptions& options, SceneWriter& out);
void generate_cloth_ball(const ClothBallOptions& options, SceneWriter& out);
void generate_bowl(const BowlOptions& options, SceneWriter& out);
void generate_funnel(const FunnelOptions& options, SceneWriter& out);
void generate_breaking(const BreakingOptions& options, SceneWriter& out);

}  // namespace vproxq::gen
