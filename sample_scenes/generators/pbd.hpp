#pragma once
// A small deterministic position-based dynamics core for the scene generators: particles,
// distance constraints (XPBD: compliance instead of iteration-dependent stiffness), shape
// matching clusters (Müller et al. 2005) for soft and rigid bodies, analytic colliders with
// friction (sphere, capsule, bounded plane, bowl, funnel), and particle–particle repulsion
// through a spatial hash, so that cloth folds onto itself and objects crowd without passing
// through each other much.
//
// "Small steps" (Macklin et al. 2019): many substeps with one solver iteration each, which
// keeps the cloth stiff without many iterations.
//
// Deterministic: one thread, a fixed order for everything (particles, constraints, hash
// candidates in index order), and only +, -, *, /, sqrt and floor, which IEEE 754 rounds the
// same everywhere (the generator is built with -ffp-contract=off).
// What it is not: an accurate simulator. Contacts are between particles (vertices), so
// triangles can still cross each other between vertices; the scenes only need plausible
// motion with close contact, folds and some interpenetration, which proximity queries are
// meant to report.
#include "sample_scenes/generators/det_math.hpp"

#include <array>
#include <cstdint>
#include <vector>

namespace vproxq::gen {

inline V3 operator*(const V3& a, double s) { return s * a; }
inline double norm(const V3& a) { return std::sqrt(dot(a, a)); }

/// 3x3 matrix, row major.
struct M3 {
  double m[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  static M3 zero() {
    M3 z;
    for (auto& row : z.m)
      for (double& v : row) v = 0;
    return z;
  }
};
V3 operator*(const M3& a, const V3& v);
M3 operator*(const M3& a, const M3& b);
M3 transpose(const M3& a);

/// Rotation matrix of the unit quaternion (w, x, y, z).
M3 rotation_from_quaternion(double w, double x, double y, double z);
/// Rotation by `angle` radians about the unit vector `axis` (det_sin/det_cos).
M3 rotation_about(const V3& axis, double angle);
/// A uniformly random rotation (random unit quaternion by rejection in the 4-ball).
M3 random_rotation(Rng& rng);

/// The rotation of the polar decomposition A = R S, by Newton's iteration
/// R <- (R + R^-T) / 2 started from A (Higham 1986). When A is (nearly) singular (a flat or
/// collapsed cluster), `fallback` (the previous rotation) is returned.
M3 polar_rotation(const M3& a, const M3& fallback);

struct DistanceConstraint {
  int i = 0, j = 0;
  double rest = 0;
  double compliance = 0;  ///< XPBD compliance (inverse stiffness, m/N); 0 = inextensible
};

/// Shape matching: the cluster's particles are pulled towards the best rigid motion of their
/// rest shape. stiffness 1 = rigid, smaller = soft. `scale` stretches the rest shape along
/// its own axes (animated by the scenes, so bodies keep deforming while they move).
struct ShapeCluster {
  std::vector<int> particles;
  std::vector<V3> rest;  ///< rest offsets from the rest centre of mass, same order
  double stiffness = 1;
  V3 scale{1, 1, 1};
  bool enabled = true;
  M3 rotation;  ///< last rotation found (also the fallback of the polar decomposition)
  V3 centre;    ///< last centre of mass
};

/// Surface motion of a collider at a point: velocity + angular_velocity x (p - pivot); used
/// by friction, so that a rotating ball drags the cloth with it.
struct SurfaceMotion {
  V3 velocity;
  V3 angular_velocity;
  V3 pivot;
};

struct SphereCollider {
  V3 centre;
  double radius = 1;
  double friction = 0;  ///< fraction of the tangential slip removed per contact, in [0, 1]
  SurfaceMotion motion;
};

struct CapsuleCollider {
  V3 a, b;
  double radius = 1;
  double friction = 0;
  SurfaceMotion motion;
};

/// The half-space side of a plane (normal points to the free side), limited to a rectangle
/// (half extents along u and v; 0 = unbounded) and to a slab `thickness` deep behind it, so
/// that a ramp is a finite board that things can fall past.
struct PlaneCollider {
  V3 origin, normal{0, 0, 1};
  V3 u{1, 0, 0}, v{0, 1, 0};
  double half_u = 0, half_v = 0;
  double thickness = 1;
  double friction = 0;
};

/// The inside of a spherical bowl: particles below `rim_z` within `shell` outside the sphere
/// are pushed back inside.
struct BowlCollider {
  V3 centre;
  double radius = 1;
  double rim_z = 0;
  double shell = 0.5;
  double friction = 0;
};

/// The inside of a funnel: a cone about the vertical axis through (axis_x, axis_y), radius
/// r_bottom at z_bottom and r_top at z_top; particles near the wall (within `shell` outside
/// it) are pushed back inside.
struct FunnelCollider {
  double axis_x = 0, axis_y = 0;
  double z_bottom = 0, z_top = 1;
  double r_bottom = 0.5, r_top = 1;
  double shell = 0.5;
  double friction = 0;
};

/// A body: a set of particles that collide with other bodies' particles, and with their own
/// only when self_collide (cloth); soft and rigid bodies keep their shape by clusters instead.
struct Body {
  bool self_collide = false;
  /// Bodies of one group >= 0 do not collide with each other: the pieces of a breaking
  /// object start with coincident vertices on their glued faces, which have no direction to
  /// be pushed apart along (and a push of a whole contact distance in one substep would
  /// fling them away).
  int group = -1;
};

struct WorldOptions {
  V3 gravity{0, 0, -9.81};
  double damping = 0.2;  ///< velocity loss per second (linear drag), for stability
  int iterations = 1;    ///< solver iterations per substep
  /// Speed limit (m/s). A particle pushed deep out of a wall or another body in one substep
  /// would otherwise leave with (correction / dt), far faster than anything in the scene.
  double max_speed = 20;
};

class World {
 public:
  explicit World(const WorldOptions& options = {}) : options_(options) {}

  int add_body(bool self_collide, int group = -1);
  /// Adds a particle; inv_mass 0 makes it kinematic (moved only by set_target).
  int add_particle(const V3& x, double inv_mass, double radius, int body);
  void add_distance(int i, int j, double compliance);  ///< rest length: the current distance
  /// Adds a cluster over `particles` with their current positions as rest shape.
  int add_cluster(const std::vector<int>& particles, double stiffness);

  /// Where a kinematic particle will be at the end of the next substep.
  void set_target(int i, const V3& x) { target_[static_cast<size_t>(i)] = x; }

  /// Advances by dt: predict, solve constraints, clusters, contacts and colliders, update
  /// velocities.
  void substep(double dt);

  std::vector<V3> x;  ///< positions
  std::vector<V3> v;  ///< velocities
  std::vector<double> inv_mass;
  std::vector<double> radius;  ///< contact radius: two particles keep radius_i + radius_j apart
  std::vector<int> body_of;
  std::vector<Body> bodies;
  std::vector<DistanceConstraint> distances;
  std::vector<ShapeCluster> clusters;
  std::vector<SphereCollider> spheres;
  std::vector<CapsuleCollider> capsules;
  std::vector<PlaneCollider> planes;
  std::vector<BowlCollider> bowls;
  std::vector<FunnelCollider> funnels;

  /// Counters of the last substep (for the generators' summaries and tests).
  std::uint64_t particle_contacts = 0;

 private:
  void solve_distances(double dt);
  void solve_clusters();
  void solve_particle_contacts();
  void solve_colliders(double dt);
  void build_hash();

  WorldOptions options_;
  std::vector<V3> prev_;
  std::vector<V3> target_;
  // Dense spatial hash (counting sort of particles by hashed cell): cell_start_[h] ..
  // cell_start_[h + 1] index cell_entries_, particles in increasing index order.
  double cell_ = 1;
  std::vector<int> cell_start_;
  std::vector<int> cell_entries_;
  std::vector<std::uint32_t> particle_bucket_;
  std::vector<std::array<std::int64_t, 3>> particle_cell_;
};

}  // namespace vproxq::gen
