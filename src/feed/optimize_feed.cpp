// Feed optimisation of NC programs (feed.hpp: optimize_feed): read, schedule, rewrite, read
// again and check, evaluate.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <numeric>
#include <optional>
#include <tuple>

#include "trochomill/engagement.hpp"
#include "trochomill/error.hpp"
#include "trochomill/feed.hpp"
#include "trochomill/force.hpp"
#include "trochomill/geometry.hpp"
#include "trochomill/io.hpp"
#include "trochomill/sim.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// A program read with its trace (the moves as the interpreter made them). The trace's file
// names point into the interpreter, so they are kept here.
struct Traced {
  GcodeProgram program;
  std::vector<GcodeMove> moves;
  std::vector<std::string> files;  // by GcodeMove::source
};

Traced read_traced(std::string_view text, std::string_view name, GcodeReadOptions opt) {
  Traced t;
  opt.keep_path = true;
  opt.trace = [&t](const GcodeMove& m) {
    if (t.files.size() <= m.source) t.files.resize(m.source + 1);
    if (t.files[m.source].empty()) t.files[m.source] = std::string(m.file);
    t.moves.push_back(m);
    t.moves.back().file = {};
  };
  t.program = read_gcode(text, name, opt);
  for (GcodeMove& m : t.moves) m.file = t.files[m.source];
  return t;
}

// Time-weighted quantiles of v over the samples with weight w > 0. (The pairs sorted by value
// in place: a force series has a step per degree of the whole program, and an index sort
// through v was a tenth of optimize-feed's time.)
CutQuantiles quantiles(const std::vector<double>& v, const std::vector<double>& w) {
  CutQuantiles q;
  std::vector<std::pair<double, double>> vw;
  double total = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    if (w[i] > 0) {
      vw.emplace_back(v[i], w[i]);
      total += w[i];
    }
  }
  if (vw.empty()) return q;
  std::sort(vw.begin(), vw.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  // The three quantiles in one pass over the cumulated weight.
  const std::array<double, 3> p = {0.5, 0.9, 0.99};
  std::array<double, 3> found = {vw.back().first, vw.back().first, vw.back().first};
  std::size_t next = 0;
  double acc = 0;
  for (std::size_t i = 0; i < vw.size() && next < p.size(); ++i) {
    acc += vw[i].second;
    while (next < p.size() && acc >= p[next] * total) found[next++] = vw[i].first;
  }
  q.p50 = found[0];
  q.p90 = found[1];
  q.p99 = found[2];
  q.max = vw.back().first;
  return q;
}

// The chips of a path: per sample its time, feed, chip and removal rate, and the time it
// stands for (the step before it where it cuts, else 0).
struct Chips {
  std::vector<double> t_s, s_mm, feed, h_mm, mrr, cut_dt_s, axial_mm;
  std::vector<std::size_t> segment;
  double cutting_time_s = 0;
};
Chips chips_of(const PathChips& e, const ToolPath& path) {
  Chips c;
  const std::size_t n = e.size();
  c.t_s = e.t_s;
  c.s_mm = e.s_mm;
  c.segment = e.segment;
  c.h_mm = e.h_mm;
  c.axial_mm = e.axial_mm;
  c.feed.resize(n);
  c.mrr.resize(n);
  c.cut_dt_s.resize(n);
  const auto& segs = path.segments();
  for (std::size_t i = 0; i < n; ++i) {
    const Segment& seg = segs[e.segment[i]];
    c.feed[i] = seg.motion() == Motion::rapid ? std::numeric_limits<double>::quiet_NaN()
                                              : seg.speed_mm_per_min();
    c.mrr[i] = e.mrr_mm3_per_s[i] * 60.0;
    const double dt = i > 0 ? e.t_s[i] - e.t_s[i - 1] : 0.0;
    c.cut_dt_s[i] = c.h_mm[i] > 0 ? dt : 0.0;
    c.cutting_time_s += c.cut_dt_s[i];
  }
  return c;
}

// The rewritten program's motion must be the input's: every input segment's end is reached in
// order, and every new segment ends on the input segment it belongs to (1e-6 mm: the split
// points are written to 1e-6 mm or finer). Returns the input segment of each new one.
std::vector<std::size_t> check_motion(const ToolPath& before, const ToolPath& after, double tol) {
  const auto& a = before.segments();
  const auto& b = after.segments();
  std::vector<std::size_t> owner(b.size(), 0);
  std::size_t j = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    const Segment& seg = a[k];
    double along = 0;
    for (;;) {
      if (j >= b.size()) {
        throw Error(
            fmt::format("optimize-feed: the rewritten program ends before segment {} "
                        "of the input ends (a rewrite fault; nothing was written)",
                        k));
      }
      owner[j] = k;
      const Segment& piece = b[j++];
      along += piece.length_mm();
      const bool last = (piece.end() - seg.end()).norm() <= tol &&
                        along >= seg.length_mm() - 1e-4 * (1 + seg.length_mm());
      const Vec3 on = seg.point_at(std::min(along, seg.length_mm()));
      if ((piece.end() - on).norm() > 1e-4 * (1 + seg.length_mm()) + 100 * tol && !last) {
        throw Error(fmt::format(
            "optimize-feed: the rewritten program leaves segment {} of the input by {:.3g} mm "
            "(a rewrite fault; nothing was written)",
            k, (piece.end() - on).norm()));
      }
      if ((seg.motion() == Motion::rapid) != (piece.motion() == Motion::rapid)) {
        throw Error(
            fmt::format("optimize-feed: segment {} changed between rapid and feed "
                        "(a rewrite fault; nothing was written)",
                        k));
      }
      if (last) break;
    }
  }
  if (j != b.size()) {
    throw Error(
        "optimize-feed: the rewritten program moves beyond the input's end (a rewrite "
        "fault; nothing was written)");
  }
  return owner;
}

// The force model's series over a whole path (fast chips), at least 360 steps a revolution:
// the peak of a short engagement arc falls between coarser steps (at the default 96 a cap
// held at those steps was passed by 7 % at steps in between on Bergmann 2021's path; at 360
// by 2 %).
ForceSeries path_forces(const Job& job, const ToolPath& path, const RunHooks& hooks) {
  SimControl control;
  control.hooks = hooks;
  Job fine = job;
  fine.forces.fast_steps_per_rev = std::max(fine.forces.fast_steps_per_rev, 360);
  return job_forces(fine, path, 0.0, path.duration_s(), true, control).series;
}

// Quantiles of the force, power and torque over the steps that cut (force > 0), equally
// weighted (the steps are equally spaced in time).
void force_quantiles(const ForceSeries& f, CutQuantiles& force, CutQuantiles& power,
                     CutQuantiles& torque) {
  std::vector<double> fr(f.size()), w(f.size()), pw(f.size()), tq(f.size());
  for (std::size_t i = 0; i < f.size(); ++i) {
    fr[i] = f.resultant_n(i);
    w[i] = fr[i] > 0 ? 1.0 : 0.0;
    pw[i] = std::abs(f.power_w[i]);
    tq[i] = std::abs(f.torque_nm[i]);
  }
  force = quantiles(fr, w);
  power = quantiles(pw, w);
  torque = quantiles(tq, w);
}

// The force model's caps as a schedule's caps: each piece's largest resultant, power and
// torque at its feed; a piece over a cap is allowed its feed times (cap / value)^(1 / (1 - m))
// (the force grows with the chip as h^(1 - m) in Kienzle's and Bergmann's models; the linear
// model's edge term makes it grow slower, which the rounds correct from above).
// `where`: the program's block ("file:line") at a length along the path (mm).
std::function<void(const ToolPath&, std::vector<double>&, std::vector<FeedLimit>&)> force_caps(
    const Job& job, const FeedOptimizeOptions& o, const RunHooks& hooks,
    std::function<std::string(double)> where) {
  if (!o.force_n && !o.power_w && !o.torque_nm) return {};
  if (!job.material.model) {
    throw InputError(
        "optimize-feed: force, power and torque caps need the job's [material] force model "
        "(a library name or coefficients)");
  }
  for (const auto& [cap, what] :
       {std::pair{o.force_n, "force (N)"}, std::pair{o.power_w, "power (W)"},
        std::pair{o.torque_nm, "torque (N m)"}}) {
    if (cap && (!(*cap > 0) || !std::isfinite(*cap))) {
      throw InputError(fmt::format("optimize-feed: the {} cap must be > 0, got {}", what, *cap));
    }
  }
  const double m = std::clamp(job.material.m, 0.0, 0.9);
  auto first_round = std::make_shared<bool>(true);
  return [&job, o, hooks, m, first_round, where](
             const ToolPath& pieces, std::vector<double>& allowed, std::vector<FeedLimit>& limit) {
    const auto& segs = pieces.segments();
    std::vector<double> fr(segs.size(), 0.0), pw(segs.size(), 0.0), tq(segs.size(), 0.0);
    // A step's chip was made since the tooth before passed: its force belongs to every piece
    // the tool ran over in that tooth period (as the chip's, schedule_feed).
    const double period_s = 60.0 / (job.cutting.spindle_speed_rpm * job.tool.teeth);
    // At the spindle phase the model starts with (the program's start's at the machine is
    // unknown: on a tool with few teeth and short engagement arcs the largest force of a
    // piece depends on whether a tooth passes where the arc peaks, by up to 10 % on Bergmann
    // 2021's two-insert mill).
    const ForceSeries f = path_forces(job, pieces, hooks);
    for (std::size_t i = 0; i < f.size(); ++i) {
      const std::size_t k1 = pieces.segment_at_time(f.t_s[i]);
      const std::size_t k0 = pieces.segment_at_time(f.t_s[i] - period_s);
      for (std::size_t k = std::min(k0, k1); k <= k1; ++k) {
        fr[k] = std::max(fr[k], f.resultant_n(i));
        pw[k] = std::max(pw[k], std::abs(f.power_w[i]));
        tq[k] = std::max(tq[k], std::abs(f.torque_nm[i]));
      }
    }
    // The caps: what each limits, its name and unit for messages, its value per piece.
    struct Cap {
      FeedLimit limit;
      const char *what, *unit;
      std::optional<double> cap;
      const std::vector<double>* value;
    };
    const std::array<Cap, 3> caps = {{{FeedLimit::force, "force", "N", o.force_n, &fr},
                                      {FeedLimit::power, "power", "W", o.power_w, &pw},
                                      {FeedLimit::torque, "torque", "N m", o.torque_nm, &tq}}};
    const auto cap_of = [&](FeedLimit l) -> const Cap* {
      for (const Cap& c : caps) {
        if (c.limit == l) return &c;
      }
      return nullptr;
    };
    for (std::size_t k = 0; k < segs.size(); ++k) {
      const double feed = segs[k].speed_mm_per_min();
      for (const Cap& c : caps) {
        const double v = (*c.value)[k];
        if (!c.cap || !(v > *c.cap)) continue;
        const double a = feed * std::pow(*c.cap / v, 1.0 / (1.0 - m));
        if (a < allowed[k]) {
          allowed[k] = a;
          limit[k] = c.limit;
        }
      }
    }
    // A cap the minimum feed cannot hold is refused at once (the rounds would only creep down
    // to the minimum feed, each a force run over the whole program). The power law's feed is
    // an upper bound on the one needed: the models' edge forces fall slower with the feed.
    if (*first_round) {
      *first_round = false;
      const double lo = o.targets.min_feed_mm_per_min;
      std::size_t worst = segs.size();
      for (std::size_t k = 0; k < segs.size(); ++k) {
        if (cap_of(limit[k]) != nullptr && allowed[k] < lo * (1 - 1e-9) &&
            (worst == segs.size() || allowed[k] < allowed[worst])) {
          worst = k;
        }
      }
      if (worst < segs.size()) {
        const Cap& c = *cap_of(limit[worst]);
        throw InputError(fmt::format(
            "{}: the {} cap of {:g} {} cannot be held at the minimum feed of {:g} mm/min: the "
            "model gives {:.4g} {} at {:g} mm/min and would need {:.3g} mm/min or less; raise "
            "the cap or lower the minimum feed (machine.min_feed)",
            where(pieces.segment_start_length_mm(worst)), c.what, *c.cap, c.unit, lo,
            (*c.value)[worst], c.unit, segs[worst].speed_mm_per_min(), allowed[worst]));
      }
    }
  };
}

// The mesh moved into the slot frame of the job's placement (the program's frame is the
// workpiece's).
Mesh mesh_in_slot_frame(const Mesh& m, const Placement& placement) {
  Mesh out = m;
  for (auto& v : out.vertices) {
    const Vec3 p = placement.to_slot(Vec3(v[0], v[1], v[2]));
    v = {p.x(), p.y(), p.z()};
  }
  return out;
}

}  // namespace

PathChips simulated_chips(const Job& job, const ToolPath& path, const Mesh* stock_mesh,
                          const RunHooks& hooks) {
  SimControl control;
  control.hooks = hooks;
  const JobSimulation js = simulate_job(job, path, 0.0, path.duration_s(), control, stock_mesh);
  if (!js.result.complete) throw Interrupted("optimize-feed interrupted");
  const auto& steps = js.result.steps;
  const std::size_t n = steps.size();
  const double period = tooth_period_s(job.tool, job.cutting);
  const double d = job.simulation.resolution_mm;
  PathChips c;
  c.t_s.resize(n);
  c.s_mm.resize(n);
  c.segment.resize(n);
  c.from_t_s.resize(n);
  c.from_s_mm.resize(n);
  c.from_segment.resize(n);
  c.h_mm.resize(n);
  c.mrr_mm3_per_s.resize(n);
  c.plunge.assign(n, 0);
  c.axial_mm.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const SimStep& st = steps[i];
    c.t_s[i] = st.t_s;
    c.s_mm[i] = path.length_at_time_mm(st.t_s, &c.segment[i]);
    c.from_t_s[i] = std::max(0.0, st.t_s - period);
    c.from_s_mm[i] = path.length_at_time_mm(c.from_t_s[i], &c.from_segment[i]);
    c.h_mm[i] = st.h_max_mm;
    double removed = 0;
    for (const double v : st.removed_mm3) removed += v;
    const double dt = i > 0 ? st.t_s - steps[i - 1].t_s : 0.0;
    c.mrr_mm3_per_s[i] = dt > 0 ? removed / dt : 0.0;
    // An axial chip: material removed with no chip on the edge (more than a dexel cube: a
    // sliver of the grid is not a plunge), or, going down, a chip thicker than the tool moved
    // sideways in the tooth period (and a dexel): the end face's cut, which the simulation's
    // radial chip (docs/models.md section 11) counts as the radial depth of its rays. As with
    // the kernel, such pieces keep their programmed feed.
    const double descent = i > 0 ? steps[i - 1].tip_mm[2] - st.tip_mm[2] : 0.0;
    const double sideways = std::hypot(st.tip_mm[0] - (i > 0 ? steps[i - 1].tip_mm[0] : 0.0),
                                       st.tip_mm[1] - (i > 0 ? steps[i - 1].tip_mm[1] : 0.0));
    const double per_tooth = dt > 0 ? sideways * period / dt : 0.0;
    c.plunge[i] = (st.h_max_mm == 0 && removed > d * d * d) ||
                  (descent > 1e-12 && st.h_max_mm > per_tooth + d);
    if (c.plunge[i]) c.h_mm[i] = 0;
    // The axial chip: the descent per tooth period where a descending step removes more than
    // a dexel cube (the simulation does not tell the end face's share from the flutes', so
    // every such descent counts: the safe side).
    if (descent > 1e-12 && dt > 0 && removed > d * d * d) c.axial_mm[i] = descent * period / dt;
  }
  return c;
}

namespace {

// The kernel's tool is a square end mill of the full radius (docs/models.md section 7). Where
// a level's cut (down from the stock's top, or from the next level above) is shallower than
// the corner, the corner alone cuts: a narrower circle than the kernel's and a chip thinned by
// the edge's sine, which only the simulation models. A note naming the shallowest such level.
std::optional<std::string> corner_note(const Job& job, const std::vector<GcodeMove>& moves,
                                       const ToolPath& slot_path, const Mesh* stock) {
  const double rc = job.tool.corner_radius_mm;
  if (!(rc > 0)) return std::nullopt;
  const double lead =
      job.tool.type == ToolType::insert_mill ? deg_to_rad(job.tool.lead_angle_deg) : 0.5 * kPi;
  const double corner_h = rc * (1 - std::cos(kPi - lead));  // the corner arc's top (mm)
  const double top = stock_top_mm(job, stock);
  // The levels (feed moves at one height below the top), with a move at each.
  std::map<double, const GcodeMove*> levels;
  for (const GcodeMove& m : moves) {
    if (m.segment == GcodeMove::npos || m.kind == GcodeMove::Kind::rapid) continue;
    const Segment& seg = slot_path.segments()[m.segment];
    const double z = seg.start().z();
    if (std::abs(seg.end().z() - z) > 1e-9 || !(z < top) || seg.length_mm() <= 0) continue;
    levels.emplace(z, &m);
  }
  double shallowest = std::numeric_limits<double>::infinity();
  const GcodeMove* at = nullptr;
  for (auto it = levels.begin(); it != levels.end(); ++it) {
    const auto above = std::next(it);
    const double depth = (above == levels.end() ? top : std::min(top, above->first)) - it->first;
    if (depth > 1e-6 && depth < corner_h - 1e-9 && depth < shallowest) {
      shallowest = depth;
      at = it->second;
    }
  }
  if (at == nullptr) return std::nullopt;
  return fmt::format(
      "{}:{}: this level cuts {:.4g} mm deep, within the tool's {:.4g} mm corner radius: the "
      "kernel takes the tool as a square end mill of radius {:.4g} mm (its circle and radial "
      "chip), so the feeds there follow that tool; the simulation engine models the corner (its "
      "narrower circle and thinner chip)",
      at->file, at->line, shallowest, rc, job.tool.radius_mm());
}

}  // namespace

FeedOptimizeResult optimize_feed(const Job& job, std::string_view text, std::string_view name,
                                 const FeedOptimizeOptions& options, const RunHooks& hooks) {
  FeedOptimizeResult r;
  hooks.begin("reading");
  GcodeReadOptions read = options.read;
  if (!read.cancel && hooks.cancel) read.cancel = [&hooks] { return hooks.cancelled(); };
  const Traced in = read_traced(text, name, read);
  if (!in.program.info.feed_read_at.empty()) {
    throw InputError(fmt::format(
        "{}: the program reads its own feed (#<_feed>): its motion may change with the feeds, "
        "so optimize-feed cannot rewrite them safely",
        in.program.info.feed_read_at));
  }
  r.warnings = in.program.info.warnings;
  r.moves = in.moves.size();
  const ToolPath& path = in.program.path;
  if (path.segments().empty()) throw InputError(fmt::format("{}: the program has no motion", name));

  // The models work in the slot frame of the job's placement; the program is in the
  // workpiece's (a rigid move: lengths, and so the pieces' places along the moves, agree).
  hooks.check();
  const Placement placement = slot_placement(job);
  const ToolPath slot_path = to_slot_frame(path, placement);
  hooks.check();
  for (const std::string& w : header_mismatches(job, in.program, std::string(name))) {
    r.warnings.push_back(w);
  }
  // Where the chips come from: the kernel, or the simulation (the stock mesh, if any, in the
  // slot frame), refused before it starts when its memory estimate passes the limit.
  std::optional<Mesh> mesh;
  if (options.stock_mesh) mesh = mesh_in_slot_frame(*options.stock_mesh, placement);
  const Mesh* stock = mesh ? &*mesh : nullptr;
  r.engine = options.engine;
  if (options.engine == FeedEngine::sim) {
    r.sim_resolution_mm = job.simulation.resolution_mm;
    r.sim_steps_per_rev = job.simulation.steps_per_rev;
    const MemoryEstimate est =
        estimate_simulation_memory(job, slot_path, 0.0, slot_path.duration_s(), stock);
    if (!(est.total(false) <= options.memory_limit_bytes)) {
      throw InputError(fmt::format(
          "optimize-feed {} sim: the simulation's estimated memory {} (boards {}, records {}) "
          "exceeds the limit of {}; coarsen [simulation] resolution (now {} mm) or "
          "steps_per_rev (now {}), or raise {}",
          option_name("engine"), memory_text(est.total(false)), memory_text(est.boards_bytes),
          memory_text(est.records_bytes), memory_text(options.memory_limit_bytes),
          job.simulation.resolution_mm, job.simulation.steps_per_rev,
          option_name("memory_limit_gb")));
    }
  }
  if (options.engine == FeedEngine::kernel) {
    if (auto w = corner_note(job, in.moves, slot_path, stock)) r.warnings.push_back(*w);
  }
  const auto path_chips = [&](const ToolPath& p) {
    return options.engine == FeedEngine::sim ? simulated_chips(job, p, stock, hooks)
                                             : kernel_chips(job, p, hooks, stock);
  };

  hooks.begin("scheduling");
  FeedTargets targets = options.targets;
  targets.stock_top_mm = stock_top_mm(job, stock);
  // The move that made each segment of the path (npos: none), by the segment's index (a
  // std::map of it took a second and no Ctrl-C on a 2-million-move program).
  std::vector<std::size_t> move_of_segment(slot_path.segments().size(), GcodeMove::npos);
  for (std::size_t i = 0; i < in.moves.size(); ++i) {
    const std::size_t sg = in.moves[i].segment;
    if (sg < move_of_segment.size()) move_of_segment[sg] = i;
  }
  const auto move_of = [&](std::size_t segment) -> const GcodeMove* {
    if (segment >= move_of_segment.size() || move_of_segment[segment] == GcodeMove::npos) {
      return nullptr;
    }
    return &in.moves[move_of_segment[segment]];
  };
  hooks.check();
  targets.caps = force_caps(job, options, hooks, [&](double s_mm) {
    // The pieces subdivide the program's moves: a length along them is one along the path.
    const GcodeMove* m = move_of(slot_path.segment_at_length(s_mm));
    if (m == nullptr) return std::string(name);
    return fmt::format("{}:{}", m->file, m->line);
  });
  targets.chips = path_chips;
  const FeedSchedule fs = schedule_feed(job, slot_path, targets, hooks);
  r.h_target_mm = options.targets.h_max_mm.value_or(job.cutting.feed_per_tooth_mm);
  r.h_axial_target_mm = options.targets.h_axial_max_mm.value_or(r.h_target_mm);

  // Each move's pieces (the schedule's pieces of its segment).
  std::vector<std::vector<const FeedPiece*>> of_segment(path.segments().size());
  for (const FeedPiece& p : fs.feed_pieces) of_segment[p.segment].push_back(&p);
  std::vector<MoveFeeds> feeds(in.moves.size());
  for (std::size_t i = 0; i < in.moves.size(); ++i) {
    const GcodeMove& m = in.moves[i];
    if (m.segment == GcodeMove::npos || m.kind == GcodeMove::Kind::rapid) continue;
    const Segment& seg = path.segments()[m.segment];
    for (const FeedPiece* p : of_segment[m.segment]) {
      const bool last = p == of_segment[m.segment].back();
      feeds[i].ends_mm.push_back(last ? m.end_mm : seg.point_at(p->to_mm));
      feeds[i].feed_mm_per_min.push_back(p->feed_mm_per_min);
    }
    if (feeds[i].ends_mm.size() > 1) ++r.moves_split;
    // Kept at the programmed feed or slower: a descent into the stock, an axial chip (the
    // schedule's plunge or axial limit on a move that does not descend).
    const Segment& in_slot = slot_path.segments()[m.segment];
    if (piece_descends_below(in_slot, 0.0, in_slot.length_mm(), *targets.stock_top_mm)) {
      ++r.moves_descending;
    } else if (std::any_of(of_segment[m.segment].begin(), of_segment[m.segment].end(),
                           [](const FeedPiece* p) {
                             return p->limit == FeedLimit::plunge || p->limit == FeedLimit::axial;
                           })) {
      ++r.moves_axial;
    }
  }

  hooks.begin("rewriting");
  r.rewrite = rewrite_feeds(text, in.moves, feeds, options.read.dialect);
  r.text = std::move(r.rewrite.text);  // one copy of the program: `text`

  // Read the result again: its motion is the input's, its feeds within the limits.
  hooks.begin("checking");
  const Traced out = read_traced(r.text, name, read);
  // The written places' rounding, 0.5 10^-places program units, twice over (inch: more).
  const double tol =
      std::max(2e-6, 25.4 * std::pow(10.0, -rewrite_places(options.read.dialect, 1.0)));
  const std::vector<std::size_t> input_segment = check_motion(path, out.program.path, tol);
  const ToolPath& after = out.program.path;

  // The limits by time: each new feed segment's time goes to the limit of the piece it lies
  // in; a kept one (its feed not the schedule's) counts as kept.
  double feed_time = 0;
  std::map<FeedLimit, double> by_limit;
  double kept_time = 0;
  r.min_feed_after_mm_per_min = std::numeric_limits<double>::infinity();
  // Per new segment: the limit of the schedule's piece it runs at (nullopt: kept).
  std::vector<std::optional<FeedLimit>> limit_of(after.segments().size());
  {
    const auto& b = after.segments();
    std::vector<double> along(path.segments().size(), 0.0);
    for (std::size_t j = 0; j < b.size(); ++j) {
      const Segment& piece = b[j];
      const std::size_t k = input_segment[j];
      const double mid = along[k] + 0.5 * piece.length_mm();
      along[k] += piece.length_mm();
      if (piece.motion() == Motion::rapid) continue;
      const double dt = piece.length_mm() / (piece.speed_mm_per_min() / 60.0);
      feed_time += dt;
      r.min_feed_after_mm_per_min = std::min(r.min_feed_after_mm_per_min, piece.speed_mm_per_min());
      r.max_feed_after_mm_per_min = std::max(r.max_feed_after_mm_per_min, piece.speed_mm_per_min());
      const FeedPiece* owner = nullptr;
      for (const FeedPiece* p : of_segment[k]) {
        if (mid >= p->from_mm - 1e-9 && mid <= p->to_mm + 1e-9) owner = p;
      }
      // Scheduled: at the piece's feed (a block run more than once may run slower, at the
      // slowest feed its runs need); kept: at the feed the program gave it.
      const bool scheduled = owner != nullptr &&
                             piece.speed_mm_per_min() <= owner->feed_mm_per_min * (1 + 1e-9) + 1e-3;
      if (scheduled) {
        by_limit[owner->limit] += dt;
        limit_of[j] = owner->limit;
      } else {
        kept_time += dt;
      }
    }
  }
  if (feed_time > 0) {
    r.share_target = by_limit[FeedLimit::none] / feed_time;
    r.share_mrr = by_limit[FeedLimit::mrr] / feed_time;
    r.share_max_feed = by_limit[FeedLimit::max_feed] / feed_time;
    r.share_min_feed = by_limit[FeedLimit::min_feed] / feed_time;
    r.share_air = by_limit[FeedLimit::air] / feed_time;
    r.share_plunge = by_limit[FeedLimit::plunge] / feed_time;
    r.share_kept = kept_time / feed_time;
    r.share_force = by_limit[FeedLimit::force] / feed_time;
    r.share_power = by_limit[FeedLimit::power] / feed_time;
    r.share_torque = by_limit[FeedLimit::torque] / feed_time;
    r.share_acceleration = by_limit[FeedLimit::acceleration] / feed_time;
    r.share_axial = by_limit[FeedLimit::axial] / feed_time;
  }
  if (!std::isfinite(r.min_feed_after_mm_per_min)) r.min_feed_after_mm_per_min = 0;

  // Times and chips before and after (the after from the program as written and read back).
  r.time_before_s = path.duration_s();
  r.time_after_s = after.duration_s();
  r.time_before_accel_s = estimate_time_s(path, job.machine);
  r.time_after_accel_s = estimate_time_s(after, job.machine);
  hooks.begin("evaluating");
  const Chips cb = chips_of(path_chips(slot_path), slot_path);
  const ToolPath after_slot = to_slot_frame(after, placement);
  const Chips ca = chips_of(path_chips(after_slot), after_slot);
  r.cutting_time_before_s = cb.cutting_time_s;
  r.cutting_time_after_s = ca.cutting_time_s;
  r.h_before_mm = quantiles(cb.h_mm, cb.cut_dt_s);
  r.h_after_mm = quantiles(ca.h_mm, ca.cut_dt_s);
  r.mrr_before = quantiles(cb.mrr, cb.cut_dt_s);
  r.mrr_after = quantiles(ca.mrr, ca.cut_dt_s);
  for (const double a : cb.axial_mm) r.h_axial_max_before_mm = std::max(r.h_axial_max_before_mm, a);
  for (const double a : ca.axial_mm) r.h_axial_max_after_mm = std::max(r.h_axial_max_after_mm, a);
  ForceSeries fa;  // the rewritten program's forces (with a model)
  if (job.material.model) {
    r.forces = true;
    const ForceSeries fb = path_forces(job, slot_path, hooks);
    fa = path_forces(job, after_slot, hooks);
    force_quantiles(fb, r.force_before_n, r.power_before_w, r.torque_before_nm);
    force_quantiles(fa, r.force_after_n, r.power_after_w, r.torque_after_nm);
    for (const auto& [f, p, at, v] :
         {std::tuple{&fb, &slot_path, &r.force_s_before_mm, &r.force_before_series_n},
          std::tuple{static_cast<const ForceSeries*>(&fa), &after_slot, &r.force_s_after_mm,
                     &r.force_after_series_n}}) {
      at->resize(f->size());
      v->resize(f->size());
      for (std::size_t i = 0; i < f->size(); ++i) {
        (*at)[i] = p->length_at_time_mm(f->t_s[i]);  // the place at the step's time
        (*v)[i] = f->resultant_n(i);
      }
    }
  }
  r.t_before_s = cb.t_s;
  r.s_before_mm = cb.s_mm;
  r.s_after_mm = ca.s_mm;
  r.feed_before = cb.feed;
  r.h_before = cb.h_mm;
  r.t_after_s = ca.t_s;
  r.feed_after = ca.feed;
  r.h_after = ca.h_mm;

  // Blocks where the chip (radial, or the end face's axial chip) stays above its target at
  // the minimum feed.
  const auto unheld_blocks = [&](const std::vector<double>& chip, double target) {
    std::map<std::pair<std::size_t, std::size_t>, UnheldBlock> unheld;
    for (std::size_t i = 0; i < chip.size(); ++i) {
      // 3 %: the schedule's own tolerance (docs/models.md section 15).
      if (!(chip[i] > target * 1.03)) continue;
      if (limit_of[ca.segment[i]] != FeedLimit::min_feed) continue;
      const GcodeMove* mp = move_of(input_segment[ca.segment[i]]);
      if (mp == nullptr) continue;
      const GcodeMove& m = *mp;
      UnheldBlock& u = unheld[{m.source, m.line}];
      u.file = std::string(m.file);
      u.line = m.line;
      u.h_max_mm = std::max(u.h_max_mm, chip[i]);
      u.feed_mm_per_min = ca.feed[i];
    }
    std::vector<UnheldBlock> list;
    for (auto& [key, u] : unheld) list.push_back(std::move(u));
    return list;
  };
  r.unheld = unheld_blocks(ca.h_mm, r.h_target_mm);
  r.unheld_axial = unheld_blocks(ca.axial_mm, r.h_axial_target_mm);

  // Caps the minimum feed cannot hold (a full slot whose edge forces alone exceed a force
  // cap, say) are refused: a program above a hard cap is not written. 3 %: the schedule's
  // tolerance, as for the chip.
  struct Over {
    const char* what;
    const char* unit;
    double cap;
    std::map<std::pair<std::size_t, std::size_t>, double> blocks;  // (file, line) -> largest
    double feed = 0;
  };
  std::vector<Over> overs;
  auto block_of = [&](std::size_t after_segment) -> const GcodeMove* {
    if (limit_of[after_segment] != FeedLimit::min_feed) return nullptr;
    return move_of(input_segment[after_segment]);
  };
  if (options.targets.mrr_mm3_per_min) {
    Over o{"removal rate cap", "mm^3/min", *options.targets.mrr_mm3_per_min, {}, 0};
    for (std::size_t i = 0; i < ca.mrr.size(); ++i) {
      if (!(ca.mrr[i] > o.cap * 1.03)) continue;
      if (const GcodeMove* m = block_of(ca.segment[i])) {
        double& v = o.blocks[{m->source, m->line}];
        v = std::max(v, ca.mrr[i]);
        o.feed = ca.feed[i];
      }
    }
    overs.push_back(std::move(o));
  }
  if (r.forces) {
    const std::tuple<const char*, const char*, std::optional<double>, int> caps[] = {
        {"force cap", "N", options.force_n, 0},
        {"power cap", "W", options.power_w, 1},
        {"torque cap", "N m", options.torque_nm, 2}};
    for (const auto& [what, unit, cap, kind] : caps) {
      if (!cap) continue;
      Over o{what, unit, *cap, {}, 0};
      for (std::size_t i = 0; i < fa.size(); ++i) {
        const double v = kind == 0   ? fa.resultant_n(i)
                         : kind == 1 ? std::abs(fa.power_w[i])
                                     : std::abs(fa.torque_nm[i]);
        if (!(v > *cap * 1.03)) continue;
        const std::size_t k = after_slot.segment_at_time(fa.t_s[i]);
        if (const GcodeMove* m = block_of(k)) {
          double& b = o.blocks[{m->source, m->line}];
          b = std::max(b, v);
          o.feed = after_slot.segments()[k].speed_mm_per_min();
        }
      }
      overs.push_back(std::move(o));
    }
  }
  for (const Over& o : overs) {
    if (o.blocks.empty()) continue;
    std::string where;
    std::size_t shown = 0;
    for (const auto& [key, v] : o.blocks) {
      if (shown++ == 8) {
        where += fmt::format(" and {} more", o.blocks.size() - 8);
        break;
      }
      const GcodeMove* m = nullptr;
      for (const GcodeMove& mv : in.moves) {
        if (mv.source == key.first && mv.line == key.second) {
          m = &mv;
          break;
        }
      }
      where += fmt::format("{}{}:{} ({:.4g} {})", shown > 1 ? ", " : "", m ? m->file : "?",
                           key.second, v, o.unit);
    }
    throw InputError(fmt::format(
        "optimize-feed: the {} of {:g} {} cannot be held: at the minimum feed ({:g} mm/min) "
        "the program still reaches more in {} block(s): {}; raise the cap or lower the minimum "
        "feed ({}, [machine] min_feed)",
        o.what, o.cap, o.unit, o.feed, o.blocks.size(), where, option_name("min_feed_mm_per_min")));
  }
  return r;
}

}  // namespace trochomill

namespace trochomill {
namespace {

nlohmann::ordered_json quantiles_json(const CutQuantiles& q) {
  return {{"p50", q.p50}, {"p90", q.p90}, {"p99", q.p99}, {"max", q.max}};
}

}  // namespace

std::string feed_summary_json(const FeedOptimizeResult& r) {
  const auto blocks = [](const std::vector<UnheldBlock>& list) {
    nlohmann::ordered_json out = nlohmann::ordered_json::array();
    for (const UnheldBlock& u : list) {
      out.push_back({{"file", u.file},
                     {"line", u.line},
                     {"h_max_mm", u.h_max_mm},
                     {"feed_mm_per_min", u.feed_mm_per_min}});
    }
    return out;
  };
  const nlohmann::ordered_json j = {
      {"engine", r.engine == FeedEngine::sim ? "sim" : "kernel"},
      {"sim_resolution_mm", r.engine == FeedEngine::sim
                                ? nlohmann::ordered_json(r.sim_resolution_mm)
                                : nlohmann::ordered_json(nullptr)},
      {"sim_steps_per_rev", r.engine == FeedEngine::sim
                                ? nlohmann::ordered_json(r.sim_steps_per_rev)
                                : nlohmann::ordered_json(nullptr)},
      {"h_target_mm", r.h_target_mm},
      {"h_axial_target_mm", r.h_axial_target_mm},
      {"h_axial_max_before_mm", r.h_axial_max_before_mm},
      {"h_axial_max_after_mm", r.h_axial_max_after_mm},
      {"time_before_s", r.time_before_s},
      {"time_after_s", r.time_after_s},
      {"time_before_with_acceleration_s", r.time_before_accel_s},
      {"time_after_with_acceleration_s", r.time_after_accel_s},
      {"time_saved_percent", r.time_before_accel_s > 0
                                 ? 100.0 * (1.0 - r.time_after_accel_s / r.time_before_accel_s)
                                 : 0.0},
      {"cutting_time_before_s", r.cutting_time_before_s},
      {"cutting_time_after_s", r.cutting_time_after_s},
      {"h_max_before_mm", quantiles_json(r.h_before_mm)},
      {"h_max_after_mm", quantiles_json(r.h_after_mm)},
      {"mrr_before_mm3_per_min", quantiles_json(r.mrr_before)},
      {"mrr_after_mm3_per_min", quantiles_json(r.mrr_after)},
      {"force_before_n", r.forces ? quantiles_json(r.force_before_n) : nullptr},
      {"force_after_n", r.forces ? quantiles_json(r.force_after_n) : nullptr},
      {"power_before_w", r.forces ? quantiles_json(r.power_before_w) : nullptr},
      {"power_after_w", r.forces ? quantiles_json(r.power_after_w) : nullptr},
      {"torque_before_nm", r.forces ? quantiles_json(r.torque_before_nm) : nullptr},
      {"torque_after_nm", r.forces ? quantiles_json(r.torque_after_nm) : nullptr},
      {"feed_after_min_mm_per_min", r.min_feed_after_mm_per_min},
      {"feed_after_max_mm_per_min", r.max_feed_after_mm_per_min},
      {"share_of_feed_time",
       {{"chip_target", r.share_target},
        {"mrr_cap", r.share_mrr},
        {"force_cap", r.share_force},
        {"power_cap", r.share_power},
        {"torque_cap", r.share_torque},
        {"acceleration", r.share_acceleration},
        {"max_feed", r.share_max_feed},
        {"min_feed", r.share_min_feed},
        {"air_feed", r.share_air},
        {"plunge_kept", r.share_plunge},
        {"axial_chip_target", r.share_axial},
        {"kept", r.share_kept}}},
      {"moves", r.moves},
      {"moves_split", r.moves_split},
      {"moves_descending_into_stock", r.moves_descending},
      {"moves_axial_chip", r.moves_axial},
      {"blocks_changed", r.rewrite.blocks_changed},
      {"lines_added", r.rewrite.lines_added},
      {"unheld", blocks(r.unheld)},
      {"unheld_axial", blocks(r.unheld_axial)},
      {"warnings", r.warnings}};
  return j.dump(2) + "\n";
}

std::string feed_summary_text(const FeedOptimizeResult& r) {
  std::string s;
  const auto pct = [](double a, double b) { return b > 0 ? 100.0 * (a / b - 1.0) : 0.0; };
  s += r.engine == FeedEngine::sim
           ? fmt::format("chips from     the tri-dexel simulation at {:g} mm, {} steps/rev\n",
                         r.sim_resolution_mm, r.sim_steps_per_rev)
           : std::string("chips from     the exact engagement kernel\n");
  s += fmt::format(
      "time            {:10.3f} s -> {:10.3f} s ({:+.1f} %), with acceleration "
      "{:.3f} s -> {:.3f} s ({:+.1f} %)\n",
      r.time_before_s, r.time_after_s, pct(r.time_after_s, r.time_before_s), r.time_before_accel_s,
      r.time_after_accel_s, pct(r.time_after_accel_s, r.time_before_accel_s));
  s += fmt::format("cutting time    {:10.3f} s -> {:10.3f} s\n", r.cutting_time_before_s,
                   r.cutting_time_after_s);
  const auto q = [](const CutQuantiles& c, const char* f) {
    return fmt::format(fmt::runtime(f), c.p50, c.p90, c.p99, c.max);
  };
  s += fmt::format("h_max (target {:.4f} mm), over the cutting time:\n", r.h_target_mm);
  s += "  before        " + q(r.h_before_mm, "p50 {:.4f}  p90 {:.4f}  p99 {:.4f}  max {:.4f} mm\n");
  s += "  after         " + q(r.h_after_mm, "p50 {:.4f}  p90 {:.4f}  p99 {:.4f}  max {:.4f} mm\n");
  s += fmt::format("axial chip (target {:.4g} mm), max: before {:.4f} mm, after {:.4f} mm\n",
                   r.h_axial_target_mm, r.h_axial_max_before_mm, r.h_axial_max_after_mm);
  s += "MRR before      " +
       q(r.mrr_before, "p50 {:.0f}  p90 {:.0f}  p99 {:.0f}  max {:.0f} mm^3/min\n");
  s += "MRR after       " +
       q(r.mrr_after, "p50 {:.0f}  p90 {:.0f}  p99 {:.0f}  max {:.0f} mm^3/min\n");
  if (r.forces) {
    for (const auto& [name, before, after, f] :
         {std::tuple{"F_R", &r.force_before_n, &r.force_after_n,
                     "p50 {:.1f}  p90 {:.1f}  p99 {:.1f}  max {:.1f} N\n"},
          std::tuple{"power", &r.power_before_w, &r.power_after_w,
                     "p50 {:.0f}  p90 {:.0f}  p99 {:.0f}  max {:.0f} W\n"},
          std::tuple{"torque", &r.torque_before_nm, &r.torque_after_nm,
                     "p50 {:.2f}  p90 {:.2f}  p99 {:.2f}  max {:.2f} N m\n"}}) {
      s += fmt::format("{:<16}", fmt::format("{} before", name)) + q(*before, f);
      s += fmt::format("{:<16}", fmt::format("{} after", name)) + q(*after, f);
    }
  }

  s += fmt::format("feeds after     {:.1f} .. {:.1f} mm/min\n", r.min_feed_after_mm_per_min,
                   r.max_feed_after_mm_per_min);
  s += fmt::format(
      "feed time held by: chip target {:.1f} %, MRR cap {:.1f} %, force cap {:.1f} %, power cap "
      "{:.1f} %, torque cap {:.1f} %, acceleration {:.1f} %, max feed {:.1f} %, min feed {:.1f} "
      "%, air feed {:.1f} %, descents and plunges kept {:.1f} %, axial chip target {:.1f} %, "
      "kept moves {:.1f} %\n",
      100 * r.share_target, 100 * r.share_mrr, 100 * r.share_force, 100 * r.share_power,
      100 * r.share_torque, 100 * r.share_acceleration, 100 * r.share_max_feed,
      100 * r.share_min_feed, 100 * r.share_air, 100 * r.share_plunge, 100 * r.share_axial,
      100 * r.share_kept);
  s += fmt::format("{} moves, {} split, {} blocks changed, {} lines added\n", r.moves,
                   r.moves_split, r.rewrite.blocks_changed, r.rewrite.lines_added);
  if (r.moves_descending + r.moves_axial > 0) {
    s += fmt::format(
        "kept at their programmed feed or slower (slower where a chip passes its target): {} "
        "descents into the stock (helix, ramp, plunge), {} moves with an axial chip\n",
        r.moves_descending, r.moves_axial);
  }
  for (const UnheldBlock& u : r.unheld) {
    s += fmt::format(
        "cannot hold the target at {}:{}: h_max {:.4f} mm at the minimum feed {:g} "
        "mm/min\n",
        u.file, u.line, u.h_max_mm, u.feed_mm_per_min);
  }
  for (const UnheldBlock& u : r.unheld_axial) {
    s += fmt::format(
        "cannot hold the axial chip target at {}:{}: {:.4f} mm a tooth at the minimum feed {:g} "
        "mm/min\n",
        u.file, u.line, u.h_max_mm, u.feed_mm_per_min);
  }
  return s;
}

}  // namespace trochomill
