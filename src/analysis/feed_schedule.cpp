// Chip-load feed scheduling of a path (analysis.hpp: schedule_feed). The engagement kernel
// gives the local maximum chip h_max at every tooth pass; the chip a tooth cuts grows in
// proportion to the feed per tooth where the engaged arcs stay the same (the removed region
// is the path's, whatever its feed; only the last tooth pass's step changes), so the feed of
// each piece of the path is scaled by target / h_max and the engagement evaluated again on
// the new path, until every piece holds its target or a limit.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "trochomill/analysis.hpp"
#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"

namespace trochomill {
namespace {

// A piece of a segment: the sub-range [a, b] of its arc length (mm) and its feed (mm/min).
struct Piece {
  std::size_t segment = 0;
  double a_mm = 0, b_mm = 0;
  double feed = 0;
  FeedLimit limit = FeedLimit::none;
};

// The segment's part between arc lengths a and b at the given speed.
Segment part(const Segment& seg, double a, double b, double speed) {
  if (seg.kind() == Segment::Kind::line) {
    return Segment::line(seg.point_at(a), seg.point_at(b), seg.motion(), speed);
  }
  return Segment::curve(seg.center(), seg.axis_a(), seg.axis_b(), seg.drift(), seg.u_at_length(a),
                        seg.u_at_length(b), seg.motion(), speed);
}

ToolPath build(const ToolPath& path, const std::vector<Piece>& pieces) {
  ToolPath out;
  out.reserve(pieces.size());
  const auto& segs = path.segments();
  const auto& cycles = path.cycles();
  std::size_t next_mark = 0;
  for (const Piece& p : pieces) {
    // Cycle marks stay at the start of the segment they marked.
    while (next_mark < cycles.size() && cycles[next_mark].first_segment == p.segment &&
           p.a_mm == 0) {
      out.mark_cycle();
      ++next_mark;
    }
    const Segment& seg = segs[p.segment];
    // Rapids stay whole at their rate; feed moves take their piece's feed.
    out.append(seg.motion() == Motion::rapid ? seg : part(seg, p.a_mm, p.b_mm, p.feed));
  }
  return out;
}

}  // namespace

const char* describe(FeedLimit limit) noexcept {
  switch (limit) {
    case FeedLimit::none:
      return "the chip target";
    case FeedLimit::min_feed:
      return "the min feed";
    case FeedLimit::max_feed:
      return "the max feed";
    case FeedLimit::air:
      return "the air feed";
    case FeedLimit::plunge:
      return "a descent or plunge keeping its feed";
    case FeedLimit::mrr:
      return "the removal rate cap";
    case FeedLimit::force:
      return "the force cap";
    case FeedLimit::power:
      return "the power cap";
    case FeedLimit::torque:
      return "the torque cap";
    case FeedLimit::acceleration:
      return "the acceleration";
    case FeedLimit::axial:
      return "the axial chip target";
  }
  return "?";
}

bool piece_descends_below(const Segment& seg, double from_mm, double to_mm, double top_mm) {
  const double z0 = seg.point_at(from_mm).z(), z1 = seg.point_at(to_mm).z();
  // 1e-9 mm: a level move's rounding is no descent; a piece ending at the top does not cut.
  return z1 < z0 - 1e-9 && z1 < top_mm - 1e-9;
}

PathChips kernel_chips(const Job& job, const ToolPath& path, const RunHooks& hooks,
                       const Mesh* stock_mesh) {
  EngagementOptions eo;
  eo.steps_per_tooth = 1;
  eo.hooks = hooks;
  eo.stock_mesh = stock_mesh;
  const EngagementSeries e = compute_engagement(path, job, eo);
  const auto& s = e.samples;
  const double R = 0.5 * job.tool.diameter_mm;
  const std::size_t n = s.size();
  PathChips c;
  c.t_s = s.t_s;
  c.s_mm = s.s_mm;
  c.segment = s.segment;
  c.from_t_s.resize(n);
  c.from_s_mm.resize(n);
  c.from_segment.resize(n);
  c.h_mm.resize(n);
  c.mrr_mm3_per_s = e.removal_rate_mm3_per_s;
  c.axial_mm = e.axial_chip_mm;
  c.plunge.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    // One sample per tooth pass: the chip was made since the sample before.
    const std::size_t a = i > 0 ? i - 1 : 0;
    c.from_t_s[i] = s.t_s[a];
    c.from_s_mm[i] = s.s_mm[a];
    c.from_segment[i] = s.segment[a];
    c.h_mm[i] = radial_chip_mm(e, i, R);  // as the analysis counts it
    // Descending into stock no earlier position touched: an axial chip.
    c.plunge[i] = i > 0 && c.h_mm[i] == 0 && e.h_max_mm[i] > 0;
  }
  return c;
}

FeedTargets default_feed_targets(const Job& job) {
  const Machine& m = job.machine;
  const double f = feed_rate_mm_per_min(job);
  FeedTargets t;
  t.min_feed_mm_per_min = m.min_feed_mm_per_min > 0 ? m.min_feed_mm_per_min : 0.1 * f;
  t.max_feed_mm_per_min = m.max_feed_mm_per_min > 0 ? m.max_feed_mm_per_min : 3.0 * f;
  t.air_feed_mm_per_min = m.air_feed_mm_per_min;
  return t;
}

FeedSchedule schedule_feed(const Job& job, const ToolPath& path, const FeedTargets& targets,
                           const RunHooks& hooks) {
  const double f0 = job.cutting.feed_per_tooth_mm;
  const double h_target = targets.h_max_mm.value_or(f0);
  if (!(h_target > 0) || !std::isfinite(h_target)) {
    throw InputError(
        fmt::format("feed schedule: the target h_max must be > 0 mm, got {}", h_target));
  }
  if (h_target >= 0.5 * job.tool.diameter_mm) {
    throw InputError(
        fmt::format("feed schedule: the target h_max {:g} mm is not below the tool radius {:g} mm",
                    h_target, 0.5 * job.tool.diameter_mm));
  }
  const double axial_target = targets.h_axial_max_mm.value_or(h_target);
  if (!(axial_target > 0) || !std::isfinite(axial_target)) {
    throw InputError(fmt::format(
        "feed schedule: the axial chip target ({}) must be a finite number > 0 mm, got {}",
        option_name("h_axial_max_mm"), axial_target));
  }
  const double lo = targets.min_feed_mm_per_min, hi = targets.max_feed_mm_per_min;
  if (!(lo > 0) || !(hi >= lo) || !std::isfinite(hi)) {
    throw InputError(fmt::format(
        "feed schedule: the feed limits ({} and {}, or [machine] min_feed and max_feed) must be "
        "0 < min <= max (mm/min), got {} and {}",
        option_name("min_feed_mm_per_min"), option_name("max_feed_mm_per_min"), lo, hi));
  }
  const std::optional<double> mrr_cap = targets.mrr_mm3_per_min;
  if (mrr_cap && (!(*mrr_cap > 0) || !std::isfinite(*mrr_cap))) {
    throw InputError(
        fmt::format("feed schedule: the removal rate cap must be > 0 mm^3/min, got {}", *mrr_cap));
  }
  const double air = targets.air_feed_mm_per_min > 0 ? targets.air_feed_mm_per_min : hi;
  // Pieces are at least half this long: at 0.01 mm their ends stay apart in every dialect's
  // written places (an arc's piece whose ends print as one point reads as a full circle).
  if (!(targets.piece_mm >= 0.01) || !std::isfinite(targets.piece_mm)) {
    throw InputError(fmt::format("feed schedule: the piece length must be at least 0.01 mm, got {}",
                                 targets.piece_mm));
  }
  if (!(targets.feed_step_percent >= 0) || !(targets.feed_step_percent <= 100)) {
    throw InputError("feed schedule: the feed step must be 0 .. 100 %");
  }

  // Pieces of at most piece_mm along each feed move; rapids stay whole.
  std::vector<Piece> pieces;
  const auto& segs = path.segments();
  for (std::size_t k = 0; k < segs.size(); ++k) {
    const Segment& seg = segs[k];
    const double len = seg.length_mm();
    if (seg.motion() == Motion::rapid || len <= targets.piece_mm) {
      pieces.push_back({k, 0, len, seg.speed_mm_per_min(), FeedLimit::none});
      continue;
    }
    const auto n = static_cast<std::size_t>(std::ceil(len / targets.piece_mm));
    if (n > 100'000'000 / std::max<std::size_t>(segs.size(), 1)) {
      throw InputError("feed schedule: the path is too long for the piece length");
    }
    for (std::size_t j = 0; j < n; ++j) {
      const double a = len * static_cast<double>(j) / static_cast<double>(n);
      const double b = j + 1 == n ? len : len * static_cast<double>(j + 1) / static_cast<double>(n);
      pieces.push_back({k, a, b, seg.speed_mm_per_min(), FeedLimit::none});
    }
  }

  // Descents below the stock's top (a helix, ramp or plunge into material): never faster than
  // programmed (FeedTargets::stock_top_mm).
  const double top = targets.stock_top_mm ? *targets.stock_top_mm : stock_top_mm(job, nullptr);
  std::vector<char> descends(pieces.size(), 0);
  for (std::size_t k = 0; k < pieces.size(); ++k) {
    const Segment& seg = segs[pieces[k].segment];
    if (seg.motion() == Motion::rapid) continue;
    descends[k] = piece_descends_below(seg, pieces[k].a_mm, pieces[k].b_mm, top) ? 1 : 0;
  }

  FeedSchedule out;
  out.time_before_s = path.duration_s();
  // The path as pieces: its segments are the pieces, so a sample's segment is its piece.
  ToolPath current = build(path, pieces);
  // Each piece's largest chip over its samples, and the feed each piece may run at: a chip
  // is the step from the tooth pass before, proportional to the feed it was made at (the
  // step's length over the tooth period), so the step's feed times target / h is the feed
  // that cuts that chip at the target. The step belongs to the pieces of both its ends: a
  // fast piece that ends where the engagement rises makes the next one's first chip.
  // The axial chip (the descent per tooth where the end face cuts) is in proportion to the
  // feed too: its step's feed times target / chip holds the axial target.
  struct PieceChips {
    std::vector<double> h_mm, allowed_feed, axial_mm, axial_feed;
    std::vector<bool> plunge, by_mrr;
  };
  const double tiny = 1e-9 * h_target;
  auto piece_chips = [&](const PathChips& e) {
    PieceChips c;
    c.h_mm.assign(pieces.size(), 0.0);
    c.allowed_feed.assign(pieces.size(), std::numeric_limits<double>::infinity());
    c.axial_mm.assign(pieces.size(), 0.0);
    c.axial_feed.assign(pieces.size(), std::numeric_limits<double>::infinity());
    c.plunge.assign(pieces.size(), false);
    c.by_mrr.assign(pieces.size(), false);
    for (std::size_t i = 0; i < e.size(); ++i) {
      const double h = e.h_mm[i];
      const double dt = e.t_s[i] - e.from_t_s[i];
      const double axial = i < e.axial_mm.size() ? e.axial_mm[i] : 0.0;
      if (axial > 1e-9 * axial_target && dt > 0) {
        const double step_feed = (e.s_mm[i] - e.from_s_mm[i]) / dt * 60.0;
        const double allowed = step_feed * axial_target / axial;
        for (std::size_t k = e.from_segment[i]; k <= e.segment[i]; ++k) {
          c.axial_mm[k] = std::max(c.axial_mm[k], axial);
          c.axial_feed[k] = std::min(c.axial_feed[k], allowed);
        }
      }
      if (e.plunge[i]) {
        // An axial chip the radial model does not hold: the pieces keep their programmed feed
        // or go slower (the axial target).
        for (std::size_t k = e.from_segment[i]; k <= e.segment[i]; ++k) c.plunge[k] = true;
        continue;
      }
      if (!(h > tiny) || !(dt > 0)) continue;
      const double step_feed = (e.s_mm[i] - e.from_s_mm[i]) / dt * 60.0;
      double allowed = step_feed * h_target / h;
      // The removal rate grows with the feed: the step's feed times cap / rate holds the cap.
      const double mrr = e.mrr_mm3_per_s[i] * 60.0;
      bool by_mrr = false;
      if (mrr_cap && mrr > 0 && step_feed * *mrr_cap / mrr < allowed) {
        allowed = step_feed * *mrr_cap / mrr;
        by_mrr = true;
      }
      // Every piece the step runs over shares its chip (a piece shorter than a step has no
      // sample of its own).
      for (std::size_t k = e.from_segment[i]; k <= e.segment[i]; ++k) {
        c.h_mm[k] = std::max(c.h_mm[k], h);
        if (allowed < c.allowed_feed[k]) {
          c.allowed_feed[k] = allowed;
          c.by_mrr[k] = by_mrr;
        }
      }
    }
    return c;
  };
  auto chips_of = [&](const ToolPath& p) {
    return targets.chips ? targets.chips(p) : kernel_chips(job, p, hooks);
  };
  const int iterations = std::max(1, targets.iterations);
  // Runs of feed pieces (across moves) within the step of the run's slowest share that feed:
  // a program changes F only where the feed changes by more than the step. Applied in the
  // rounds that only lower feeds, so the last evaluation sees the feeds the program gets.
  auto share_runs = [&] {
    const double step = 0.01 * targets.feed_step_percent;
    std::size_t run = 0;
    double run_feed = 0;
    auto close_run = [&](std::size_t end) {
      for (std::size_t k = run; k < end; ++k) {
        if (segs[pieces[k].segment].motion() != Motion::rapid) pieces[k].feed = run_feed;
      }
    };
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      const Piece& p = pieces[k];
      if (segs[p.segment].motion() == Motion::rapid) continue;
      const bool joins = run_feed > 0 && p.limit != FeedLimit::plunge &&
                         pieces[run].limit != FeedLimit::plunge &&
                         std::abs(p.feed - run_feed) <= step * std::min(p.feed, run_feed);
      if (joins) {
        run_feed = std::min(run_feed, p.feed);
        continue;
      }
      close_run(k);
      run = k;
      run_feed = p.feed;
    }
    close_run(pieces.size());
  };
  // Feeds the machine reaches with its acceleration (machine.max_acceleration, mm/s^2):
  // backward, a piece slows within its own length to the next one's feed (the tool arrives
  // where the chip grows at that feed); forward, a piece's feed is reached within its length
  // from the one before. Both only lower feeds (a rapid between pieces breaks the chain).
  const double accel = job.machine.max_acceleration_mm_per_s2;
  auto reachable = [&] {
    if (!(accel > 0)) return;
    auto lower = [&](Piece& p, double v_mm_s) {
      const double f = std::max(60.0 * v_mm_s, lo);
      if (f < p.feed) {
        p.feed = f;
        if (p.limit != FeedLimit::plunge) p.limit = FeedLimit::acceleration;
      }
    };
    auto feed_piece = [&](std::size_t k) {
      return segs[pieces[k].segment].motion() != Motion::rapid;
    };
    for (std::size_t k = pieces.size(); k-- > 1;) {  // backward
      if (!feed_piece(k) || !feed_piece(k - 1)) continue;
      const double v = pieces[k].feed / 60.0, len = pieces[k - 1].b_mm - pieces[k - 1].a_mm;
      lower(pieces[k - 1], std::sqrt(v * v + 2 * accel * len));
    }
    for (std::size_t k = 1; k < pieces.size(); ++k) {  // forward
      if (!feed_piece(k) || !feed_piece(k - 1)) continue;
      const double v = pieces[k - 1].feed / 60.0, len = pieces[k].b_mm - pieces[k].a_mm;
      lower(pieces[k], std::sqrt(v * v + 2 * accel * len));
    }
  };
  // Rounds beyond `iterations` (lowering only) while a cap still binds above 1 % of a
  // piece's feed: the caps' models (forces) answer the feed less than in proportion, so they
  // settle from above more slowly than the chip.
  constexpr int kCapRounds = 8;
  for (int it = 0;; ++it) {
    const PathChips e = chips_of(current);
    const PieceChips pc = piece_chips(e);
    const std::vector<double>& h = pc.h_mm;
    if (it == 0) {
      out.h_max_before_mm = e.size() > 0 ? *std::max_element(e.h_mm.begin(), e.h_mm.end()) : 0;
      for (const double a : e.axial_mm)
        out.h_axial_max_before_mm = std::max(out.h_axial_max_before_mm, a);
    }
    // The caps evaluated on the path as it is: they lower the allowed feeds where needed.
    std::vector<double> allowed = pc.allowed_feed;
    std::vector<FeedLimit> cap_limit(pieces.size(), FeedLimit::none);
    if (targets.caps) targets.caps(current, allowed, cap_limit);
    bool cap_over = false;
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      cap_over |= cap_limit[k] != FeedLimit::none && allowed[k] < 0.99 * pieces[k].feed &&
                  pieces[k].feed > lo * (1 + 1e-9);
    }
    if (it >= iterations && (!cap_over || it >= iterations + kCapRounds)) {
      out.h_max_after_mm = 0;
      for (std::size_t k = 0; k < pieces.size(); ++k) {
        if (segs[pieces[k].segment].motion() == Motion::rapid) continue;
        // 3 %: the schedule's tolerance (docs/models.md section 15).
        if (h[k] > 1.03 * h_target) {
          if (!out.missed) out.missed = FeedSchedule::Missed{};
          FeedSchedule::Missed& ms = *out.missed;
          ++ms.pieces;
          if (h[k] > ms.h_max_mm) {
            ms.h_max_mm = h[k];
            ms.at_mm = segs[pieces[k].segment].point_at(pieces[k].a_mm);
            ms.at_s = current.segment_start_time_s(k);
            ms.feed_mm_per_min = pieces[k].feed;
            ms.limit = pieces[k].limit;
          }
        }
        out.h_max_after_mm = std::max(out.h_max_after_mm, h[k]);
        out.h_axial_max_after_mm = std::max(out.h_axial_max_after_mm, pc.axial_mm[k]);
        out.piece_h_max_mm.push_back(h[k]);
        out.piece_feed_mm_per_min.push_back(pieces[k].feed);
        out.piece_limit.push_back(pieces[k].limit);
      }
      break;
    }
    // Each piece at the feed its chips allow, within the limits; a piece without a chip (air)
    // at the air feed.
    for (std::size_t k = 0; k < pieces.size(); ++k) {
      Piece& p = pieces[k];
      if (segs[p.segment].motion() == Motion::rapid) continue;
      const double programmed = segs[p.segment].speed_mm_per_min();
      if (pc.plunge[k]) {
        p.feed = programmed;
        p.limit = FeedLimit::plunge;
        if (pc.axial_feed[k] < programmed) {
          p.feed = std::max(pc.axial_feed[k], lo);
          p.limit = pc.axial_feed[k] < lo ? FeedLimit::min_feed : FeedLimit::axial;
        }
        continue;
      }
      // A cap may bind where the radial chip is nil: a step whose chip was made in the piece
      // before (the tool entering the stock from air), or a descent's axial chip alone.
      const bool cuts = std::isfinite(pc.allowed_feed[k]) || std::isfinite(allowed[k]) ||
                        std::isfinite(pc.axial_feed[k]);
      double f = cuts ? std::min({allowed[k], pc.allowed_feed[k], pc.axial_feed[k]}) : air;
      // The chip is proportional to the step only where the engaged arcs stay as they were:
      // the region behind the tool is scalloped by the earlier steps too, so the feeds settle
      // by lowering alone in the second half of the rounds (the chip ends at or below the
      // target instead of swinging about it).
      if (2 * it >= iterations) f = std::min(f, p.feed);
      p.limit = !cuts                                                         ? FeedLimit::air
                : pc.axial_feed[k] < std::min(allowed[k], pc.allowed_feed[k]) ? FeedLimit::axial
                : allowed[k] < pc.allowed_feed[k]                             ? cap_limit[k]
                : pc.by_mrr[k]                                                ? FeedLimit::mrr
                                                                              : FeedLimit::none;
      if (f > hi) {
        f = hi;
        if (p.limit == FeedLimit::none) p.limit = FeedLimit::max_feed;
      }
      if (f < lo) {
        f = lo;
        p.limit = FeedLimit::min_feed;
      }
      if (descends[k] && f >= programmed) {
        f = programmed;
        p.limit = FeedLimit::plunge;
      }
      p.feed = f;
    }
    if (2 * it >= iterations) {
      share_runs();
      reachable();
    }
    current = build(path, pieces);
    hooks.check("feed schedule interrupted");
  }
  // Merge neighbouring pieces of one segment at one feed (share_runs made them equal).
  std::vector<Piece> merged;
  for (const Piece& p : pieces) {
    if (!merged.empty()) {
      Piece& q = merged.back();
      if (q.segment == p.segment && q.b_mm == p.a_mm && q.feed == p.feed) {
        q.b_mm = p.b_mm;
        continue;
      }
    }
    merged.push_back(p);
  }
  out.path = build(path, merged);
  for (const Piece& p : merged) {
    if (segs[p.segment].motion() == Motion::rapid) continue;
    out.feed_pieces.push_back({p.segment, p.a_mm, p.b_mm, p.feed, p.limit});
  }
  out.time_after_s = out.path.duration_s();
  out.pieces = merged.size();
  return out;
}

}  // namespace trochomill
