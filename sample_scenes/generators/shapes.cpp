#include "sample_scenes/generators/shapes.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace vproxq::gen {

std::vector<std::pair<int, int>> mesh_edges(const std::vector<Face>& faces) {
  std::vector<std::pair<int, int>> edges;
  edges.reserve(faces.size() * 3);
  for (const Face& f : faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[static_cast<size_t>(k)], b = f[static_cast<size_t>((k + 1) % 3)];
      edges.emplace_back(std::min(a, b), std::max(a, b));
    }
  std::sort(edges.begin(), edges.end());
  edges.erase(std::unique(edges.begin(), edges.end()), edges.end());
  return edges;
}

void orient_outwards(Mesh& mesh) {
  double volume6 = 0;
  for (const Face& f : mesh.faces) {
    const V3& a = mesh.positions[static_cast<size_t>(f[0])];
    const V3& b = mesh.positions[static_cast<size_t>(f[1])];
    const V3& c = mesh.positions[static_cast<size_t>(f[2])];
    volume6 += dot(a, cross(b, c));
  }
  if (volume6 < 0)
    for (Face& f : mesh.faces) std::swap(f[1], f[2]);
}

std::vector<Face> grid_faces(int rows, int cols, bool wrap_columns) {
  std::vector<Face> faces;
  const int cells = wrap_columns ? cols : cols - 1;
  for (int r = 0; r + 1 < rows; ++r)
    for (int c = 0; c < cells; ++c) {
      const int c1 = (c + 1) % cols;
      const Index a = r * cols + c, b = r * cols + c1, d = (r + 1) * cols + c,
                  e = (r + 1) * cols + c1;
      // Alternate the diagonal so the sheet has no preferred shear direction.
      if ((r + c) % 2 == 0) {
        faces.push_back({a, b, e});
        faces.push_back({a, e, d});
      } else {
        faces.push_back({a, b, d});
        faces.push_back({b, e, d});
      }
    }
  return faces;
}

namespace {

/// Rings of a surface of revolution about z: ring k has `segments` vertices at radius
/// radii[k], height heights[k]; optional poles close the ends. Faces between consecutive
/// rings, fans to the poles.
Mesh revolve(const std::vector<double>& radii, const std::vector<double>& heights, int segments,
             const double* bottom_pole, const double* top_pole) {
  Mesh m;
  const int rings = static_cast<int>(radii.size());
  for (int k = 0; k < rings; ++k)
    for (int s = 0; s < segments; ++s) {
      const double phi = kTwoPi * s / segments;
      m.positions.push_back({radii[static_cast<size_t>(k)] * det_cos(phi),
                             radii[static_cast<size_t>(k)] * det_sin(phi),
                             heights[static_cast<size_t>(k)]});
    }
  m.faces = grid_faces(rings, segments, true);
  if (bottom_pole) {
    const auto pole = static_cast<Index>(m.positions.size());
    m.positions.push_back({0, 0, *bottom_pole});
    for (int s = 0; s < segments; ++s) m.faces.push_back({pole, (s + 1) % segments, s});
  }
  if (top_pole) {
    const auto pole = static_cast<Index>(m.positions.size());
    m.positions.push_back({0, 0, *top_pole});
    const int base = (rings - 1) * segments;
    for (int s = 0; s < segments; ++s)
      m.faces.push_back({pole, base + s, base + (s + 1) % segments});
  }
  return m;
}

}  // namespace

Mesh capsule_mesh(double radius, double length, int segments, int cap_rings) {
  std::vector<double> radii, heights;
  // Bottom hemisphere from just above the south pole to the equator, then the top one.
  for (int k = 1; k <= cap_rings; ++k) {
    const double a = kHalfPi * k / cap_rings;  // 0 at the pole, pi/2 at the equator
    radii.push_back(radius * det_sin(a));
    heights.push_back(-radius * det_cos(a));
  }
  for (int k = cap_rings; k >= 1; --k) {
    const double a = kHalfPi * k / cap_rings;
    radii.push_back(radius * det_sin(a));
    heights.push_back(length + radius * det_cos(a));
  }
  const double bottom = -radius, top = length + radius;
  Mesh m = revolve(radii, heights, segments, &bottom, &top);
  orient_outwards(m);
  return m;
}

Mesh bowl_mesh(const V3& centre, double radius, double rim_z, int segments, int rings) {
  // Polar angle from the bottom pole up to the rim.
  const double cos_rim = (rim_z - centre.z) / radius;  // in (-1, 1)
  // acos by bisection on det_cos (monotone on [0, pi]): no std::acos, whose last bit varies.
  double lo = 0, hi = kPi;
  for (int it = 0; it < 80; ++it) {
    const double mid = 0.5 * (lo + hi);
    if (-det_cos(mid) < cos_rim) lo = mid; else hi = mid;
  }
  const double rim_angle = lo;  // angle from the south pole: z = centre.z - R cos(a)
  std::vector<double> radii, heights;
  for (int k = 1; k <= rings; ++k) {
    const double a = rim_angle * k / rings;
    radii.push_back(radius * det_sin(a));
    heights.push_back(-radius * det_cos(a));
  }
  const double bottom = -radius;
  Mesh m = revolve(radii, heights, segments, &bottom, nullptr);
  for (V3& p : m.positions) p = p + centre;
  return m;
}

Mesh funnel_mesh(double r_bottom, double z_bottom, double r_top, double z_top, int segments,
                 int rings) {
  std::vector<double> radii, heights;
  for (int k = 0; k <= rings; ++k) {
    const double t = static_cast<double>(k) / rings;
    radii.push_back(r_bottom + t * (r_top - r_bottom));
    heights.push_back(z_bottom + t * (z_top - z_bottom));
  }
  return revolve(radii, heights, segments, nullptr, nullptr);
}

Mesh board_mesh(const V3& origin, const V3& u, const V3& v, double half_u, double half_v, int nu,
                int nv) {
  Mesh m;
  for (int j = 0; j <= nv; ++j)
    for (int i = 0; i <= nu; ++i) {
      const double s = -half_u + 2 * half_u * i / nu, t = -half_v + 2 * half_v * j / nv;
      m.positions.push_back(origin + s * u + t * v);
    }
  m.faces = grid_faces(nv + 1, nu + 1, false);
  return m;
}

namespace {

struct P2 {
  double x = 0, y = 0;
};

/// sqrt(x^2 + y^2) with correctly rounded operations (std::hypot's last bit varies by libm).
double length2d(double x, double y) { return std::sqrt(x * x + y * y); }

/// A pen drawing a dense polyline (steps of at most kPenStep) from lines and arcs.
class Pen {
 public:
  explicit Pen(P2 start) { points_.push_back(start); }
  void line_to(P2 to) {
    const P2 from = points_.back();
    const double len = length2d(to.x - from.x, to.y - from.y);
    const int n = std::max(1, static_cast<int>(std::ceil(len / kPenStep)));
    for (int k = 1; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      points_.push_back({from.x + t * (to.x - from.x), from.y + t * (to.y - from.y)});
    }
  }
  /// Arc (or spiral, when r0 != r1) about `c` from angle a0 to a1 (radians; a1 < a0 turns
  /// clockwise), joined to the current point by a line.
  void arc(P2 c, double r0, double r1, double a0, double a1) {
    const double len = std::abs(a1 - a0) * std::max(r0, r1);
    const int n = std::max(2, static_cast<int>(std::ceil(len / kPenStep)));
    for (int k = 0; k <= n; ++k) {
      const double t = static_cast<double>(k) / n;
      const double a = a0 + t * (a1 - a0), r = r0 + t * (r1 - r0);
      const P2 p{c.x + r * det_cos(a), c.y + r * det_sin(a)};
      if (k == 0) line_to(p); else points_.push_back(p);
    }
  }
  const std::vector<P2>& points() const { return points_; }

 private:
  static constexpr double kPenStep = 0.005;
  std::vector<P2> points_;
};

constexpr double kDeg = kPi / 180;

/// The stroke of a glyph, and whether it is closed.
std::vector<P2> glyph_stroke(int glyph, bool& closed) {
  closed = false;
  switch (glyph) {
    case 0: {  // s: two half circles
      Pen p({0.3 + 0.22 * det_cos(20 * kDeg), 0.75 + 0.22 * det_sin(20 * kDeg)});
      p.arc({0.3, 0.75}, 0.22, 0.22, 20 * kDeg, 270 * kDeg);
      p.arc({0.3, 0.31}, 0.22, 0.22, 90 * kDeg, -160 * kDeg);
      return p.points();
    }
    case 1: {  // i: a stem with a foot
      Pen p({0.3, 0.95});
      p.line_to({0.3, 0.15});
      p.arc({0.45, 0.15}, 0.15, 0.15, 180 * kDeg, 270 * kDeg);
      return p.points();
    }
    case 2:
    case 3: {  // g: bowl and descender hook
      // The bowl runs clockwise from its lower right to its right side, where the stroke goes
      // on down into the stem: drawn the other way round it came up that side and went
      // straight back down, and the tube folded through itself at the turn.
      Pen p({0.35 + 0.27 * det_cos(-80 * kDeg), 0.6 + 0.27 * det_sin(-80 * kDeg)});
      p.arc({0.35, 0.6}, 0.27, 0.27, -80 * kDeg, -360 * kDeg);
      p.line_to({0.62, 0.0});
      p.arc({0.37, 0.0}, 0.25, 0.25, 0, -150 * kDeg);
      return p.points();
    }
    case 4: {  // r: stem and arch
      Pen p({0.1, 0.0});
      p.line_to({0.1, 0.45});
      p.arc({0.35, 0.45}, 0.25, 0.25, 180 * kDeg, 45 * kDeg);
      return p.points();
    }
    case 5: {  // a: bowl and stem (the bowl clockwise, as for g)
      Pen p({0.33 + 0.25 * det_cos(-80 * kDeg), 0.35 + 0.25 * det_sin(-80 * kDeg)});
      p.arc({0.33, 0.35}, 0.25, 0.25, -80 * kDeg, -360 * kDeg);
      p.line_to({0.58, 0.1});
      p.arc({0.68, 0.1}, 0.1, 0.1, 180 * kDeg, 270 * kDeg);
      return p.points();
    }
    case 6: {  // p: descender stem, then a bowl that stops short of the stem
      Pen p({0.1, -0.4});
      p.line_to({0.1, 0.6});
      p.arc({0.35, 0.38}, 0.25, 0.25, 120 * kDeg, -110 * kDeg);
      return p.points();
    }
    case 7: {  // h: ascender stem, then the shoulder (the lower left leg is not drawn)
      Pen p({0.1, 1.0});
      p.line_to({0.1, 0.35});
      p.arc({0.3, 0.35}, 0.2, 0.2, 180 * kDeg, 360 * kDeg);
      p.line_to({0.5, 0.6});
      return p.points();
    }
    case 8: {  // 0: an ellipse
      closed = true;
      std::vector<P2> pts;
      const int n = 400;
      for (int k = 0; k < n; ++k) {
        const double a = kTwoPi * k / n;
        pts.push_back({0.35 + 0.3 * det_cos(a), 0.5 + 0.45 * det_sin(a)});
      }
      return pts;
    }
    case 9: {  // 6: an inward spiral (its turns 0.3 apart never touch)
      Pen p({0.35 + 0.55 * det_cos(70 * kDeg), 0.4 + 0.55 * det_sin(70 * kDeg)});
      p.arc({0.35, 0.4}, 0.55, 0.18, 70 * kDeg, 70 * kDeg + 1.2 * 360 * kDeg);
      return p.points();
    }
    default:
      throw std::invalid_argument("glyph_stroke: no glyph " + std::to_string(glyph));
  }
}

/// `count` points at equal arc length along the polyline (closed: around the loop, the first
/// point not repeated; open: both ends included).
std::vector<P2> resample(const std::vector<P2>& pts, int count, bool closed) {
  std::vector<P2> path = pts;
  if (closed) path.push_back(pts.front());
  std::vector<double> s(path.size(), 0.0);
  for (std::size_t k = 1; k < path.size(); ++k)
    s[k] = s[k - 1] + length2d(path[k].x - path[k - 1].x, path[k].y - path[k - 1].y);
  const double total = s.back();
  std::vector<P2> out;
  std::size_t seg = 1;
  for (int k = 0; k < count; ++k) {
    const double target = closed ? total * k / count : total * k / (count - 1);
    while (seg + 1 < path.size() && s[seg] < target) ++seg;
    const double len = s[seg] - s[seg - 1];
    const double t = len > 0 ? std::clamp((target - s[seg - 1]) / len, 0.0, 1.0) : 0.0;
    out.push_back({path[seg - 1].x + t * (path[seg].x - path[seg - 1].x),
                   path[seg - 1].y + t * (path[seg].y - path[seg - 1].y)});
  }
  return out;
}

}  // namespace

char glyph_char(int glyph) { return "siggraph06"[glyph % kGlyphCount]; }

Mesh glyph_mesh(int glyph, int around, int along, double scale, double half_width,
                double half_depth) {
  // The stroke first: it sets `closed`, and the order in which a call's arguments are
  // evaluated is unspecified (GCC read `closed` before the stroke set it, clang after).
  bool closed = false;
  const std::vector<P2> stroke = glyph_stroke(glyph, closed);
  const std::vector<P2> centre = resample(stroke, along, closed);
  Mesh m;
  for (int k = 0; k < along; ++k) {
    const int prev = closed ? (k + along - 1) % along : std::max(0, k - 1);
    const int next = closed ? (k + 1) % along : std::min(along - 1, k + 1);
    const double tx = centre[static_cast<size_t>(next)].x - centre[static_cast<size_t>(prev)].x;
    const double ty = centre[static_cast<size_t>(next)].y - centre[static_cast<size_t>(prev)].y;
    const double tl = std::sqrt(tx * tx + ty * ty);
    const double nx = -ty / tl, ny = tx / tl;  // in-plane normal
    const P2& c = centre[static_cast<size_t>(k)];
    for (int j = 0; j < around; ++j) {
      const double phi = kTwoPi * j / around;
      const double w = half_width * det_cos(phi), d = half_depth * det_sin(phi);
      m.positions.push_back({c.x + w * nx, c.y + w * ny, d});
    }
  }
  // Rings are the rows of the grid, the points around a ring its columns.
  std::vector<Face> tube = grid_faces(along, around, true);
  if (closed) {
    // Close the loop: faces between the last ring and the first.
    const std::vector<Face> seam = grid_faces(2, around, true);
    for (Face f : seam) {
      for (Index& i : f) i = i < around ? (along - 1) * around + i : i - around;
      tube.push_back(f);
    }
  } else {
    for (int end = 0; end < 2; ++end) {
      const int ring = end == 0 ? 0 : along - 1;
      const auto pole = static_cast<Index>(m.positions.size());
      m.positions.push_back({centre[static_cast<size_t>(ring)].x,
                             centre[static_cast<size_t>(ring)].y, 0});
      for (int j = 0; j < around; ++j) {
        const Index a = ring * around + j, b = ring * around + (j + 1) % around;
        tube.push_back(end == 0 ? Face{pole, b, a} : Face{pole, a, b});
      }
    }
  }
  m.faces = std::move(tube);
  V3 sum;
  for (const V3& p : m.positions) sum = sum + p;
  const V3 mid = (1.0 / static_cast<double>(m.positions.size())) * sum;
  for (V3& p : m.positions) p = scale * (p - mid);
  orient_outwards(m);
  return m;
}

}  // namespace vproxq::gen
