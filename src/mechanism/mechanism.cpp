// Mechanism curves over a cycle, zone shares and the step / feed recommendation
// (include/trochomill/mechanism.hpp, docs/models.md section 9).
#include "trochomill/mechanism.hpp"

#include <fmt/format.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_for_each.h>

#include <algorithm>
#include <cmath>

#include "common/sincos.hpp"
#include "mechanism/internal.hpp"
#include "trochomill/error.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

int zone_of(double k, const MechanismThresholds& t) {
  if (k < t.czi_max_pct) return 1;
  if (k < t.czii_max_pct) return 2;
  return 3;
}

}  // namespace

namespace {

struct CycleSetup {
  double a, b, s, R, fz, feed, edge_speed;
};

CycleSetup setup(const Job& job, const MechanismSettings& st) {
  if (job.path.type != PathType::trochoidal && job.path.type != PathType::elliptical) {
    throw InputError(fmt::format(
        "the mechanism model needs [path] type = \"trochoidal\" or \"elliptical\" (a closed "
        "trochoid cycle), got \"{}\"",
        to_string(job.path.type)));
  }
  if (!(job.tool.edge_radius_mm > 0)) {
    throw InputError(
        "[tool] edge_radius must be > 0 mm for the mechanism model (K_re = h / r_e); "
        "a ground carbide edge is typically 0.005-0.03 mm");
  }
  if (st.model == ChipModel::pivkin2025 && job.path.type != PathType::trochoidal) {
    throw InputError(
        "the pivkin2025 model is published for the circular trochoid: it needs [path] type = "
        "\"trochoidal\" (use " +
        option_name("model") + " exact for the elliptical family)");
  }
  if (st.points < 36) throw InputError(fmt::format("points must be >= 36, got {}", st.points));
  CycleSetup c;
  const SlotGeometry sg = slot_geometry(job);
  c.R = sg.tool_radius_mm;
  c.a = sg.orbit_a_mm;
  if (!(c.a > 0)) {
    throw InputError(fmt::format("the slot ({} mm) must be wider than the tool ({} mm)",
                                 job.slot.width_mm, job.tool.diameter_mm));
  }
  c.b = sg.orbit_b_mm;
  c.s = sg.step_mm;
  c.fz = job.cutting.feed_per_tooth_mm;
  c.feed = feed_rate_mm_per_min(job) / 60.0;
  c.edge_speed = rpm_to_rad_per_s(spindle_speed_rpm(job)) * c.R;
  return c;
}

double path_speed(const CycleSetup& g, double th) {     // |c'(theta)| (mm/rad)
  const detail::SinCos q = detail::sincos_table()(th);  // within 2.2e-16 of libm's, faster
  const double x = g.a * q.s, y = g.b * q.c + g.s / kTwoPi;
  return std::sqrt(x * x + y * y);
}

// Time (s) from theta = 0 to theta along the cycle: Simpson's rule on |c'| / f_r with
// `n` (even) intervals.
double time_to(const CycleSetup& g, double theta, int n) {
  double sum = 0;
  for (int k = 0; k <= n; ++k) {
    const double w = (k == 0 || k == n) ? 1 : (k % 2 ? 4 : 2);
    sum += w * path_speed(g, theta * k / n);
  }
  return sum * (theta / n) / 3 / g.feed;
}

// The chip columns of a curve, written in place (no array of points in between: a cycle's
// columns are a few hundred kB, and fresh pages cost as much as the model's arithmetic).
struct ChipColumns {
  double* h;
  double* psi;
  double* kappa;
  [[nodiscard]] mech::ChipPoint get(std::size_t i) const { return {h[i], psi[i], kappa[i]}; }
  void set(std::size_t i, const mech::ChipPoint& p) const {
    h[i] = p.h_mm;
    psi[i] = p.psi_rad;
    kappa[i] = p.kappa_rad;
  }
};

// The exact model on the uniform grid theta_i = 2 pi i / n of a whole cycle, adaptively:
// direct evaluations on every `stride`-th point (about every 9 degrees), then each interval is
// bisected on the grid until the midpoint's direct value agrees with the interpolation from the
// interval's ends (h within 2e-3 f_z, psi within 3e-3 rad, kappa within 1e-4 rad) and all three
// points agree on cutting or not; the points between are then filled by the quadratic through the
// three. The start and end of cutting are thus resolved to the grid (a cycle of a closed orbit
// cuts on one arc: an engagement shorter than ~4.5 degrees between two non-cutting samples could
// be missed), and the curve agrees with direct evaluation at every point within about those
// tolerances (test Mechanism.AdaptiveCycleMatchesDirect; measured: h within 3.3e-4 f_z, psi
// within 2e-3 rad over 18 cases). The columns start at zero.
void exact_cycle(const mech::ExactModel& model, std::size_t n, double fz, const ChipColumns& pts) {
  if (n == 0) return;
  auto theta = [n](std::size_t i) {
    return kTwoPi * static_cast<double>(i) / static_cast<double>(n);
  };
  const std::size_t stride = std::max<std::size_t>(1, n / 40);  // ~9 degrees
  const std::size_t nc = (n + stride - 1) / stride;
  // Coarse points (index nc stands for i = n, the next cycle's theta = 0: the same point), one
  // task each: the cutting half costs several times the other, so no blocks of them.
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, nc, 1),
      [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t k = r.begin(); k < r.end(); ++k) {
          pts.set(k * stride, model.at(theta(k * stride)));
        }
      },
      tbb::simple_partitioner());
  const double tol_h = 2e-3 * fz, tol_psi = 3e-3, tol_kappa = 1e-4;
  auto at = [&](std::size_t i) { return pts.get(i % n); };
  // Every span is a task: it evaluates its midpoint and either fills its points or feeds its
  // two halves back as tasks (a span near the start of the cut splits a dozen times, so one
  // task per coarse interval would leave the other thread idle). A span reads only its ends,
  // written before it was fed, and writes only inside itself: the same result whatever the
  // thread count or order.
  struct Span {
    std::size_t i0, i1;
  };
  std::vector<Span> spans(nc);
  for (std::size_t k = 0; k < nc; ++k) spans[k] = {k * stride, std::min(n, (k + 1) * stride)};
  tbb::parallel_for_each(spans.begin(), spans.end(), [&](Span sp, tbb::feeder<Span>& feeder) {
    if (sp.i1 - sp.i0 <= 1) return;
    const std::size_t m = (sp.i0 + sp.i1) / 2;
    const mech::ChipPoint pm = model.at(theta(m));
    pts.set(m, pm);
    const mech::ChipPoint p0 = at(sp.i0), p1 = at(sp.i1);
    const double w = static_cast<double>(m - sp.i0) / static_cast<double>(sp.i1 - sp.i0);
    auto lerp = [w](double a, double b) { return a + w * (b - a); };
    const bool same = (p0.h_mm > 0) == (pm.h_mm > 0) && (pm.h_mm > 0) == (p1.h_mm > 0);
    if (!same || std::abs(pm.h_mm - lerp(p0.h_mm, p1.h_mm)) > tol_h ||
        std::abs(pm.psi_rad - lerp(p0.psi_rad, p1.psi_rad)) > tol_psi ||
        std::abs(pm.kappa_rad - lerp(p0.kappa_rad, p1.kappa_rad)) > tol_kappa) {
      feeder.add({sp.i0, m});
      feeder.add({m, sp.i1});
      return;
    }
    // Quadratic (Lagrange) through (i0, m, i1) for the points between.
    const double x0 = static_cast<double>(sp.i0), xm = static_cast<double>(m),
                 x1 = static_cast<double>(sp.i1);
    for (std::size_t i = sp.i0 + 1; i < sp.i1; ++i) {
      if (i == m) continue;
      const double x = static_cast<double>(i);
      const double l0 = (x - xm) * (x - x1) / ((x0 - xm) * (x0 - x1));
      const double lm = (x - x0) * (x - x1) / ((xm - x0) * (xm - x1));
      const double l1 = (x - x0) * (x - xm) / ((x1 - x0) * (x1 - xm));
      auto q = [&](double a, double b, double c) { return l0 * a + lm * b + l1 * c; };
      if (pm.h_mm > 0) {
        pts.h[i] = std::max(0.0, q(p0.h_mm, pm.h_mm, p1.h_mm));
        pts.psi[i] = std::max(0.0, q(p0.psi_rad, pm.psi_rad, p1.psi_rad));
        pts.kappa[i] = q(p0.kappa_rad, pm.kappa_rad, p1.kappa_rad);
      } else {  // not cutting: psi may still be positive (engaged without a chip)
        pts.psi[i] = std::max(0.0, q(p0.psi_rad, pm.psi_rad, p1.psi_rad));
      }
    }
  });
}

// The chip at the given angles; `uniform_cycle`: they are the uniform grid of a whole cycle
// (the exact model then samples adaptively, see exact_cycle).
// (The columns start at zero.)
void chip_points(const Job& job, const MechanismSettings& st, const CycleSetup& g,
                 const std::vector<double>& thetas, bool uniform_cycle, const ChipColumns& pts) {
  const std::size_t n = thetas.size();
  if (st.model == ChipModel::pivkin2025) {
    // Closed form, point by point in blocks on TBB's threads (each point its own slots: the
    // same numbers whatever the thread count). Pivkin's theta is ours + pi/2.
    const Pivkin2025 model(2 * g.a, g.s, 2 * g.R, g.fz, job.tool.teeth);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 256),
                      [&](const tbb::blocked_range<std::size_t>& r) {
                        for (std::size_t i = r.begin(); i < r.end(); ++i) {
                          const Pivkin2025::Point p = model.at(thetas[i] + 0.5 * kPi);
                          if (p.cutting) pts.set(i, {p.h_mm, p.psi_rad, p.kappa_rad});
                        }
                      });
    return;
  }
  const mech::ExactModel model(g.a, g.b, g.s, g.R, g.fz, g.feed, g.edge_speed);
  if (uniform_cycle) {
    exact_cycle(model, n, g.fz, pts);
    return;
  }
  // Every theta is independent: evaluated in parallel, each result in its own slot (the
  // same numbers whatever the thread count).
  tbb::parallel_for(std::size_t{0}, n, [&](std::size_t i) { pts.set(i, model.at(thetas[i])); });
}

// Every column at the given angles (kept as the curve's theta_rad); t_s left to the caller,
// which finds the path's speed |c'| there when it is a whole cycle (`uniform_cycle`).
MechanismCurve evaluate(const Job& job, const MechanismSettings& st, const CycleSetup& g,
                        std::vector<double> thetas, bool use_wear, bool uniform_cycle) {
  MechanismCurve c;
  c.model = st.model;
  c.edge_radius_mm = job.tool.edge_radius_mm;
  const std::size_t n = thetas.size();
  c.theta_rad = std::move(thetas);
  for (auto* v : {&c.t_s, &c.h_mm, &c.psi_rad, &c.teeth_in_contact, &c.gamma_k_rad, &c.kappa_rad,
                  &c.k_re_pct, &c.k_re_wear_pct}) {
    v->resize(n);
  }
  c.zone.resize(n);
  chip_points(job, st, g, c.theta_rad, uniform_cycle,
              ChipColumns{c.h_mm.data(), c.psi_rad.data(), c.kappa_rad.data()});
  const double re = job.tool.edge_radius_mm, vb = job.tool.flank_wear_mm;
  // Point by point, with the path's speed for a whole cycle, in blocks on TBB's threads (each
  // point its own slots: the same numbers whatever the thread count; run serially, these were
  // a quarter of a 3600-point cycle on two cores).
  tbb::parallel_for(
      tbb::blocked_range<std::size_t>(0, n, 512), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t i = r.begin(); i < r.end(); ++i) {
          const mech::ChipPoint p{c.h_mm[i], c.psi_rad[i], c.kappa_rad[i]};
          c.teeth_in_contact[i] = p.psi_rad * job.tool.teeth / kTwoPi;
          // asin(1) is pi / 2 to the last bit: no call where nothing is cut (half the cycle).
          c.gamma_k_rad[i] = p.h_mm <= 0   ? -0.5 * kPi
                             : p.h_mm < re ? -std::asin((re - p.h_mm) / re)
                                           : 0.0;
          c.k_re_pct[i] = 100.0 * p.h_mm / re;
          c.k_re_wear_pct[i] =
              100.0 * (p.h_mm + (p.kappa_rad > 0 && vb > 0 ? vb * std::tan(p.kappa_rad) : 0.0)) /
              re;
          const double k = use_wear ? c.k_re_wear_pct[i] : c.k_re_pct[i];
          c.zone[i] = p.h_mm > 0 ? zone_of(k, st.thresholds) : 0;
          if (uniform_cycle) c.t_s[i] = path_speed(g, c.theta_rad[i]);
        }
      });
  c.cycle_time_s = time_to(g, kTwoPi, 512);
  return c;
}

}  // namespace

MechanismCurve mechanism_curve(const Job& job, const MechanismSettings& st, bool use_wear) {
  const CycleSetup g = setup(job, st);
  const auto n = static_cast<std::size_t>(st.points);
  std::vector<double> thetas(n);
  for (std::size_t i = 0; i < n; ++i)
    thetas[i] = kTwoPi * static_cast<double>(i) / static_cast<double>(n);
  MechanismCurve c = evaluate(job, st, g, std::move(thetas), use_wear, true);
  // Time from theta = 0: trapezoid rule on |c'| / f_r between the samples (evaluate left
  // the speeds in t_s; summed in order in place).
  const std::vector<double>& th = c.theta_rad;
  std::vector<double>& t = c.t_s;
  double prev = n > 0 ? t[0] : 0.0;
  if (n > 0) t[0] = 0;
  for (std::size_t i = 1; i < n; ++i) {
    const double cur = t[i];
    t[i] = t[i - 1] + 0.5 * (cur + prev) * (th[i] - th[i - 1]) / g.feed;
    prev = cur;
  }
  return c;
}

MechanismCurve mechanism_curve_at(const Job& job, const MechanismSettings& st,
                                  const std::vector<double>& theta_rad, bool use_wear) {
  const CycleSetup g = setup(job, st);
  MechanismCurve c = evaluate(job, st, g, theta_rad, use_wear, false);
  for (std::size_t i = 0; i < theta_rad.size(); ++i) {
    c.t_s[i] = time_to(g, theta_rad[i], 64);
  }
  return c;
}

ZoneSummary summarize_zones(const MechanismCurve& c, const MechanismSettings& st, bool use_wear) {
  ZoneSummary z;
  const std::size_t n = c.theta_rad.size();
  if (n == 0) return z;
  // The cutting part starts where cutting resumes after a pause (cyclically).
  std::size_t start = 0;
  bool found = false;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t prev = (i + n - 1) % n;
    if (c.zone[i] != 0 && c.zone[prev] == 0) {
      start = i;
      found = true;
      break;
    }
  }
  z.cutting_start_s = found ? c.t_s[start] : 0.0;
  double dur[3] = {0, 0, 0};
  double tt = 0;  // time from the start of cutting
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = (start + k) % n, j = (i + 1) % n;
    const double dt = j == 0 ? c.cycle_time_s - c.t_s[i] : c.t_s[j] - c.t_s[i];
    const int zone = c.zone[i];
    if (zone > 0) {
      dur[zone - 1] += dt;
      if (z.start_s[zone - 1] < 0) z.start_s[zone - 1] = tt;
      z.end_s[zone - 1] = tt + dt;
      z.h_max_mm = std::max(z.h_max_mm, c.h_mm[i]);
      const double kre = use_wear ? c.k_re_wear_pct[i] : c.k_re_pct[i];
      if (z.transition_s < 0 && kre >= st.thresholds.transition_pct) z.transition_s = tt;
    }
    tt += dt;
  }
  z.cutting_time_s = dur[0] + dur[1] + dur[2];
  // The first half of the cut: from its start to the middle of its span (the end of the last
  // cutting sample, the latest zone end); CZI's time in it, pieces split at the middle.
  if (found) {
    z.cutting_span_s = std::max({0.0, z.end_s[0], z.end_s[1], z.end_s[2]});
    const double half = 0.5 * z.cutting_span_s;
    double czi = 0;
    tt = 0;
    for (std::size_t k = 0; k < n && tt < half; ++k) {
      const std::size_t i = (start + k) % n, j = (i + 1) % n;
      const double dt = j == 0 ? c.cycle_time_s - c.t_s[i] : c.t_s[j] - c.t_s[i];
      if (c.zone[i] == 1) czi += std::min(tt + dt, half) - tt;
      tt += dt;
    }
    z.plunger_first_half_share = half > 0 ? czi / half : 0;
  }
  for (int q = 0; q < 3; ++q) {
    z.share[q] = z.cutting_time_s > 0 ? dur[q] / z.cutting_time_s : 0;
    z.cycle_share[q] = c.cycle_time_s > 0 ? dur[q] / c.cycle_time_s : 0;
  }
  z.h_m_mm = c.edge_radius_mm * (1 - std::cos(deg_to_rad(st.friction_angle_deg)));
  return z;
}

Recommendation recommend(const Job& job, const MechanismSettings& st, bool use_wear,
                         bool for_feed) {
  if (!(st.share > 0 && st.share <= 1)) {
    throw InputError(fmt::format("share must be in (0, 1], got {}", st.share));
  }
  if (!(st.plunger_share >= 0 && st.plunger_share < 1)) {
    throw InputError(fmt::format("plunger_share must be in [0, 1), got {}", st.plunger_share));
  }
  const bool plunger = st.criterion == Criterion::plunger;
  MechanismSettings coarse = st;
  coarse.points = std::min(st.points, 720);  // the search; the answer is re-evaluated finely
  const bool of_cycle = st.share_of == ShareOf::cycle;
  const auto cziii = [&](const ZoneSummary& z) { return of_cycle ? z.cycle_share[2] : z.share[2]; };
  const double R = job.tool.radius_mm();
  auto eval = [&](double v, const MechanismSettings& s) {
    Job j = job;
    if (for_feed) {  // same spindle speed: the feed rate follows f_z
      j.cutting.feed_per_tooth_mm = v;
      j.cutting.feed_rate_mm_per_min = v * j.cutting.spindle_speed_rpm * j.tool.teeth;
    } else {
      j.path.step_mm = v;
    }
    return summarize_zones(mechanism_curve(j, s, use_wear), s, use_wear);
  };
  // Scan upwards on a coarse theta grid (steps up to the tool radius, feeds up to 0.5
  // mm/tooth) for the first bracket, then bisect it on the full grid to 0.1 % of the value:
  // where the share grows slowly (the whole cycle's, about 0.06 a mm of step on Pivkin's
  // example) the coarse grid's crossing is a few % off the full one's.
  const double lo_v = for_feed ? 1e-4 : 1e-3, hi_v = for_feed ? 0.5 : R;
  const auto met = [&](const ZoneSummary& z) {
    return plunger ? z.plunger_first_half_share <= st.plunger_share : cziii(z) >= st.share;
  };
  const auto holds = [&](double v, const MechanismSettings& s) { return met(eval(v, s)); };
  constexpr int kScan = 48;
  double prev = lo_v;
  Recommendation r;
  for (int k = 0; k <= kScan; ++k) {
    const double v = lo_v * std::pow(hi_v / lo_v, static_cast<double>(k) / kScan);
    if (holds(v, coarse)) {
      double a = k == 0 ? v : prev, b = v;
      // The full grid may disagree at the bracket's ends: widen it until it does not.
      for (int it = 0; it < 200 && !holds(b, st) && b < hi_v; ++it)
        a = b, b = std::min(hi_v, b * 1.01);
      for (int it = 0; it < 200 && a > lo_v && holds(a, st); ++it)
        b = a, a = std::max(lo_v, a / 1.01);
      if (a <= lo_v && holds(a, st)) b = a;  // the share holds from the scan's start
      for (int it = 0; it < 60 && (b - a) > 1e-3 * b; ++it) {
        const double m = 0.5 * (a + b);
        (holds(m, st) ? b : a) = m;
      }
      r.zones = eval(b, st);
      r.found = met(r.zones);
      r.value = b;
      break;
    }
    prev = v;
  }
  const char* what = for_feed ? "feed per tooth" : "trochoid step";
  const char* of = of_cycle ? "the cycle" : "the cutting part";
  const double* sh = of_cycle ? r.zones.cycle_share : r.zones.share;
  const std::string wear =
      use_wear ? fmt::format(", flank wear {:g} mm", job.tool.flank_wear_mm) : "";
  if (plunger) {
    r.explanation =
        r.found ? fmt::format(
                      "smallest {} {:.4g} mm keeps CZI (ploughing, K_re < {:g} %, r_e {:g} mm{}) "
                      "to {:.1f} % of the first half of the cut (at most {:g} %: Pivkin 2025's "
                      "plunger criterion); CZIII {:.0f} % of the cutting part",
                      what, r.value, st.thresholds.czi_max_pct, job.tool.edge_radius_mm, wear,
                      100 * r.zones.plunger_first_half_share, 100 * st.plunger_share,
                      100 * r.zones.share[2])
                : fmt::format(
                      "no {} up to {:g} mm keeps CZI to {:g} % of the first half of the cut: "
                      "the chip there stays below {:g} % of r_e = {:g} mm",
                      what, hi_v, 100 * st.plunger_share, st.thresholds.czi_max_pct,
                      job.tool.edge_radius_mm);
    return r;
  }
  if (r.found) {
    r.explanation = fmt::format(
        "smallest {} {:.4g} mm puts {:.0f} % of {} in CZIII (K_re >= {:g} %, r_e {:g} mm{}); "
        "CZI {:.0f} %, CZII {:.0f} %{}",
        what, r.value, 100 * sh[2], of, st.thresholds.czii_max_pct, job.tool.edge_radius_mm, wear,
        100 * sh[0], 100 * sh[1], of_cycle ? ", the rest not cutting" : "");
  } else {
    r.explanation = fmt::format(
        "no {} up to {:g} mm puts {:.0f} % of {} in CZIII{}", what, hi_v, 100 * st.share, of,
        of_cycle ? " (the cut is too short a part of the cycle, or its chip stays thin)"
                 : fmt::format(": the chip stays below {:g} % of r_e = {:g} mm",
                               st.thresholds.czii_max_pct, job.tool.edge_radius_mm));
  }
  return r;
}

}  // namespace trochomill
