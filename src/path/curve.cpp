// Exact path primitives: lines and the curve p(u) = c + A cos u + B sin u + V u, with
// arc-length parametrisation. For circles and helices |p'| is constant (closed form); for
// other curves the cumulative length is tabulated with 5-point Gauss-Legendre per span of at
// most 1/8 rad and inverted by safeguarded Newton steps on the same quadrature.
#include <algorithm>
#include <array>
#include <cmath>

#include "common/sincos.hpp"
#include "trochomill/error.hpp"
#include "trochomill/path.hpp"

namespace trochomill {
namespace {

constexpr double kSpansPerRadian = 8.0;
// 5-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr std::array<double, 5> kGlX = {-0.9061798459386640, -0.5384693101056831, 0.0,
                                        0.5384693101056831, 0.9061798459386640};
constexpr std::array<double, 5> kGlW = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889,
                                        0.4786286704993665, 0.2369268850561891};

bool close_rel(double a, double b, double scale) {
  return std::abs(a - b) <= 1e-12 * std::max(scale, 1.0);
}

}  // namespace

Segment Segment::line(const Vec3& p0, const Vec3& p1, Motion motion, double speed_mm_per_min) {
  Segment s;
  s.kind_ = Kind::line;
  s.motion_ = motion;
  s.speed_mm_per_min_ = speed_mm_per_min;
  s.c_ = p0;
  s.v_ = p1 - p0;
  s.u0_ = 0;
  s.u1_ = 1;
  s.length_mm_ = s.v_.norm();
  s.speed_u_ = s.length_mm_;
  return s;
}

Segment Segment::curve(const Vec3& center, const Vec3& a, const Vec3& b, const Vec3& v,
                       double u0_rad, double u1_rad, Motion motion, double speed_mm_per_min) {
  Segment s;
  s.kind_ = Kind::curve;
  s.motion_ = motion;
  s.speed_mm_per_min_ = speed_mm_per_min;
  s.c_ = center;
  s.a_ = a;
  s.b_ = b;
  s.v_ = v;
  s.u0_ = u0_rad;
  s.u1_ = u1_rad;
  s.build_length_table();
  return s;
}

Segment Segment::arc_xy(double cx, double cy, double radius_mm, double start_angle_rad,
                        double sweep_rad, double z0_mm, double z1_mm, Motion motion,
                        double speed_mm_per_min) {
  const Vec3 c(cx, cy, z0_mm);
  const Vec3 a(radius_mm * std::cos(start_angle_rad), radius_mm * std::sin(start_angle_rad), 0);
  const Vec3 b(-radius_mm * std::sin(start_angle_rad), radius_mm * std::cos(start_angle_rad), 0);
  const Vec3 v(0, 0, sweep_rad != 0 ? (z1_mm - z0_mm) / sweep_rad : 0.0);
  return curve(c, a, b, v, 0.0, sweep_rad, motion, speed_mm_per_min);
}

Vec3 Segment::point_u(double u) const {
  if (kind_ == Kind::line) return c_ + u * v_;
  return c_ + a_ * std::cos(u) + b_ * std::sin(u) + v_ * u;
}

Vec3 Segment::derivative_u(double u) const {
  if (kind_ == Kind::line) return v_;
  return -a_ * std::sin(u) + b_ * std::cos(u) + v_;
}

Vec3 Segment::second_derivative_u(double u) const {
  if (kind_ == Kind::line) return Vec3::Zero();
  return -a_ * std::cos(u) - b_ * std::sin(u);
}

bool Segment::is_circular() const noexcept {
  if (kind_ != Kind::curve) return false;
  const double ra = a_.norm(), rb = b_.norm();
  const double scale = std::max(ra, rb);
  return close_rel(ra, rb, scale) && std::abs(a_.dot(b_)) <= 1e-12 * scale * scale &&
         std::abs(a_.dot(v_)) <= 1e-12 * scale * std::max(1.0, v_.norm()) &&
         std::abs(b_.dot(v_)) <= 1e-12 * scale * std::max(1.0, v_.norm());
}

bool Segment::is_flat_xy() const noexcept {
  if (kind_ == Kind::line) return std::abs(v_.z()) <= 1e-12;
  return std::abs(a_.z()) <= 1e-12 && std::abs(b_.z()) <= 1e-12 && std::abs(v_.z()) <= 1e-12;
}

void Segment::build_length_table() {
  const double du = u1_ - u0_;
  cum_length_.clear();
  if (is_circular()) {
    // |p'|^2 = r^2 + |V|^2 exactly (A, B orthogonal of equal length, V normal to both).
    speed_u_ = std::sqrt(a_.squaredNorm() + v_.squaredNorm());
    length_mm_ = speed_u_ * std::abs(du);
    return;
  }
  speed_u_ = 0;
  const int spans = std::max(4, static_cast<int>(std::ceil(std::abs(du) * kSpansPerRadian)));
  cum_length_.resize(spans + 1);
  cum_length_[0] = 0;
  const double h = du / spans;
  for (int i = 0; i < spans; ++i) {
    const double ua = u0_ + h * i;
    double sum = 0;
    for (std::size_t k = 0; k < kGlX.size(); ++k) {
      sum += kGlW[k] * derivative_u(ua + 0.5 * h * (kGlX[k] + 1.0)).norm();
    }
    cum_length_[i + 1] = cum_length_[i] + 0.5 * std::abs(h) * sum;
  }
  length_mm_ = cum_length_.back();
}

double Segment::u_at_length(double s_mm) const {
  const double du = u1_ - u0_;
  if (length_mm_ <= 0) return u0_;
  s_mm = std::clamp(s_mm, 0.0, length_mm_);
  if (cum_length_.empty()) return u0_ + du * (s_mm / length_mm_);
  const int spans = static_cast<int>(cum_length_.size()) - 1;
  const auto it = std::upper_bound(cum_length_.begin(), cum_length_.end(), s_mm);
  const int i = std::clamp(static_cast<int>(it - cum_length_.begin()) - 1, 0, spans - 1);
  const double h = du / spans;
  const double ua = u0_ + h * i;
  const double target = s_mm - cum_length_[i];
  const double span_len = cum_length_[i + 1] - cum_length_[i];
  // |p'(u)| with the sine and cosine from the table (within 2.2e-16 of libm's): this Newton
  // takes some twenty of them a sample, and sampling a program's elliptical orbits was a tenth
  // of `analyze`. (The length's tolerance below, 1e-13 of the segment, is far above that.)
  const detail::SinCosTable& table = detail::sincos_table();
  auto speed_at = [&](double u) {
    const detail::SinCos q = table(u);
    return (-a_ * q.s + b_ * q.c + v_).norm();
  };
  // Length from ua to u by 5-point Gauss-Legendre (exact enough within one short span).
  auto length_to = [&](double u) {
    const double w = u - ua;
    double sum = 0;
    for (std::size_t k = 0; k < kGlX.size(); ++k) {
      sum += kGlW[k] * speed_at(ua + 0.5 * w * (kGlX[k] + 1.0));
    }
    return 0.5 * std::abs(w) * sum;
  };
  // Safeguarded Newton in the fraction f of the span: bracket [lo, hi] shrinks each step.
  double lo = 0, hi = 1;
  double f = span_len > 0 ? target / span_len : 0.0;
  for (int iter = 0; iter < 50; ++iter) {
    const double u = ua + h * f;
    const double err = length_to(u) - target;
    if (std::abs(err) <= 1e-13 * std::max(1.0, length_mm_)) break;
    if (err > 0)
      hi = f;
    else
      lo = f;
    const double speed = speed_at(u) * std::abs(h);
    double next = speed > 0 ? f - err / speed : 0.5 * (lo + hi);
    if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
    f = next;
  }
  return ua + h * f;
}

Segment::Frame Segment::frame_at(double s_mm) const {
  const double u = u_at_length(s_mm);
  Frame f;
  f.point = point_u(u);
  const Vec3 d1 = derivative_u(u);
  const double n = d1.norm();
  f.tangent = n > 0 ? Vec3(d1 / n * (u1_ >= u0_ ? 1.0 : -1.0)) : Vec3::Zero();
  if (kind_ == Kind::curve && n > 0) {
    f.curvature_per_mm = d1.cross(second_derivative_u(u)).norm() / (n * n * n);
  }
  return f;
}

Vec3 Segment::tangent_at(double s_mm) const {
  const Vec3 d = derivative_u(u_at_length(s_mm)) * (u1_ >= u0_ ? 1.0 : -1.0);
  const double n = d.norm();
  return n > 0 ? Vec3(d / n) : Vec3::Zero();
}

double Segment::curvature_at(double s_mm) const {
  if (kind_ == Kind::line) return 0.0;
  const double u = u_at_length(s_mm);
  const Vec3 d1 = derivative_u(u), d2 = second_derivative_u(u);
  const double n = d1.norm();
  return n > 0 ? d1.cross(d2).norm() / (n * n * n) : 0.0;
}

}  // namespace trochomill
