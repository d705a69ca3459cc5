// The fast chip source: analytic engagement, axial discs and helix lag (force.hpp;
// docs/models.md section 12).
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "internal.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/force.hpp"
#include "trochomill/path.hpp"
#include "trochomill/units.hpp"

namespace trochomill {

namespace {

constexpr std::size_t kChunk = 256;
constexpr std::size_t kMaxTeeth = 64;  // as [tool] teeth allows

bool in_arcs(const std::vector<AngleArc>& arcs, double th) {
  for (const AngleArc& a : arcs) {
    double d = std::fmod(th - a.start_rad, kTwoPi);
    if (d < 0) d += kTwoPi;
    if (d <= a.sweep_rad()) return true;
  }
  return false;
}

}  // namespace

FastChipSource::FastChipSource(const Job& job, const ToolPath& path, double from_s, double to_s,
                               int steps_per_rev, const EngagementSeries* engagement,
                               const RunHooks& hooks)
    : spr_(steps_per_rev), hooks_(hooks) {
  const double dur = path.duration_s();
  from_s = std::max(0.0, from_s);
  to_s = std::min(dur, to_s);
  if (!(to_s > from_s)) {
    throw InputError(fmt::format("forces: empty window {:g}..{:g} s (the path lasts {:g} s)",
                                 from_s, to_s, dur));
  }
  if (steps_per_rev < 8) {
    throw InputError(fmt::format("fast chips: steps_per_rev must be >= 8, got {}", steps_per_rev));
  }
  const double w = rpm_to_rad_per_s(spindle_speed_rpm(job));
  if (!(w > 0)) throw InputError("fast chips: the spindle does not turn");
  dt_ = kTwoPi / (w * steps_per_rev);
  nsteps_ = static_cast<std::size_t>(std::ceil((to_s - from_s) / dt_ - 1e-9));

  // Centre positions on the step grid, from one revolution plus a step before the window.
  back_ = static_cast<std::size_t>(steps_per_rev) + 2;
  times_.resize(nsteps_ + back_ + 1);
  for (std::size_t g = 0; g < times_.size(); ++g) {
    times_[g] = from_s + (static_cast<double>(g) - static_cast<double>(back_)) * dt_;
  }
  // The engaged arcs (one sample per tooth pass over the whole path: the history matters)
  // beside the centre positions, sampled in blocks in parallel (each sample on its own: the
  // same for any thread count).
  const std::size_t blk = 16384, nb = (times_.size() + blk - 1) / blk;
  std::vector<PathSamples> parts(nb);
  if (engagement == nullptr) hooks.begin("engagement");
  tbb::parallel_invoke(
      [&] {
        if (engagement != nullptr) {
          eng_ = *engagement;
          return;
        }
        EngagementOptions eo;
        eo.hooks = hooks;
        eng_ = compute_engagement(path, job, eo);
      },
      [&] {
        tbb::parallel_for(std::size_t{0}, nb, [&](std::size_t b) {
          std::vector<double> ts(
              times_.begin() + static_cast<std::ptrdiff_t>(b * blk),
              times_.begin() + static_cast<std::ptrdiff_t>(std::min(times_.size(), (b + 1) * blk)));
          for (double& t : ts) t = std::clamp(t, 0.0, dur);
          parts[b] = sample_at_times(path, ts);
        });
      });
  for (const PathSamples& p : parts) {
    ps_.x_mm.insert(ps_.x_mm.end(), p.x_mm.begin(), p.x_mm.end());
    ps_.y_mm.insert(ps_.y_mm.end(), p.y_mm.begin(), p.y_mm.end());
    ps_.z_mm.insert(ps_.z_mm.end(), p.z_mm.begin(), p.z_mm.end());
  }
}

template <class Visit>
void FastChipSource::scan(const SimTool& tool, std::vector<SimStep>& steps,
                          const Visit& visit) const {
  const std::size_t nz = tool.tooth_angle_rad.size();
  const double w = std::abs(tool.omega_rad_per_s);
  if (nz == 0 || !(w > 0)) throw InputError("fast chips: the tool has no teeth or no speed");
  if (nz > kMaxTeeth) {
    throw InputError(fmt::format("fast chips: {} teeth; at most {}", nz, kMaxTeeth));
  }
  if (std::abs(w * dt_ * spr_ - kTwoPi) > 1e-9) {
    throw InputError("fast chips: the tool's spindle speed is not the job's");
  }
  const double dt = dt_;
  const std::size_t nsteps = nsteps_, back = back_;
  const std::vector<double>& times = times_;
  const PathSamples& ps = ps_;
  const EngagementSeries& eng = eng_;

  // Per tooth k, the earlier teeth j and how long ago (in steps, fractional) they passed the
  // same angle: the cutting-direction angle from j back to k, a full turn for k itself.
  struct Lag {
    double steps;
    double dr;  // R_k - R_j
    double dz;  // z_j - z_k: how far tooth j's tip sits above tooth k's
  };
  std::vector<std::vector<Lag>> lags(nz);
  for (std::size_t k = 0; k < nz; ++k) {
    for (std::size_t j = 0; j < nz; ++j) {
      double a = tool.omega_rad_per_s < 0 ? tool.tooth_angle_rad[k] - tool.tooth_angle_rad[j]
                                          : tool.tooth_angle_rad[j] - tool.tooth_angle_rad[k];
      a = std::fmod(a, kTwoPi);
      if (a < 0) a += kTwoPi;
      if (a < 1e-12) a = kTwoPi;
      lags[k].push_back({a / (w * dt), tool.radial_offset_mm[k] - tool.radial_offset_mm[j],
                         tool.axial_offset_mm[j] - tool.axial_offset_mm[k]});
    }
  }

  const int spt = tool.segments();
  const EdgeGrid grid = edge_grid(tool, 0.2);
  // The chip normal to the edge against tooth j's surface: the contours' offset along the
  // edge normal n = (n_r, n_z), (d . u + R_k - R_j) n_r + (z_j - z_k) (-n_z): on the
  // cylinder the radial offset, at the corner's bottom the axial one (the floor layer an
  // axially lower tooth cuts alone).
  struct Disc {
    double h_mid, h0, h1, sine, down;  // sine = n_r, down = -n_z
    double s0, width;                  // edge length at h0, and the segment's length
    double lag, cl, sl;  // helix lag angle (wrapped to [0, 2 pi)), its cosine and sine
  };
  std::vector<Disc> discs;
  const double total = tool.edge_length_at(tool.flute_length_mm);
  for (int k = 0; k < spt; ++k) {
    const double s0 = k * tool.segment_mm, s1 = std::min(total, (k + 1) * tool.segment_mm);
    const double hm = grid.at(k, 0).h_mm;
    double lag = std::fmod(hm * std::tan(tool.helix_rad) / tool.radius_mm, kTwoPi);
    if (lag < 0) lag += kTwoPi;
    const auto& n = grid.at(k, 0).normal;  // (n_r, 0, n_z)
    discs.push_back({hm, tool.height_at_length(s0), tool.height_at_length(s1), n[0], -n[2], s0,
                     s1 - s0, lag, std::cos(lag), std::sin(lag)});
  }

  steps.resize(nsteps);
  std::vector<double> tooth_wrapped(nz), tooth_cos(nz), tooth_sin(nz);
  for (std::size_t k = 0; k < nz; ++k) {
    double a = std::fmod(tool.tooth_angle_rad[k], kTwoPi);
    if (a < 0) a += kTwoPi;
    tooth_wrapped[k] = a, tooth_cos[k] = std::cos(a), tooth_sin[k] = std::sin(a);
  }
  // Steps in chunks of kChunk in parallel; the visitor writes per chunk or per step only, so
  // results are the same for any thread count.
  const std::size_t nchunks = (nsteps + kChunk - 1) / kChunk;
  hooks_.begin("chips");
  SharedProgress progress(hooks_, nchunks);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nchunks), [&](const auto& range) {
    for (std::size_t c = range.begin(); c != range.end(); ++c) {
      hooks_.check();
      progress.add(1);
      for (std::size_t i = c * kChunk; i < std::min(nsteps, (c + 1) * kChunk); ++i) {
        const std::size_t g = i + back + 1;
        const double t = times[g];
        SimStep& st = steps[i];
        st.t_s = t;
        st.tip_mm = {ps.x_mm[g], ps.y_mm[g], ps.z_mm[g]};
        // The engagement sample nearest in time.
        const auto it = std::lower_bound(eng.samples.t_s.begin(), eng.samples.t_s.end(), t);
        std::size_t e = static_cast<std::size_t>(it - eng.samples.t_s.begin());
        if (e == eng.samples.size() ||
            (e > 0 && t - eng.samples.t_s[e - 1] < eng.samples.t_s[e] - t)) {
          if (e > 0) --e;
        }
        if (e >= eng.arcs.size() || eng.arcs[e].empty()) continue;
        const auto& arcs = eng.arcs[e];
        double spin = std::fmod(tool.omega_rad_per_s * t, kTwoPi);
        if (spin < 0) spin += kTwoPi;
        const double cs = std::cos(spin), ss = std::sin(spin);
        std::array<double, 8> starts{};
        for (std::size_t q = 0; q < std::min<std::size_t>(arcs.size(), starts.size()); ++q) {
          double a = std::fmod(arcs[q].start_rad, kTwoPi);
          if (a < 0) a += kTwoPi;
          starts[q] = a;
        }
        double hsum = 0;
        int hn = 0;
        for (std::size_t k = 0; k < nz; ++k) {
          const double tip_z = ps.z_mm[g] + tool.axial_offset_mm[k];
          if (tip_z + discs[0].h0 >= 0) continue;  // the tooth is above the stock
          // The centre's displacement since each earlier tooth passed, once per tooth.
          std::array<double, kMaxTeeth> dx, dy, dr, dz;
          const std::size_t nl = lags[k].size();
          for (std::size_t q = 0; q < nl; ++q) {
            const Lag& l = lags[k][q];
            const double gp = static_cast<double>(g) - l.steps;
            const auto g0 = static_cast<std::size_t>(std::max(0.0, std::floor(gp)));
            const double f = std::clamp(gp - static_cast<double>(g0), 0.0, 1.0);
            const std::size_t g1 = std::min(g0 + 1, times.size() - 1);
            dx[q] = ps.x_mm[g] - (ps.x_mm[g0] + f * (ps.x_mm[g1] - ps.x_mm[g0]));
            dy[q] = ps.y_mm[g] - (ps.y_mm[g0] + f * (ps.y_mm[g1] - ps.y_mm[g0]));
            dr[q] = l.dr;
            dz[q] = l.dz;
          }
          // The tip angle: the tooth's own angle plus the spindle's, both in [0, 2 pi).
          double base = tooth_wrapped[k] + spin;
          if (base >= kTwoPi) base -= kTwoPi;
          const double cb = tooth_cos[k] * cs - tooth_sin[k] * ss;
          const double sb = tooth_sin[k] * cs + tooth_cos[k] * ss;
          // The engaged arcs relative to this tooth's tip angle, so each disc only adds its lag.
          struct Rel {
            double a0, sweep;
          };
          std::array<Rel, 8> rel{};
          const std::size_t na = std::min<std::size_t>(arcs.size(), rel.size());
          for (std::size_t q = 0; q < na; ++q) {
            double a = starts[q] - base;
            if (a < 0) a += kTwoPi;
            rel[q] = {a, arcs[q].sweep_rad()};
          }
          for (int d = 0; d < spt; ++d) {
            const Disc& dc = discs[static_cast<std::size_t>(d)];
            if (tip_z + dc.h0 >= 0) break;  // above the top face from here up
            // Engaged: the disc's lag (in [0, 2 pi) after wrapping) inside an arc.
            double off = dc.lag;
            bool in = false;
            if (arcs.size() > rel.size()) {
              in = in_arcs(arcs, base + off);
            } else {
              for (std::size_t q = 0; q < na && !in; ++q) {
                double dd = off - rel[q].a0;
                if (dd < 0) dd += kTwoPi;
                in = dd <= rel[q].sweep;
              }
            }
            if (!in) continue;
            const double h1 = std::min(dc.h1, -tip_z);
            const double width = h1 >= dc.h1 ? dc.width : tool.edge_length_at(h1) - dc.s0;
            if (!(width > 0)) continue;
            const double ux = cb * dc.cl - sb * dc.sl, uy = sb * dc.cl + cb * dc.sl;
            double h = 1e300;
            for (std::size_t q = 0; q < nl; ++q) {
              h = std::min(h, (dx[q] * ux + dy[q] * uy + dr[q]) * dc.sine + dz[q] * dc.down);
            }
            if (!(h > 0)) continue;
            visit(c, i, k, d, h, width, ux, uy);
            st.h_max_mm = std::max(st.h_max_mm, h);
            hsum += h;
            ++hn;
          }
        }
        st.engaged_segments = hn;
        st.h_mean_mm = hn > 0 ? hsum / hn : 0.0;
      }
    }
  });
}

SimResult FastChipSource::chips(const SimTool& tool) const {
  SimResult r;
  r.segments_per_tooth = tool.segments();
  const std::size_t nchunks = (nsteps_ + kChunk - 1) / kChunk;
  std::vector<std::vector<ChipEntry>> parts(nchunks);
  const int spt = r.segments_per_tooth;
  scan(tool, r.steps,
       [&](std::size_t c, std::size_t i, std::size_t k, int d, double h, double w, double, double) {
         ChipEntry ce;
         ce.step = static_cast<std::uint32_t>(i);
         ce.segment = static_cast<std::uint32_t>(k * static_cast<std::size_t>(spt) +
                                                 static_cast<std::size_t>(d));
         ce.h_mm = static_cast<float>(h);
         ce.w_mm = static_cast<float>(w);
         parts[c].push_back(ce);
       });
  std::size_t total = 0;
  for (const auto& p : parts) total += p.size();
  r.chip_map.reserve(total);
  for (const auto& p : parts) r.chip_map.insert(r.chip_map.end(), p.begin(), p.end());
  tally_steps(r);
  r.complete = true;
  return r;
}

ForceSeries FastChipSource::forces(const SimTool& tool, const EdgeGrid& grid,
                                   const SegmentForces& model,
                                   std::vector<SimStep>* steps_out) const {
  if (grid.segments != tool.segments()) {
    throw InputError(fmt::format("fast forces: the edge grid has {} segments, the tool {}",
                                 grid.segments, tool.segments()));
  }
  std::vector<SimStep> steps;
  ForceSeries s;
  const std::size_t nz = tool.tooth_angle_rad.size();
  s.teeth = static_cast<int>(nz);
  const std::size_t nt = nsteps_ * nz;
  s.tooth_fx_n.assign(nt, 0.0), s.tooth_fy_n.assign(nt, 0.0), s.tooth_fz_n.assign(nt, 0.0);
  s.tooth_torque_nm.assign(nt, 0.0);
  const double dir = tool.omega_rad_per_s < 0 ? -1.0 : 1.0;
  // The chip's force, rotated at the disc's angle (cosine and sine from the scan), summed per
  // step and tooth in the scan's order.
  scan(tool, steps,
       [&](std::size_t, std::size_t i, std::size_t k, int d, double h, double w, double ct,
           double st) {
         // The record's precision: chips are stored as float in the simulation's format.
         add_segment_force(s, i * nz + k,
                           model.force(d, static_cast<float>(h), static_cast<float>(w)), ct, st,
                           dir, grid.at(d, 0).r_mm);
       });
  s.t_s.resize(steps.size());
  for (std::size_t i = 0; i < steps.size(); ++i) s.t_s[i] = steps[i].t_s;
  sum_teeth(s, std::abs(tool.omega_rad_per_s));
  if (steps_out != nullptr) *steps_out = std::move(steps);
  return s;
}

SimResult fast_chips(const Job& job, const ToolPath& path, const SimTool& tool, double from_s,
                     double to_s, int steps_per_rev) {
  return FastChipSource(job, path, from_s, to_s, steps_per_rev).chips(tool);
}

}  // namespace trochomill
