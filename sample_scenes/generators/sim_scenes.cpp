#include "sample_scenes/generators/sim_scenes.hpp"

#include "sample_scenes/generators/geodesic_sphere.hpp"
#include "sample_scenes/generators/pbd.hpp"
#include "sample_scenes/generators/shapes.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <string>

namespace vproxq::gen {
namespace {

/// Runs the scene's `substeps` substeps of length dt and calls emit(k, t) for frame k at
/// substep floor(k substeps / (frames - 1)). step(t) advances the world from t to t + dt.
template <typename Step, typename Emit>
void run_schedule(int frames, long long substeps, double dt, Step&& step, Emit&& emit) {
  long long done = 0;
  for (int k = 0; k < frames; ++k) {
    const long long at = frames > 1 ? static_cast<long long>(k) * substeps / (frames - 1) : 0;
    for (; done < at; ++done) step(static_cast<double>(done) * dt);
    emit(k, static_cast<double>(done) * dt);
  }
}

/// Smooth start of a motion: 0 at t <= 0, 1 at t >= ramp (cubic smoothstep).
double ease_in(double t, double ramp) {
  const double s = std::clamp(t / ramp, 0.0, 1.0);
  return s * s * (3 - 2 * s);
}

std::vector<V3> particle_positions(const World& w, int first, std::size_t count) {
  return std::vector<V3>(w.x.begin() + first, w.x.begin() + first + static_cast<long>(count));
}

std::vector<V3> transformed(const std::vector<V3>& local, const M3& r, const V3& t) {
  std::vector<V3> out;
  out.reserve(local.size());
  for (const V3& p : local) out.push_back(t + r * p);
  return out;
}

// ---------------------------------------------------------------------------------------------
// Cloth

/// Compliances of the cloth constraints (XPBD, m/N with unit particle masses): stretch is
/// inextensible, shear a little soft, bending (distance to the second neighbours) soft, so
/// the cloth folds but does not crumple at the vertex scale.
constexpr double kStretchCompliance = 0;
constexpr double kShearCompliance = 1e-7;
constexpr double kBendCompliance = 2e-5;

/// Stretch, shear and bending constraints of a rows x cols particle grid starting at `first`
/// (vertex r * cols + c), wrapped around the columns for a tube.
void add_cloth_constraints(World& w, int first, int rows, int cols, bool wrap) {
  auto id = [&](int r, int c) { return first + r * cols + (wrap ? (c + cols) % cols : c); };
  const int last_col = wrap ? cols : cols - 1;
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < cols; ++c) {
      if (c < last_col) w.add_distance(id(r, c), id(r, c + 1), kStretchCompliance);
      if (r + 1 < rows) w.add_distance(id(r, c), id(r + 1, c), kStretchCompliance);
      if (r + 1 < rows && c < last_col) {
        w.add_distance(id(r, c), id(r + 1, c + 1), kShearCompliance);
        w.add_distance(id(r, c + 1), id(r + 1, c), kShearCompliance);
      }
      if (c + 1 < last_col || (wrap && cols > 4)) w.add_distance(id(r, c), id(r, c + 2), kBendCompliance);
      if (r + 2 < rows) w.add_distance(id(r, c), id(r + 2, c), kBendCompliance);
    }
}

/// Contact radius of cloth particles, relative to their spacing: two particles keep
/// 2 * 0.4 = 0.8 spacings apart, which never fights the stretch constraints of neighbours
/// and stops most layers from passing through each other.
constexpr double kClothRadius = 0.4;

// ---------------------------------------------------------------------------------------------
// Soft letters

/// A soft letter: its particles (the mesh vertices), edge constraints and one shape-matching
/// cluster whose rest shape breathes along the letter's own axes.
struct SoftLetter {
  int first = 0;  ///< first particle
  int cluster = 0;
  const Mesh* mesh = nullptr;
  std::string name;
  double breathe_amplitude = 0;
  std::array<double, 2> breathe_omega{};
  std::array<double, 2> breathe_phase{};
};

/// Shape matching per substep (at kLetterDt): soft enough that impacts dent the letters
/// visibly, stiff enough that they recover; edges keep the surface from crumpling locally.
constexpr double kLetterClusterStiffness = 0.03;
constexpr double kLetterEdgeCompliance = 2e-5;
/// Relative amplitude of the letters' own deformation (rest shape scaled along x and y).
constexpr double kLetterBreathe = 0.12;
constexpr double kLetterDt = 1.0 / 480;

SoftLetter add_letter(World& w, Rng& rng, const Mesh& mesh, const std::string& name,
                      const V3& centre, double radius) {
  SoftLetter s;
  s.mesh = &mesh;
  s.name = name;
  const M3 rot = random_rotation(rng);
  const int body = w.add_body(false);
  s.first = static_cast<int>(w.x.size());
  std::vector<int> ids;
  for (const V3& p : mesh.positions) ids.push_back(w.add_particle(centre + rot * p, 1.0, radius, body));
  for (const auto& [a, b] : mesh_edges(mesh.faces))
    w.add_distance(s.first + a, s.first + b, kLetterEdgeCompliance);
  // The cluster's rest shape is the unrotated mesh, so `scale` acts along the letter's axes.
  s.cluster = w.add_cluster(ids, kLetterClusterStiffness);
  ShapeCluster& c = w.clusters[static_cast<size_t>(s.cluster)];
  c.rest = mesh.positions;
  c.rotation = rot;
  s.breathe_amplitude = kLetterBreathe;
  for (int k = 0; k < 2; ++k) {
    s.breathe_omega[static_cast<size_t>(k)] = rng.uniform(kTwoPi * 0.6, kTwoPi * 1.4);
    s.breathe_phase[static_cast<size_t>(k)] = rng.uniform(0, kTwoPi);
  }
  return s;
}

void breathe(World& w, const SoftLetter& s, double t) {
  ShapeCluster& c = w.clusters[static_cast<size_t>(s.cluster)];
  c.scale = {1 + s.breathe_amplitude * det_sin(s.breathe_omega[0] * t + s.breathe_phase[0]),
             1 + s.breathe_amplitude * det_sin(s.breathe_omega[1] * t + s.breathe_phase[1]), 1};
}

/// Contact radius of letter particles: half the mean edge length, so neighbouring letters'
/// surfaces stay about one edge apart at the vertices.
double mean_edge_length(const Mesh& m) {
  double sum = 0;
  const auto edges = mesh_edges(m.faces);
  for (const auto& [a, b] : edges)
    sum += norm(m.positions[static_cast<size_t>(b)] - m.positions[static_cast<size_t>(a)]);
  return sum / static_cast<double>(edges.size());
}

/// Letter i of a letters scene: glyph `mesh`, named "letter<i>_<char>", contact radius half
/// its mean edge length.
SoftLetter add_scene_letter(World& w, Rng& rng, const Mesh& mesh, int i, const V3& start) {
  return add_letter(w, rng, mesh, std::string("letter") + std::to_string(i) + "_" + glyph_char(i),
                    start, 0.5 * mean_edge_length(mesh));
}

/// Simulates a letters scene for `duration` seconds at kLetterDt and writes `frames` frames of
/// its letters (the static geometry is written by the caller).
void run_letters(World& w, const std::vector<SoftLetter>& letters, int frames, double duration,
                 SceneWriter& out) {
  auto step = [&](double t) {
    for (const SoftLetter& s : letters) breathe(w, s, t + kLetterDt);
    w.substep(kLetterDt);
  };
  run_schedule(frames, static_cast<long long>(duration / kLetterDt + 0.5), kLetterDt, step,
               [&](int k, double t) {
                 out.begin_frame(k, t);
                 for (const SoftLetter& s : letters)
                   out.add_object(s.name, particle_positions(w, s.first, s.mesh->positions.size()),
                                  s.mesh->faces);
                 out.end_frame();
               });
  out.finish("meshes");
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// 1. Skirt

void generate_skirt(const SkirtOptions& o, SceneWriter& out) {
  constexpr double kDt = 1.0 / 480;
  constexpr double kWarmup = 0.5;    // seconds of draping before the body moves
  constexpr double kDuration = 2.5;  // seconds shown
  constexpr double kWaistZ = 1.0, kWaistR = 0.17, kHemR = 0.42, kLength = 0.6;
  constexpr double kHipX = 0.085, kHipZ = 0.93, kLegR = 0.065, kLegLength = 0.85;
  constexpr double kStride = 0.45;  // leg swing amplitude (radians)
  Rng rng(o.seed, 0);
  const double gait = kTwoPi * rng.uniform(0.55, 0.65);  // step frequency (rad/s)
  const double twist = rng.uniform(0.25, 0.4);           // body twist amplitude (radians)
  const double sway_phase = rng.uniform(0, kTwoPi);

  WorldOptions wo;
  wo.damping = 0.3;
  World w(wo);
  const int cloth = w.add_body(true);
  const int rows = o.rings, cols = o.segments;
  const double dz = kLength / (rows - 1);
  std::vector<V3> waist_rest;
  for (int r = 0; r < rows; ++r) {
    const double s = static_cast<double>(r) / (rows - 1);
    const double rad = kWaistR + (kHemR - kWaistR) * s;
    const double spacing = std::min(kTwoPi * rad / cols, dz);
    for (int c = 0; c < cols; ++c) {
      const double phi = kTwoPi * c / cols;
      const V3 p{rad * det_cos(phi), rad * det_sin(phi), kWaistZ - kLength * s};
      w.add_particle(p, r == 0 ? 0.0 : 1.0, kClothRadius * spacing, cloth);
      if (r == 0) waist_rest.push_back(p);
    }
  }
  add_cloth_constraints(w, 0, rows, cols, true);
  const std::vector<Face> skirt_faces = grid_faces(rows, cols, true);
  const Mesh leg = capsule_mesh(kLegR, kLegLength, 12, 3);

  // Body pose at time t (t < 0: warm-up, at rest): twist about z, sway in x, bob in z.
  auto body = [&](double t, M3& rot, V3& shift) {
    const double e = ease_in(t, 0.5);
    rot = rotation_about({0, 0, 1}, e * twist * det_sin(0.5 * gait * t));
    shift = {e * 0.04 * det_sin(0.5 * gait * t + sway_phase), 0, e * 0.015 * det_sin(2 * gait * t)};
  };
  // Leg `side` (0 left, 1 right): rotation and hip position in the world.
  auto leg_pose = [&](double t, int side, M3& rot, V3& hip) {
    M3 br;
    V3 bs;
    body(t, br, bs);
    const double swing = ease_in(t, 0.5) * kStride * det_sin(gait * t) * (side == 0 ? 1 : -1);
    // The capsule mesh runs up the +z axis; turn it upside down, then swing it about x.
    rot = br * rotation_about({1, 0, 0}, kPi + swing);
    hip = bs + br * V3{side == 0 ? -kHipX : kHipX, 0, kHipZ};
  };
  for (int side = 0; side < 2; ++side) {
    CapsuleCollider c;
    c.radius = kLegR;
    c.friction = 0.3;
    w.capsules.push_back(c);
  }
  auto pose_colliders = [&](double t) {
    for (int side = 0; side < 2; ++side) {
      M3 rot;
      V3 hip;
      leg_pose(t, side, rot, hip);
      CapsuleCollider& c = w.capsules[static_cast<size_t>(side)];
      c.a = hip;
      c.b = hip + rot * V3{0, 0, kLegLength};
    }
    M3 br;
    V3 bs;
    body(t, br, bs);
    for (int c = 0; c < cols; ++c) w.set_target(c, bs + br * waist_rest[static_cast<size_t>(c)]);
  };

  auto step = [&](double t) {
    pose_colliders(t + kDt);
    w.substep(kDt);
  };
  const auto warmup = static_cast<long long>(kWarmup / kDt + 0.5);
  for (long long s = 0; s < warmup; ++s) step(-kWarmup + static_cast<double>(s) * kDt);

  run_schedule(o.frames, static_cast<long long>(kDuration / kDt + 0.5), kDt, step,
               [&](int k, double t) {
                 out.begin_frame(k, t);
                 out.add_object("skirt", particle_positions(w, 0, w.x.size()), skirt_faces);
                 for (int side = 0; side < 2; ++side) {
                   M3 rot;
                   V3 hip;
                   leg_pose(t, side, rot, hip);
                   out.add_object(side == 0 ? "leg_left" : "leg_right",
                                  transformed(leg.positions, rot, hip), leg.faces);
                 }
                 out.end_frame();
               });
  out.finish("meshes");
}

// ---------------------------------------------------------------------------------------------
// 2. Cloth on a ball

void generate_cloth_ball(const ClothBallOptions& o, SceneWriter& out) {
  constexpr double kDt = 1.0 / 480;
  constexpr double kDuration = 3.0;
  constexpr double kSize = 2.2, kHeight = 1.35;
  constexpr double kBallR = 0.45, kBallZ = 0.55;
  Rng rng(o.seed, 0);
  const double yaw = rng.uniform(0, 0.5);
  const V3 offset{rng.uniform(0.05, 0.2), rng.uniform(-0.15, 0.15), 0};
  const V3 spin{rng.uniform(1.0, 2.0), 0, rng.uniform(3.0, 4.5)};  // rad/s
  const double drift = rng.uniform(0.2, 0.3);                       // ball sway (m)

  WorldOptions wo;
  wo.damping = 0.2;
  World w(wo);
  const int cloth = w.add_body(true);
  const int n = o.resolution;
  const double spacing = kSize / (n - 1);
  const M3 turn = rotation_about({0, 0, 1}, yaw);
  for (int r = 0; r < n; ++r)
    for (int c = 0; c < n; ++c) {
      const V3 local{-0.5 * kSize + spacing * c, -0.5 * kSize + spacing * r, 0};
      w.add_particle(offset + V3{0, 0, kHeight} + turn * local, 1.0, kClothRadius * spacing, cloth);
    }
  add_cloth_constraints(w, 0, n, n, false);
  const std::vector<Face> cloth_faces = grid_faces(n, n, false);

  const UnitSphereMesh sphere = geodesic_sphere(4);
  std::vector<V3> ball_local;
  for (const V3& d : sphere.directions) ball_local.push_back(kBallR * d);
  const double spin_rate = norm(spin);
  const V3 spin_axis = (1.0 / spin_rate) * spin;
  auto ball_centre = [&](double t) {
    return V3{drift * det_sin(kTwoPi * 0.3 * t), 0, kBallZ + 0.1 * det_sin(kTwoPi * 0.5 * t)};
  };
  auto ball_velocity = [&](double t) {
    return V3{drift * kTwoPi * 0.3 * det_cos(kTwoPi * 0.3 * t), 0,
              0.1 * kTwoPi * 0.5 * det_cos(kTwoPi * 0.5 * t)};
  };
  SphereCollider ball;
  ball.radius = kBallR;
  ball.friction = 0.6;
  ball.motion.angular_velocity = spin;
  w.spheres.push_back(ball);
  PlaneCollider ground;
  ground.friction = 0.5;
  w.planes.push_back(ground);
  const Mesh floor = board_mesh({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 1.6, 1.6, 8, 8);
  out.write_static("ground.obj", "ground", floor.positions, floor.faces);

  auto step = [&](double t) {
    SphereCollider& b = w.spheres[0];
    b.centre = ball_centre(t + kDt);
    b.motion.pivot = b.centre;
    b.motion.velocity = ball_velocity(t + kDt);
    w.substep(kDt);
  };
  run_schedule(o.frames, static_cast<long long>(kDuration / kDt + 0.5), kDt, step,
               [&](int k, double t) {
                 out.begin_frame(k, t);
                 out.add_object("cloth", particle_positions(w, 0, w.x.size()), cloth_faces);
                 out.add_object("ball",
                                transformed(ball_local, rotation_about(spin_axis, spin_rate * t),
                                            ball_centre(t)),
                                sphere.faces);
                 out.end_frame();
               });
  out.finish("meshes");
}

// ---------------------------------------------------------------------------------------------
// 3. Letters in a bowl

void generate_bowl(const BowlOptions& o, SceneWriter& out) {
  constexpr double kDuration = 3.5;
  const V3 centre{0, 0, 2.2};
  constexpr double kBowlR = 2.2, kRimZ = 1.6;
  WorldOptions wo;
  wo.damping = 0.3;
  World w(wo);
  BowlCollider bowl;
  bowl.centre = centre;
  bowl.radius = kBowlR;
  bowl.rim_z = kRimZ;
  bowl.friction = 0.3;
  w.bowls.push_back(bowl);
  const Mesh bowl_surface = bowl_mesh(centre, kBowlR, kRimZ, 32, 8);
  out.write_static("bowl.obj", "bowl", bowl_surface.positions, bowl_surface.faces);

  std::vector<Mesh> glyphs;
  for (int g = 0; g < kGlyphCount; ++g) glyphs.push_back(glyph_mesh(g, o.around, o.along, 0.9, 0.07, 0.12));
  std::vector<SoftLetter> letters;
  for (int i = 0; i < o.objects; ++i) {
    Rng rng(o.seed, static_cast<std::uint64_t>(i) + 1);
    const Mesh& m = glyphs[static_cast<size_t>(i % kGlyphCount)];
    // Dropped one above the other, a little off the axis, so they land on each other.
    const double a = rng.uniform(0, kTwoPi), r = rng.uniform(0, 0.8);
    const V3 start{r * det_cos(a), r * det_sin(a), 2.0 + 0.9 * i};
    letters.push_back(add_scene_letter(w, rng, m, i, start));
  }
  run_letters(w, letters, o.frames, kDuration, out);
}

// ---------------------------------------------------------------------------------------------
// 4. Letters through a funnel onto a ramp

void generate_funnel(const FunnelOptions& o, SceneWriter& out) {
  constexpr double kDuration = 3.0;
  constexpr double kTopR = 3.2, kTopZ = 3.0, kBottomR = 0.9, kBottomZ = 0.0;
  constexpr double kSpawnR = 2.6, kSpacing = 0.85;
  constexpr double kRampTilt = 25.0 * kPi / 180;
  WorldOptions wo;
  wo.damping = 0.3;
  World w(wo);
  FunnelCollider f;
  f.r_bottom = kBottomR;
  f.z_bottom = kBottomZ;
  f.r_top = kTopR;
  f.z_top = kTopZ;
  f.friction = 0.1;
  w.funnels.push_back(f);
  PlaneCollider ramp;
  ramp.origin = {1.8, 0, -1.8};
  ramp.normal = {det_sin(kRampTilt), 0, det_cos(kRampTilt)};
  ramp.u = {det_cos(kRampTilt), 0, -det_sin(kRampTilt)};
  ramp.v = {0, 1, 0};
  ramp.half_u = 3.0;
  ramp.half_v = 1.6;
  ramp.thickness = 0.5;
  ramp.friction = 0.05;
  w.planes.push_back(ramp);
  PlaneCollider floor;
  floor.origin = {0, 0, -4.5};
  floor.friction = 0.4;
  w.planes.push_back(floor);
  const Mesh funnel = funnel_mesh(kBottomR, kBottomZ, kTopR, kTopZ, 64, 8);
  const Mesh ramp_mesh = board_mesh(ramp.origin, ramp.u, ramp.v, ramp.half_u, ramp.half_v, 16, 8);
  const Mesh floor_mesh = board_mesh({4.5, 0, -4.5}, {1, 0, 0}, {0, 1, 0}, 6, 6, 8, 8);
  out.write_static("funnel.obj", "funnel", funnel.positions, funnel.faces);
  out.write_static("ramp.obj", "ramp", ramp_mesh.positions, ramp_mesh.faces);
  out.write_static("floor.obj", "floor", floor_mesh.positions, floor_mesh.faces);

  std::vector<Mesh> glyphs;
  for (int g = 0; g < kGlyphCount; ++g)
    glyphs.push_back(glyph_mesh(g, o.around, o.along, 0.6, 0.08, 0.12));
  // Start slots: a square lattice inside the spawn disc, layer after layer upwards.
  std::vector<std::array<double, 2>> disc;
  const int m = static_cast<int>(kSpawnR / kSpacing);
  for (int iy = -m; iy <= m; ++iy)
    for (int ix = -m; ix <= m; ++ix)
      if ((ix * ix + iy * iy) * kSpacing * kSpacing <= kSpawnR * kSpawnR)
        disc.push_back({ix * kSpacing, iy * kSpacing});
  std::vector<SoftLetter> letters;
  for (int i = 0; i < o.objects; ++i) {
    Rng rng(o.seed, static_cast<std::uint64_t>(i) + 1);
    const auto& slot = disc[static_cast<size_t>(i) % disc.size()];
    const int layer = i / static_cast<int>(disc.size());
    const double jx = rng.uniform(-0.08, 0.08);
    const double jy = rng.uniform(-0.08, 0.08);
    const V3 start{slot[0] + jx, slot[1] + jy, kTopZ + 0.6 + kSpacing * layer};
    const Mesh& mesh = glyphs[static_cast<size_t>(i % kGlyphCount)];
    letters.push_back(add_scene_letter(w, rng, mesh, i, start));
  }
  run_letters(w, letters, o.frames, kDuration, out);
}

// ---------------------------------------------------------------------------------------------
// 5. Breaking objects

namespace {

/// Surface of an axis-aligned box of lattice cells [lo, hi) (integer lattice coordinates),
/// one vertex per lattice point on the surface, two triangles per cell face, oriented
/// outwards. `key_of` returns each vertex's lattice point.
struct LatticeBox {
  std::vector<std::array<int, 3>> points;
  std::vector<Face> faces;
};

LatticeBox lattice_box(const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
  LatticeBox box;
  std::map<std::array<int, 3>, Index> id;
  auto vertex = [&](const std::array<int, 3>& p) {
    auto it = id.find(p);
    if (it != id.end()) return it->second;
    const auto i = static_cast<Index>(box.points.size());
    box.points.push_back(p);
    id.emplace(p, i);
    return i;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int fixed = side == 0 ? lo[static_cast<size_t>(axis)] : hi[static_cast<size_t>(axis)];
      for (int a = lo[static_cast<size_t>(u)]; a < hi[static_cast<size_t>(u)]; ++a)
        for (int b = lo[static_cast<size_t>(v)]; b < hi[static_cast<size_t>(v)]; ++b) {
          auto at = [&](int da, int db) {
            std::array<int, 3> p{};
            p[static_cast<size_t>(axis)] = fixed;
            p[static_cast<size_t>(u)] = a + da;
            p[static_cast<size_t>(v)] = b + db;
            return vertex(p);
          };
          const Index p00 = at(0, 0), p10 = at(1, 0), p11 = at(1, 1), p01 = at(0, 1);
          // (u, v, axis) is right-handed: counter-clockwise in (u, v) faces +axis.
          if (side == 1) {
            box.faces.push_back({p00, p10, p11});
            box.faces.push_back({p00, p11, p01});
          } else {
            box.faces.push_back({p00, p11, p10});
            box.faces.push_back({p00, p01, p11});
          }
        }
    }
  return box;
}

/// The pieces of one breaking object, in lattice cells (pieces x, y, z).
constexpr std::array<std::array<int, 3>, 3> kPieceLayouts = {{{2, 1, 1}, {3, 1, 1}, {2, 2, 1}}};
/// Layout of object i: 7 of every 14 objects two pieces, 3 three, 4 four (39 pieces in 14
/// objects, about 5.6K triangles before they break with 4 cells per piece side).
constexpr std::array<int, 14> kLayoutOfObject = {0, 2, 1, 0, 2, 0, 1, 0, 2, 0, 1, 2, 0, 0};
constexpr double kPieceSize = 0.4;

struct BreakingObject {
  std::string name;
  int body = 0;
  int cluster = 0;                   ///< whole object (enabled until it breaks)
  std::vector<int> piece_clusters;   ///< one per piece (enabled once it breaks)
  std::vector<int> piece_first;      ///< first particle of each piece
  std::vector<const LatticeBox*> piece_boxes;
  LatticeBox whole;                  ///< outer surface before breaking
  std::vector<int> whole_particle;   ///< particle of each vertex of `whole`
  bool broken = false;
};

}  // namespace

void generate_breaking(const BreakingOptions& o, SceneWriter& out) {
  constexpr double kDt = 1.0 / 480;
  constexpr double kDuration = 2.5;
  constexpr double kKick = 0.8;  // m/s: pieces fly apart from the object's centre
  constexpr double kGrid = 1.6;  // drop positions: a square grid this far apart
  const int g = o.cells;
  const double cell = kPieceSize / g;
  const double radius = 0.3 * cell;  // coincident glued vertices aside, pieces start apart

  WorldOptions wo;
  wo.damping = 0.2;
  World w(wo);
  PlaneCollider ground;
  ground.friction = 0.6;
  w.planes.push_back(ground);
  const Mesh floor = board_mesh({0, 0, 0}, {1, 0, 0}, {0, 1, 0}, 4, 4, 10, 10);
  out.write_static("ground.obj", "ground", floor.positions, floor.faces);

  // Piece boxes are shared by every object with the same layout: lattice [p g, (p + 1) g).
  std::map<std::array<int, 3>, LatticeBox> piece_box;
  std::vector<BreakingObject> objects(static_cast<size_t>(o.objects));
  const int per_row = 4;
  for (int i = 0; i < o.objects; ++i) {
    Rng rng(o.seed, static_cast<std::uint64_t>(i) + 1);
    BreakingObject& obj = objects[static_cast<size_t>(i)];
    obj.name = "object" + std::to_string(i);
    const auto& layout = kPieceLayouts[static_cast<size_t>(kLayoutOfObject[static_cast<size_t>(i) % 14])];
    const std::array<int, 3> size{layout[0] * g, layout[1] * g, layout[2] * g};
    const V3 half{0.5 * size[0] * cell, 0.5 * size[1] * cell, 0.5 * size[2] * cell};
    const M3 rot = random_rotation(rng);
    const double jx = rng.uniform(-0.1, 0.1);
    const double jy = rng.uniform(-0.1, 0.1);
    const double drop = rng.uniform(0.8, 3.0);
    const V3 centre{kGrid * (i % per_row - 0.5 * (per_row - 1)) + jx,
                    kGrid * (i / per_row - 0.5 * (per_row - 1)) + jy, drop};
    const V3 spin{rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)};
    auto place = [&](const std::array<int, 3>& p) {
      return centre + rot * (V3{p[0] * cell, p[1] * cell, p[2] * cell} - half);
    };
    obj.body = w.add_body(false, i);
    std::map<std::array<int, 3>, int> particle_at;  // lattice point -> first particle there
    std::vector<int> all;
    for (int pz = 0; pz < layout[2]; ++pz)
      for (int py = 0; py < layout[1]; ++py)
        for (int px = 0; px < layout[0]; ++px) {
          const std::array<int, 3> lo{px * g, py * g, pz * g};
          auto [it, fresh] = piece_box.try_emplace(
              {lo[0], lo[1], lo[2]}, LatticeBox{});
          if (fresh) it->second = lattice_box(lo, {lo[0] + g, lo[1] + g, lo[2] + g});
          const LatticeBox& box = it->second;
          obj.piece_boxes.push_back(&box);
          obj.piece_first.push_back(static_cast<int>(w.x.size()));
          std::vector<int> ids;
          for (const auto& p : box.points) {
            const V3 x = place(p);
            const int id = w.add_particle(x, 1.0, radius, obj.body);
            w.v[static_cast<size_t>(id)] = cross(spin, x - centre);
            particle_at.try_emplace(p, id);
            ids.push_back(id);
            all.push_back(id);
          }
          const int c = w.add_cluster(ids, 1.0);
          w.clusters[static_cast<size_t>(c)].enabled = false;
          obj.piece_clusters.push_back(c);
        }
    obj.cluster = w.add_cluster(all, 1.0);
    obj.whole = lattice_box({0, 0, 0}, size);
    for (const auto& p : obj.whole.points) obj.whole_particle.push_back(particle_at.at(p));
  }

  // An object breaks at the end of the substep in which it first touches the ground.
  auto break_on_impact = [&](BreakingObject& obj) {
    if (obj.broken) return;
    bool touching = false;
    for (std::size_t p = 0; p < obj.piece_first.size() && !touching; ++p)
      for (std::size_t k = 0; k < obj.piece_boxes[p]->points.size(); ++k)
        if (w.x[static_cast<size_t>(obj.piece_first[p]) + k].z <= 1.01 * radius) {
          touching = true;
          break;
        }
    if (!touching) return;
    obj.broken = true;
    w.clusters[static_cast<size_t>(obj.cluster)].enabled = false;
    const V3 centre = w.clusters[static_cast<size_t>(obj.cluster)].centre;
    for (std::size_t p = 0; p < obj.piece_first.size(); ++p) {
      ShapeCluster& c = w.clusters[static_cast<size_t>(obj.piece_clusters[p])];
      c.enabled = true;
      // Each piece becomes its own body in the object's group: it collides with the other
      // objects and their pieces, not with its siblings (see Body::group).
      const int body = w.add_body(false, w.bodies[static_cast<size_t>(obj.body)].group);
      V3 sum;
      for (int i : c.particles) sum = sum + w.x[static_cast<size_t>(i)];
      const V3 pc = (1.0 / static_cast<double>(c.particles.size())) * sum;
      const V3 away = pc - centre;
      const double len = norm(away);
      const V3 kick = len > 0 ? (kKick / len) * away : V3{};
      c.rotation = w.clusters[static_cast<size_t>(obj.cluster)].rotation;
      for (int i : c.particles) {
        w.body_of[static_cast<size_t>(i)] = body;
        w.v[static_cast<size_t>(i)] = w.v[static_cast<size_t>(i)] + kick;
      }
    }
  };
  auto step = [&](double) {
    w.substep(kDt);
    for (BreakingObject& obj : objects) break_on_impact(obj);
  };
  run_schedule(o.frames, static_cast<long long>(kDuration / kDt + 0.5), kDt, step,
               [&](int k, double t) {
                 out.begin_frame(k, t);
                 for (const BreakingObject& obj : objects) {
                   if (!obj.broken) {
                     std::vector<V3> pos;
                     for (int id : obj.whole_particle) pos.push_back(w.x[static_cast<size_t>(id)]);
                     out.add_object(obj.name, pos, obj.whole.faces);
                     continue;
                   }
                   // All pieces in the object's group, each with its own vertices: vproxq
                   // ("objects": "components") makes each piece an object.
                   std::vector<V3> pos;
                   std::vector<Face> faces;
                   for (std::size_t p = 0; p < obj.piece_first.size(); ++p) {
                     const auto base = static_cast<Index>(pos.size());
                     const LatticeBox& box = *obj.piece_boxes[p];
                     for (std::size_t q = 0; q < box.points.size(); ++q)
                       pos.push_back(w.x[static_cast<size_t>(obj.piece_first[p]) + q]);
                     for (const Face& f : box.faces) faces.push_back({f[0] + base, f[1] + base, f[2] + base});
                   }
                   out.add_object(obj.name, pos, faces);
                 }
                 out.end_frame();
               });
  out.finish("components");
}

}  // namespace vproxq::gen
