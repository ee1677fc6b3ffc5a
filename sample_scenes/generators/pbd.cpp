#include "sample_scenes/generators/pbd.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace vproxq::gen {

V3 operator*(const M3& a, const V3& v) {
  return {(a.m[0][0] * v.x + a.m[0][1] * v.y) + a.m[0][2] * v.z,
          (a.m[1][0] * v.x + a.m[1][1] * v.y) + a.m[1][2] * v.z,
          (a.m[2][0] * v.x + a.m[2][1] * v.y) + a.m[2][2] * v.z};
}

M3 operator*(const M3& a, const M3& b) {
  M3 r = M3::zero();
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      r.m[i][j] = (a.m[i][0] * b.m[0][j] + a.m[i][1] * b.m[1][j]) + a.m[i][2] * b.m[2][j];
  return r;
}

M3 transpose(const M3& a) {
  M3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r.m[i][j] = a.m[j][i];
  return r;
}

M3 rotation_from_quaternion(double w, double x, double y, double z) {
  M3 r;
  r.m[0][0] = 1 - 2 * (y * y + z * z);
  r.m[0][1] = 2 * (x * y - w * z);
  r.m[0][2] = 2 * (x * z + w * y);
  r.m[1][0] = 2 * (x * y + w * z);
  r.m[1][1] = 1 - 2 * (x * x + z * z);
  r.m[1][2] = 2 * (y * z - w * x);
  r.m[2][0] = 2 * (x * z - w * y);
  r.m[2][1] = 2 * (y * z + w * x);
  r.m[2][2] = 1 - 2 * (x * x + y * y);
  return r;
}

M3 rotation_about(const V3& axis, double angle) {
  const double s = det_sin(0.5 * angle), c = det_cos(0.5 * angle);
  return rotation_from_quaternion(c, s * axis.x, s * axis.y, s * axis.z);
}

M3 random_rotation(Rng& rng) {
  for (;;) {
    // One statement per draw: the order of operands within an expression is unspecified.
    const double w = rng.uniform(-1, 1);
    const double x = rng.uniform(-1, 1);
    const double y = rng.uniform(-1, 1);
    const double z = rng.uniform(-1, 1);
    const double n2 = (w * w + x * x) + (y * y + z * z);
    if (n2 > 1.0 || n2 < 1e-6) continue;  // uniform in the 4-ball, hence on the 3-sphere
    const double n = std::sqrt(n2);
    return rotation_from_quaternion(w / n, x / n, y / n, z / n);
  }
}

namespace {

double determinant(const M3& a) {
  return (a.m[0][0] * (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) -
          a.m[0][1] * (a.m[1][0] * a.m[2][2] - a.m[1][2] * a.m[2][0])) +
         a.m[0][2] * (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]);
}

double frobenius2(const M3& a) {
  double s = 0;
  for (const auto& row : a.m)
    for (double v : row) s += v * v;
  return s;
}

/// A^-T = cofactor(A) / det(A).
M3 inverse_transpose(const M3& a, double det) {
  M3 c;
  c.m[0][0] = (a.m[1][1] * a.m[2][2] - a.m[1][2] * a.m[2][1]) / det;
  c.m[0][1] = (a.m[1][2] * a.m[2][0] - a.m[1][0] * a.m[2][2]) / det;
  c.m[0][2] = (a.m[1][0] * a.m[2][1] - a.m[1][1] * a.m[2][0]) / det;
  c.m[1][0] = (a.m[0][2] * a.m[2][1] - a.m[0][1] * a.m[2][2]) / det;
  c.m[1][1] = (a.m[0][0] * a.m[2][2] - a.m[0][2] * a.m[2][0]) / det;
  c.m[1][2] = (a.m[0][1] * a.m[2][0] - a.m[0][0] * a.m[2][1]) / det;
  c.m[2][0] = (a.m[0][1] * a.m[1][2] - a.m[0][2] * a.m[1][1]) / det;
  c.m[2][1] = (a.m[0][2] * a.m[1][0] - a.m[0][0] * a.m[1][2]) / det;
  c.m[2][2] = (a.m[0][0] * a.m[1][1] - a.m[0][1] * a.m[1][0]) / det;
  return c;
}

/// Relative size of det(A) against |A|^3 below which A counts as singular (a cluster squashed
/// flat): Newton's iteration would amplify noise there.
constexpr double kSingularDeterminant = 1e-9;
/// Newton's polar iteration converges quadratically; stop when a step changes R by less than
/// this (Frobenius norm squared), or after kPolarIterations.
constexpr double kPolarConverged = 1e-26;
constexpr int kPolarIterations = 40;

}  // namespace

M3 polar_rotation(const M3& a, const M3& fallback) {
  const double f2 = frobenius2(a);
  double det = determinant(a);
  // A reflection (det < 0) means an inverted cluster; keep the last rotation instead.
  if (!(det > kSingularDeterminant * f2 * std::sqrt(f2))) return fallback;
  M3 r = a;
  for (int it = 0; it < kPolarIterations; ++it) {
    const M3 inv_t = inverse_transpose(r, det);
    M3 next;
    double change = 0;
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) {
        next.m[i][j] = 0.5 * (r.m[i][j] + inv_t.m[i][j]);
        const double d = next.m[i][j] - r.m[i][j];
        change += d * d;
      }
    r = next;
    if (change < kPolarConverged) break;
    det = determinant(r);
    if (!(det > 0)) return fallback;
  }
  return r;
}

int World::add_body(bool self_collide, int group) {
  bodies.push_back(Body{self_collide, group});
  return static_cast<int>(bodies.size()) - 1;
}

int World::add_particle(const V3& p, double w, double r, int body) {
  x.push_back(p);
  v.push_back({});
  inv_mass.push_back(w);
  radius.push_back(r);
  body_of.push_back(body);
  target_.push_back(p);
  return static_cast<int>(x.size()) - 1;
}

void World::add_distance(int i, int j, double compliance) {
  distances.push_back({i, j, norm(x[static_cast<size_t>(j)] - x[static_cast<size_t>(i)]),
                       compliance});
}

int World::add_cluster(const std::vector<int>& particles, double stiffness) {
  ShapeCluster c;
  c.particles = particles;
  c.stiffness = stiffness;
  V3 sum;
  for (int i : particles) sum = sum + x[static_cast<size_t>(i)];
  c.centre = (1.0 / static_cast<double>(particles.size())) * sum;
  for (int i : particles) c.rest.push_back(x[static_cast<size_t>(i)] - c.centre);
  clusters.push_back(std::move(c));
  return static_cast<int>(clusters.size()) - 1;
}

void World::substep(double dt) {
  const std::size_t n = x.size();
  prev_ = x;
  const double keep = std::max(0.0, 1.0 - options_.damping * dt);
  for (std::size_t i = 0; i < n; ++i) {
    if (inv_mass[i] > 0) {
      v[i] = keep * (v[i] + dt * options_.gravity);
      x[i] = x[i] + dt * v[i];
    } else {
      x[i] = target_[i];
    }
  }
  build_hash();
  for (int it = 0; it < options_.iterations; ++it) {
    solve_distances(dt);
    solve_clusters();
    solve_particle_contacts();
    solve_colliders(dt);
  }
  const double max2 = options_.max_speed * options_.max_speed;
  for (std::size_t i = 0; i < n; ++i) {
    v[i] = (1.0 / dt) * (x[i] - prev_[i]);
    const double s2 = dot(v[i], v[i]);
    if (s2 > max2) v[i] = (options_.max_speed / std::sqrt(s2)) * v[i];
  }
}

void World::solve_distances(double dt) {
  // One XPBD iteration from lambda = 0 (small steps): the correction is
  // -C / (w_i + w_j + compliance / dt^2) along the constraint gradient.
  const double inv_dt2 = 1.0 / (dt * dt);
  for (const DistanceConstraint& c : distances) {
    const auto i = static_cast<size_t>(c.i), j = static_cast<size_t>(c.j);
    const double wsum = inv_mass[i] + inv_mass[j];
    if (wsum == 0) continue;
    const V3 d = x[j] - x[i];
    const double len = norm(d);
    if (len == 0) continue;
    const double s = (len - c.rest) / ((wsum + c.compliance * inv_dt2) * len);
    x[i] = x[i] + (s * inv_mass[i]) * d;
    x[j] = x[j] - (s * inv_mass[j]) * d;
  }
}

void World::solve_clusters() {
  for (ShapeCluster& c : clusters) {
    if (!c.enabled) continue;
    V3 sum;
    for (int i : c.particles) sum = sum + x[static_cast<size_t>(i)];
    const V3 centre = (1.0 / static_cast<double>(c.particles.size())) * sum;
    M3 a = M3::zero();
    for (std::size_t k = 0; k < c.particles.size(); ++k) {
      const V3 p = x[static_cast<size_t>(c.particles[k])] - centre;
      const V3 q{c.scale.x * c.rest[k].x, c.scale.y * c.rest[k].y, c.scale.z * c.rest[k].z};
      const double pv[3] = {p.x, p.y, p.z}, qv[3] = {q.x, q.y, q.z};
      for (int r = 0; r < 3; ++r)
        for (int s = 0; s < 3; ++s) a.m[r][s] += pv[r] * qv[s];
    }
    c.rotation = polar_rotation(a, c.rotation);
    c.centre = centre;
    for (std::size_t k = 0; k < c.particles.size(); ++k) {
      const auto i = static_cast<size_t>(c.particles[k]);
      if (inv_mass[i] == 0) continue;
      const V3 q{c.scale.x * c.rest[k].x, c.scale.y * c.rest[k].y, c.scale.z * c.rest[k].z};
      const V3 goal = centre + c.rotation * q;
      x[i] = x[i] + c.stiffness * (goal - x[i]);
    }
  }
}

namespace {

std::array<std::int64_t, 3> cell_of(const V3& p, double cell) {
  return {static_cast<std::int64_t>(std::floor(p.x / cell)),
          static_cast<std::int64_t>(std::floor(p.y / cell)),
          static_cast<std::int64_t>(std::floor(p.z / cell))};
}

/// Bucket of a cell in a table of 2^k buckets (`mask` = 2^k - 1): unsigned arithmetic, which
/// wraps the same way everywhere.
std::uint32_t bucket_of(const std::array<std::int64_t, 3>& c, std::uint32_t mask) {
  const auto h = (static_cast<std::uint64_t>(c[0]) * 73856093ull) ^
                 (static_cast<std::uint64_t>(c[1]) * 19349663ull) ^
                 (static_cast<std::uint64_t>(c[2]) * 83492791ull);
  return static_cast<std::uint32_t>((h ^ (h >> 29)) & mask);
}

}  // namespace

void World::build_hash() {
  const std::size_t n = x.size();
  double rmax = 0;
  for (double r : radius) rmax = std::max(rmax, r);
  cell_ = rmax > 0 ? 2 * rmax : 1;
  std::size_t size = 1;
  while (size < 2 * n) size <<= 1;
  const auto mask = static_cast<std::uint32_t>(size - 1);
  cell_start_.assign(size + 1, 0);
  particle_bucket_.resize(n);
  particle_cell_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    particle_cell_[i] = cell_of(x[i], cell_);
    particle_bucket_[i] = bucket_of(particle_cell_[i], mask);
    ++cell_start_[particle_bucket_[i] + 1];
  }
  for (std::size_t b = 0; b < size; ++b) cell_start_[b + 1] += cell_start_[b];
  cell_entries_.resize(n);
  std::vector<int> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    cell_entries_[static_cast<size_t>(fill[particle_bucket_[i]]++)] = static_cast<int>(i);
}

void World::solve_particle_contacts() {
  particle_contacts = 0;
  const std::size_t n = x.size();
  if (n == 0) return;
  const auto mask = static_cast<std::uint32_t>(cell_start_.size() - 2);
  std::array<std::uint32_t, 27> seen{};
  for (std::size_t i = 0; i < n; ++i) {
    if (radius[i] <= 0) continue;
    // The particle's cell at hashing time: positions move a little during the solve, but a
    // neighbour within 2 * rmax is still in one of the 27 cells around it, up to that drift.
    const auto& c = particle_cell_[i];
    int nseen = 0;
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const std::uint32_t b = bucket_of({c[0] + dx, c[1] + dy, c[2] + dz}, mask);
          // Two neighbour cells can share a bucket: visit each bucket once.
          if (std::find(seen.begin(), seen.begin() + nseen, b) != seen.begin() + nseen) continue;
          seen[static_cast<size_t>(nseen++)] = b;
          for (int e = cell_start_[b]; e < cell_start_[b + 1]; ++e) {
            const auto j = static_cast<size_t>(cell_entries_[static_cast<size_t>(e)]);
            if (j <= i || radius[j] <= 0) continue;
            if (body_of[i] == body_of[j]) {
              if (!bodies[static_cast<size_t>(body_of[i])].self_collide) continue;
            } else {
              const int gi = bodies[static_cast<size_t>(body_of[i])].group;
              if (gi >= 0 && gi == bodies[static_cast<size_t>(body_of[j])].group) continue;
            }
            const double wsum = inv_mass[i] + inv_mass[j];
            if (wsum == 0) continue;
            const double rr = radius[i] + radius[j];
            const V3 d = x[j] - x[i];
            const double d2 = dot(d, d);
            // Coincident particles (the glued faces of a breaking object) have no direction
            // to separate along; the motion of their bodies separates them.
            if (d2 >= rr * rr || d2 == 0) continue;
            const double len = std::sqrt(d2);
            const double s = (len - rr) / (wsum * len);
            x[i] = x[i] + (s * inv_mass[i]) * d;
            x[j] = x[j] - (s * inv_mass[j]) * d;
            ++particle_contacts;
          }
        }
  }
}

namespace {

/// Moves p out along `n` to signed distance `target` (from a surface point at signed distance
/// `signed_distance`), then removes `friction` of its slip along the surface relative to the
/// surface's own motion during the substep.
void push_with_friction(V3& p, const V3& before, const V3& n, double signed_distance,
                        double target, double friction, const V3& surface_displacement) {
  p = p + (target - signed_distance) * n;
  if (friction <= 0) return;
  const V3 d = (p - before) - surface_displacement;
  const V3 tangential = d - dot(d, n) * n;
  p = p - friction * tangential;
}

V3 surface_velocity(const SurfaceMotion& m, const V3& p) {
  return m.velocity + cross(m.angular_velocity, p - m.pivot);
}

}  // namespace

void World::solve_colliders(double dt) {
  const std::size_t n = x.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (inv_mass[i] == 0) continue;
    V3& p = x[i];
    const double r = radius[i];
    for (const SphereCollider& s : spheres) {
      const V3 d = p - s.centre;
      const double len = norm(d);
      if (len >= s.radius + r || len == 0) continue;
      push_with_friction(p, prev_[i], (1.0 / len) * d, len - s.radius, r, s.friction,
                         dt * surface_velocity(s.motion, p));
    }
    for (const CapsuleCollider& c : capsules) {
      const V3 ab = c.b - c.a;
      double t = dot(p - c.a, ab) / dot(ab, ab);
      t = std::clamp(t, 0.0, 1.0);
      const V3 d = p - (c.a + t * ab);
      const double len = norm(d);
      if (len >= c.radius + r || len == 0) continue;
      push_with_friction(p, prev_[i], (1.0 / len) * d, len - c.radius, r, c.friction,
                         dt * surface_velocity(c.motion, p));
    }
    for (const PlaneCollider& pl : planes) {
      const V3 d = p - pl.origin;
      const double s = dot(d, pl.normal);
      if (s >= r || s < -pl.thickness) continue;
      if (pl.half_u > 0 && std::abs(dot(d, pl.u)) > pl.half_u) continue;
      if (pl.half_v > 0 && std::abs(dot(d, pl.v)) > pl.half_v) continue;
      push_with_friction(p, prev_[i], pl.normal, s, r, pl.friction, {});
    }
    for (const BowlCollider& b : bowls) {
      if (p.z > b.rim_z) continue;
      const V3 d = p - b.centre;
      const double len = norm(d);
      // Signed distance to the wall, positive inside the bowl.
      const double s = b.radius - len;
      if (s >= r || s < -b.shell || len == 0) continue;
      push_with_friction(p, prev_[i], (-1.0 / len) * d, s, r, b.friction, {});
    }
    for (const FunnelCollider& f : funnels) {
      // The wall is a segment in the (rho, z) half-plane; its inward normal (towards the axis)
      // is the segment direction turned by +90 degrees.
      const double dx = p.x - f.axis_x, dy = p.y - f.axis_y;
      const double rho = std::sqrt(dx * dx + dy * dy);
      if (rho == 0) continue;
      const double tr = f.r_top - f.r_bottom, tz = f.z_top - f.z_bottom;
      const double tl = std::sqrt(tr * tr + tz * tz);
      const double along = ((rho - f.r_bottom) * tr + (p.z - f.z_bottom) * tz) / (tl * tl);
      if (along < 0 || along > 1) continue;
      const double nr = -tz / tl, nz = tr / tl;
      const double s = (rho - f.r_bottom) * nr + (p.z - f.z_bottom) * nz;
      if (s >= r || s < -f.shell) continue;
      const V3 normal{nr * dx / rho, nr * dy / rho, nz};
      push_with_friction(p, prev_[i], normal, s, r, f.friction, {});
    }
  }
}

}  // namespace vproxq::gen
