// Cubic radial basis function interpolation with a linear polynomial, global or as a
// partition of unity of local interpolants (topography.hpp; docs/models.md section 13).
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>

#include "trochomill/error.hpp"
#include "trochomill/topography.hpp"

namespace trochomill {

namespace {

// Solves the interpolation system [Phi P; P^T 0] [w; c] = [f; 0] in coordinates centred on
// (su, sv).
void solve_patch(const std::vector<std::array<double, 2>>& x, const std::vector<double>& f,
                 double su, double sv, std::vector<double>& w, std::array<double, 3>& poly) {
  const auto n = static_cast<Eigen::Index>(x.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(n + 3, n + 3);
  Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 3);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double ui = x[static_cast<std::size_t>(i)][0] - su,
                 vi = x[static_cast<std::size_t>(i)][1] - sv;
    for (Eigen::Index j = 0; j < i; ++j) {
      const double du = ui - (x[static_cast<std::size_t>(j)][0] - su),
                   dv = vi - (x[static_cast<std::size_t>(j)][1] - sv);
      const double r = std::sqrt(du * du + dv * dv);
      a(i, j) = a(j, i) = r * r * r;
    }
    a(i, n) = a(n, i) = 1;
    a(i, n + 1) = a(n + 1, i) = ui;
    a(i, n + 2) = a(n + 2, i) = vi;
    b(i) = f[static_cast<std::size_t>(i)];
  }
  const Eigen::VectorXd sol = a.partialPivLu().solve(b);
  w.assign(sol.data(), sol.data() + n);
  poly = {sol(n), sol(n + 1), sol(n + 2)};
}

double wendland(double r) {  // C2, support 1
  if (r >= 1) return 0;
  const double t = 1 - r;
  return t * t * t * t * (4 * r + 1);
}

}  // namespace

CubicRbf::CubicRbf(std::vector<std::array<double, 2>> points, std::vector<double> values,
                   int patch_points) {
  if (points.size() != values.size()) {
    throw InputError(fmt::format("RBF: {} points but {} values", points.size(), values.size()));
  }
  if (points.size() < 3) {
    throw InputError(fmt::format("RBF: need at least 3 points, got {}", points.size()));
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    if (!std::isfinite(points[i][0]) || !std::isfinite(points[i][1]) || !std::isfinite(values[i])) {
      throw InputError(fmt::format("RBF: point {} is not finite", i));
    }
  }
  double ulo = 1e300, uhi = -1e300, vlo = 1e300, vhi = -1e300;
  for (const auto& p : points) {
    ulo = std::min(ulo, p[0]), uhi = std::max(uhi, p[0]);
    vlo = std::min(vlo, p[1]), vhi = std::max(vhi, p[1]);
  }
  const std::size_t n = points.size();
  if (static_cast<int>(n) <= std::max(16, patch_points)) {
    Patch p;
    p.cu = 0.5 * (ulo + uhi), p.cv = 0.5 * (vlo + vhi), p.radius = 1e300;
    p.su = p.cu, p.sv = p.cv;
    solve_patch(points, values, p.su, p.sv, p.w, p.poly);
    p.x = std::move(points);
    patches_.push_back(std::move(p));
    return;
  }
  // Partition of unity: square cells holding ~`per_cell` points on average; one patch per
  // non-empty cell, centred on it, with a support radius reaching past the cell's corners and
  // grown until it holds at least `min_pts` points.
  const double per_cell = 36, min_pts = 40;
  const double wu = std::max(uhi - ulo, 1e-9), wv = std::max(vhi - vlo, 1e-9);
  cell_ = std::sqrt(wu * wv * per_cell / static_cast<double>(n));
  cell_ = std::max(cell_, std::max(wu, wv) / 4096.0);
  u0_ = ulo, v0_ = vlo;
  nu_ = std::max(1, static_cast<int>(std::ceil(wu / cell_)));
  nv_ = std::max(1, static_cast<int>(std::ceil(wv / cell_)));
  std::vector<std::vector<int>> bins(static_cast<std::size_t>(nu_ * nv_));
  const auto cell_of = [&](double u, double v) {
    const int i = std::clamp(static_cast<int>((u - u0_) / cell_), 0, nu_ - 1);
    const int j = std::clamp(static_cast<int>((v - v0_) / cell_), 0, nv_ - 1);
    return i * nv_ + j;
  };
  for (std::size_t k = 0; k < n; ++k) {
    bins[static_cast<std::size_t>(cell_of(points[k][0], points[k][1]))].push_back(
        static_cast<int>(k));
  }
  std::vector<int> centres;
  for (int c = 0; c < nu_ * nv_; ++c) {
    if (!bins[static_cast<std::size_t>(c)].empty()) centres.push_back(c);
  }
  patches_.resize(centres.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, centres.size()), [&](const auto& rg) {
    for (std::size_t q = rg.begin(); q != rg.end(); ++q) {
      const int c = centres[q], ci = c / nv_, cj = c % nv_;
      Patch& p = patches_[q];
      p.cu = u0_ + (ci + 0.5) * cell_, p.cv = v0_ + (cj + 0.5) * cell_;
      double radius = cell_;
      for (int grow = 0; grow < 64; ++grow) {
        p.x.clear();
        std::vector<double> f;
        const int reach = static_cast<int>(std::ceil(radius / cell_));
        for (int i = std::max(0, ci - reach); i <= std::min(nu_ - 1, ci + reach); ++i) {
          for (int j = std::max(0, cj - reach); j <= std::min(nv_ - 1, cj + reach); ++j) {
            for (const int k : bins[static_cast<std::size_t>(i * nv_ + j)]) {
              const auto& x = points[static_cast<std::size_t>(k)];
              if (std::hypot(x[0] - p.cu, x[1] - p.cv) < radius) {
                p.x.push_back(x);
                f.push_back(values[static_cast<std::size_t>(k)]);
              }
            }
          }
        }
        if (static_cast<double>(p.x.size()) >= std::min(min_pts, static_cast<double>(n)) ||
            radius > 2 * (wu + wv)) {
          p.radius = radius;
          p.su = p.cu, p.sv = p.cv;
          solve_patch(p.x, f, p.su, p.sv, p.w, p.poly);
          break;
        }
        radius *= 1.25;
      }
    }
  });
  // Per cell, the patches whose support reaches it.
  cells_.assign(static_cast<std::size_t>(nu_ * nv_), {});
  for (std::size_t q = 0; q < patches_.size(); ++q) {
    const Patch& p = patches_[q];
    const int i0 = std::max(0, static_cast<int>(std::floor((p.cu - p.radius - u0_) / cell_)));
    const int i1 = std::min(nu_ - 1, static_cast<int>(std::floor((p.cu + p.radius - u0_) / cell_)));
    const int j0 = std::max(0, static_cast<int>(std::floor((p.cv - p.radius - v0_) / cell_)));
    const int j1 = std::min(nv_ - 1, static_cast<int>(std::floor((p.cv + p.radius - v0_) / cell_)));
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j)
        cells_[static_cast<std::size_t>(i * nv_ + j)].push_back(static_cast<int>(q));
    }
  }
}

double CubicRbf::eval_patch(const Patch& p, double u, double v) {
  const double lu = u - p.su, lv = v - p.sv;
  double s = p.poly[0] + p.poly[1] * lu + p.poly[2] * lv;
  for (std::size_t i = 0; i < p.x.size(); ++i) {
    const double du = lu - (p.x[i][0] - p.su), dv = lv - (p.x[i][1] - p.sv);
    const double r = std::sqrt(du * du + dv * dv);
    s += p.w[i] * r * r * r;
  }
  return s;
}

double CubicRbf::operator()(double u, double v) const {
  if (patches_.size() == 1 && cells_.empty()) return eval_patch(patches_[0], u, v);
  const int i = std::clamp(static_cast<int>(std::floor((u - u0_) / cell_)), 0, nu_ - 1);
  const int j = std::clamp(static_cast<int>(std::floor((v - v0_) / cell_)), 0, nv_ - 1);
  double num = 0, den = 0;
  int nearest = -1;
  double nearest_d = 1e300;
  for (const int q : cells_[static_cast<std::size_t>(i * nv_ + j)]) {
    const Patch& p = patches_[static_cast<std::size_t>(q)];
    const double d = std::hypot(u - p.cu, v - p.cv);
    const double wt = wendland(d / p.radius);
    if (wt > 0) num += wt * eval_patch(p, u, v), den += wt;
    if (d / p.radius < nearest_d) nearest_d = d / p.radius, nearest = q;
  }
  if (den > 0) return num / den;
  // Outside every support (beyond the data): the nearest patch's extrapolation.
  if (nearest < 0) {
    for (std::size_t q = 0; q < patches_.size(); ++q) {
      const double d = std::hypot(u - patches_[q].cu, v - patches_[q].cv) / patches_[q].radius;
      if (d < nearest_d) nearest_d = d, nearest = static_cast<int>(q);
    }
  }
  return eval_patch(patches_[static_cast<std::size_t>(nearest)], u, v);
}

}  // namespace trochomill
