#include "core/geometry/exact_distance.hpp"

#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

using Limbs = std::vector<std::uint32_t>;

/// Compares two magnitudes, either of which may have zero limbs at the top.
int compare_magnitudes(const Limbs& a, const Limbs& b) {
  for (size_t i = std::max(a.size(), b.size()); i-- > 0;) {
    const std::uint32_t x = i < a.size() ? a[i] : 0u, y = i < b.size() ? b[i] : 0u;
    if (x != y) return x < y ? -1 : 1;
  }
  return 0;
}

Limbs add_magnitudes(const Limbs& a, const Limbs& b) {
  const Limbs& longer = a.size() >= b.size() ? a : b;
  const Limbs& shorter = a.size() >= b.size() ? b : a;
  Limbs out(longer.size() + 1, 0);
  std::uint64_t carry = 0;
  for (size_t i = 0; i < longer.size(); ++i) {
    const std::uint64_t s = std::uint64_t{longer[i]} + (i < shorter.size() ? shorter[i] : 0u) + carry;
    out[i] = static_cast<std::uint32_t>(s);
    carry = s >> 32;
  }
  out[longer.size()] = static_cast<std::uint32_t>(carry);
  return out;
}

/// a - b for a >= b.
Limbs subtract_magnitudes(const Limbs& a, const Limbs& b) {
  Limbs out(a.size(), 0);
  std::int64_t borrow = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    std::int64_t d = std::int64_t{a[i]} - (i < b.size() ? std::int64_t{b[i]} : 0) - borrow;
    borrow = d < 0;
    if (d < 0) d += std::int64_t{1} << 32;
    out[i] = static_cast<std::uint32_t>(d);
  }
  return out;
}

Limbs multiply_magnitudes(const Limbs& a, const Limbs& b) {
  Limbs out(a.size() + b.size(), 0);
  for (size_t i = 0; i < a.size(); ++i) {
    std::uint64_t carry = 0;
    for (size_t j = 0; j < b.size(); ++j) {
      const std::uint64_t t = std::uint64_t{a[i]} * b[j] + out[i + j] + carry;
      out[i + j] = static_cast<std::uint32_t>(t);
      carry = t >> 32;
    }
    for (size_t k = i + b.size(); carry != 0; ++k) {
      const std::uint64_t t = std::uint64_t{out[k]} + carry;
      out[k] = static_cast<std::uint32_t>(t);
      carry = t >> 32;
    }
  }
  return out;
}

/// a * 2^bits.
Limbs shift_left(const Limbs& a, std::int64_t bits) {
  const auto whole = static_cast<size_t>(bits / 32);
  const auto part = static_cast<unsigned>(bits % 32);
  Limbs out(a.size() + whole + 1, 0);
  for (size_t i = 0; i < a.size(); ++i) {
    const std::uint64_t v = std::uint64_t{a[i]} << part;
    out[i + whole] |= static_cast<std::uint32_t>(v);
    out[i + whole + 1] |= static_cast<std::uint32_t>(v >> 32);
  }
  return out;
}

}  // namespace

Dyadic::Dyadic(double x) {
  if (x == 0.0) return;
  int e = 0;
  const double m = std::frexp(std::fabs(x), &e);  // in [0.5, 1)
  const auto mantissa = static_cast<std::uint64_t>(std::ldexp(m, 53));  // exact: 53 bits
  negative_ = x < 0;
  magnitude_ = {static_cast<std::uint32_t>(mantissa), static_cast<std::uint32_t>(mantissa >> 32)};
  exponent_ = e - 53;
  normalize();
}

void Dyadic::normalize() {
  while (!magnitude_.empty() && magnitude_.back() == 0) magnitude_.pop_back();
  size_t low = 0;
  while (low < magnitude_.size() && magnitude_[low] == 0) ++low;
  if (low > 0) {
    magnitude_.erase(magnitude_.begin(), magnitude_.begin() + static_cast<std::ptrdiff_t>(low));
    exponent_ += 32 * static_cast<std::int64_t>(low);
  }
  if (magnitude_.empty()) {
    negative_ = false;
    exponent_ = 0;
  }
}

Dyadic Dyadic::operator-() const {
  Dyadic r = *this;
  if (!r.magnitude_.empty()) r.negative_ = !r.negative_;
  return r;
}

Dyadic operator+(const Dyadic& a, const Dyadic& b) {
  if (a.sign() == 0) return b;
  if (b.sign() == 0) return a;
  const std::int64_t e = std::min(a.exponent_, b.exponent_);
  const Limbs ma = shift_left(a.magnitude_, a.exponent_ - e);
  const Limbs mb = shift_left(b.magnitude_, b.exponent_ - e);
  Dyadic r;
  r.exponent_ = e;
  if (a.negative_ == b.negative_) {
    r.magnitude_ = add_magnitudes(ma, mb);
    r.negative_ = a.negative_;
  } else if (compare_magnitudes(ma, mb) >= 0) {
    r.magnitude_ = subtract_magnitudes(ma, mb);
    r.negative_ = a.negative_;
  } else {
    r.magnitude_ = subtract_magnitudes(mb, ma);
    r.negative_ = b.negative_;
  }
  r.normalize();
  return r;
}

Dyadic operator-(const Dyadic& a, const Dyadic& b) { return a + (-b); }

Dyadic operator*(const Dyadic& a, const Dyadic& b) {
  Dyadic r;
  if (a.sign() == 0 || b.sign() == 0) return r;
  r.magnitude_ = multiply_magnitudes(a.magnitude_, b.magnitude_);
  r.exponent_ = a.exponent_ + b.exponent_;
  r.negative_ = a.negative_ != b.negative_;
  r.normalize();
  return r;
}

int compare(const Dyadic& a, const Dyadic& b) { return (a - b).sign(); }

int compare(const ExactFraction& a, const ExactFraction& b) { return compare(a.num * b.den, b.num * a.den); }

namespace {

using ExactVec = std::array<Dyadic, 3>;

ExactVec exact(const Vec3& v) { return {Dyadic(v.x()), Dyadic(v.y()), Dyadic(v.z())}; }
ExactVec operator-(const ExactVec& a, const ExactVec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Dyadic dot(const ExactVec& a, const ExactVec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
ExactVec cross(const ExactVec& a, const ExactVec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}

}  // namespace

ExactFraction exact_point_triangle_squared_distance(const Vec3& p, const Triangle& t) {
  const ExactVec q = exact(p);
  const std::array<ExactVec, 3> c = {exact(t[0]), exact(t[1]), exact(t[2])};
  std::array<ExactVec, 3> w, e;  // w[k] = p - corner k, e[k] = corner k+1 - corner k
  for (int k = 0; k < 3; ++k) {
    w[static_cast<size_t>(k)] = q - c[static_cast<size_t>(k)];
    e[static_cast<size_t>(k)] = c[static_cast<size_t>((k + 1) % 3)] - c[static_cast<size_t>(k)];
  }
  const Dyadic one(1.0);
  ExactFraction best{dot(w[0], w[0]), one};
  auto consider = [&](ExactFraction f) {
    if (compare(f, best) < 0) best = std::move(f);
  };
  for (size_t k = 0; k < 3; ++k) {
    consider({dot(w[k], w[k]), one});
    const Dyadic ee = dot(e[k], e[k]);
    if (ee.sign() <= 0) continue;
    const Dyadic s = dot(w[k], e[k]);  // the foot's parameter along the edge, times ee
    if (s.sign() > 0 && compare(s, ee) < 0) consider({dot(w[k], w[k]) * ee - s * s, ee});
  }
  const ExactVec n = cross(e[0], c[2] - c[0]);
  const Dyadic nn = dot(n, n);
  if (nn.sign() > 0) {
    bool inside = true;
    for (size_t k = 0; k < 3 && inside; ++k) inside = dot(cross(e[k], w[k]), n).sign() >= 0;
    if (inside) {
      const Dyadic h = dot(n, w[0]);
      consider({h * h, nn});
    }
  }
  return best;
}

}  // namespace vproxq
