// G-code writer for six dialects (haas as fanuc, mach3 as linuxcnc). Circular arcs in the XY plane
// become G2/G3 (split into pieces of less than 180 degrees, which every control accepts, Grbl
// included); other flat curves become biarcs (or chords on request) within the tolerance; anything
// else chords.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <map>

#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"
#include "trochomill/version.hpp"

namespace trochomill {
namespace {

class Emitter {
 public:
  // Positions come in the slot frame and are written in the workpiece (the placement).
  Emitter(const GcodeWriteOptions& opt, const Placement& placement)
      : opt_(opt), placement_(placement), scale_(std::pow(10.0, opt.decimals)) {
    for (int k = 0; k < opt.decimals; ++k) pow10_ *= 10;
    out_.reserve(1 << 16);
  }

  std::string& out() { return out_; }

  void comment(std::string_view text) {
    std::string t(text);
    if (opt_.dialect == Dialect::sinumerik || opt_.dialect == Dialect::grbl) {
      for (char& c : t)
        if (c == '\n') c = ' ';
      out_ += "; ";
      out_ += t;
      out_ += '\n';
      return;
    }
    for (char& c : t) {
      if (c == '(') c = '[';
      if (c == ')') c = ']';
      if (c == '\n') c = ' ';
    }
    out_ += '(';
    out_ += t;
    out_ += ")\n";
  }
  void line(std::string_view text) {
    out_ += text;
    out_ += '\n';
  }

  // Number with fixed decimals, trailing zeros trimmed (Fanuc: the point kept), no "-0": the
  // value is rounded to an integer count of 10^-decimals mm (the same rounding as rounded())
  // and printed exactly.
  void num(char letter, double v) {
    const double scaled = std::round(v * scale_);
    if (!(std::abs(scaled) < 9e15)) throw Error(fmt::format("coordinate {} is out of range", v));
    auto q = static_cast<long long>(scaled);
    out_ += ' ';
    out_ += letter;
    if (q < 0) {
      out_ += '-';
      q = -q;
    }
    const long long whole = q / pow10_, frac = q % pow10_;
    char buf[24];
    int n = 0;
    long long w = whole;
    do {
      buf[n++] = static_cast<char>('0' + w % 10);
      w /= 10;
    } while (w > 0);
    while (n > 0) out_ += buf[--n];
    if (frac != 0) {
      char digits[8];
      long long f = frac;
      for (int k = opt_.decimals - 1; k >= 0; --k) {
        digits[k] = static_cast<char>('0' + f % 10);
        f /= 10;
      }
      int len = opt_.decimals;
      while (len > 0 && digits[len - 1] == '0') --len;
      out_ += '.';
      out_.append(digits, static_cast<std::size_t>(len));
    } else if (opt_.dialect == Dialect::fanuc || opt_.dialect == Dialect::haas) {
      // A Fanuc set to least-increment input (its factory setting) reads "Z5" as 5 um: every
      // Fanuc number carries its decimal point.
      out_ += '.';
    }
  }

  // A motion block: code G0/G1/G2/G3, only the axes that change (X and Y on the first move
  // after the Z approach).
  void move(int g, const Vec3& slot_p, double feed, const double* slot_ij = nullptr) {
    const bool first = !have_pos_;
    const Vec3 p = placement_.to_work(slot_p);
    const Vec3 ij_work =
        slot_ij != nullptr ? placement_.turn(Vec3(slot_ij[0], slot_ij[1], 0)) : Vec3::Zero();
    const double ij_w[2] = {ij_work.x(), ij_work.y()};
    const double* ij = slot_ij != nullptr ? ij_w : nullptr;
    const Vec3 q = rounded(p);
    const bool same_xy = have_pos_ && q.x() == pos_.x() && q.y() == pos_.y();
    if (same_xy && q.z() == pos_.z()) return;  // nothing moves at the written precision
    if (g >= 2 && same_xy) {
      // An arc piece (always under 180 degrees) whose ends round to one point: a control
      // reads G2/G3 with its end at its start as a full circle (a tiny arc of a pass would
      // sweep the whole circle through the stock and the islands). A line instead: it lies
      // within the rounding of the arc's chord.
      g = 1;
      ij = nullptr;
    }
    out_ += 'G';
    out_ += static_cast<char>('0' + g);
    if (first || q.x() != pos_.x() || g >= 2) num('X', p.x());
    if (first || q.y() != pos_.y() || g >= 2) num('Y', p.y());
    if (q.z() != pos_.z()) num('Z', p.z());
    if (ij != nullptr) {
      num('I', ij[0]);
      num('J', ij[1]);
    }
    if (g != 0 && feed != feed_) {
      num('F', feed);
      feed_ = feed;
    }
    out_ += '\n';
    pos_ = q;
    have_pos_ = true;
  }
  // A Z-only rapid with extra words after G0 (the length offset "G43 H1" on the first one).
  void move_z(int g, double z, const std::string& words) {
    out_ += 'G';
    out_ += static_cast<char>('0' + g);
    if (!words.empty()) {
      out_ += ' ';
      out_ += words;
    }
    num('Z', z);
    out_ += '\n';
    pos_.z() = rounded(Vec3(0, 0, z)).z();
  }
  [[nodiscard]] double z() const { return pos_.z(); }

 private:
  [[nodiscard]] Vec3 rounded(const Vec3& p) const {
    return Vec3(std::round(p.x() * scale_) / scale_, std::round(p.y() * scale_) / scale_,
                std::round(p.z() * scale_) / scale_);
  }
  const GcodeWriteOptions& opt_;
  const Placement& placement_;
  double scale_;         ///< 10^decimals
  long long pow10_ = 1;  ///< 10^decimals
  std::string out_;
  Vec3 pos_ = Vec3::Zero();
  bool have_pos_ = false;
  double feed_ = -1;
};

void emit_arc(Emitter& e, const Vec3& start, double cx, double cy, double r, double a0,
              double sweep, double z0, double z1, double feed) {
  // Pieces of strictly less than 180 degrees: exact, and unambiguous on every control.
  const int n = static_cast<int>(std::floor(std::abs(sweep) / kPi)) + 1;
  const int g = sweep > 0 ? 3 : 2;
  Vec3 from = start;
  for (int k = 1; k <= n; ++k) {
    const double a = a0 + sweep * k / n;
    const Vec3 to(cx + r * std::cos(a), cy + r * std::sin(a), z0 + (z1 - z0) * k / n);
    const double ij[2] = {cx - from.x(), cy - from.y()};
    e.move(g, to, feed, ij);
    from = to;
  }
}

// Biarc fits of curves that differ only by translation are the same arcs shifted: the cycles
// of a planned slot are all one shape, so each shape is fitted once (about 100 times fewer
// fits for a 100-cycle slot). Arcs are stored relative to the curve's centre.
struct FitKey {
  std::array<double, 11> v;
  bool operator<(const FitKey& o) const { return v < o.v; }
};
using FitCache = std::map<FitKey, std::vector<FitArc>>;

const std::vector<FitArc>& cached_biarcs(const Segment& seg, double tol, FitCache& cache,
                                         std::vector<FitArc>& scratch) {
  const Vec3& a = seg.axis_a();
  const Vec3& b = seg.axis_b();
  const Vec3& v = seg.drift();
  const FitKey key{
      {a.x(), a.y(), b.x(), b.y(), v.x(), v.y(), seg.u0(), seg.u1(), tol, seg.center().z(), 0.0}};
  auto it = cache.find(key);
  if (it == cache.end()) {
    // Fit the curve as centred at the origin (in x, y), then keep it.
    const Segment centred = Segment::curve(Vec3(0, 0, seg.center().z()), a, b, v, seg.u0(),
                                           seg.u1(), seg.motion(), seg.speed_mm_per_min());
    it = cache.emplace(key, fit_biarcs(centred, tol)).first;
  }
  scratch = it->second;
  const double cx = seg.center().x(), cy = seg.center().y();
  for (FitArc& arc : scratch) {
    arc.start.x() += cx;
    arc.start.y() += cy;
    arc.end.x() += cx;
    arc.end.y() += cy;
    arc.cx += cx;
    arc.cy += cy;
  }
  // Exact end points: the translated fit meets the path's own end points to rounding.
  scratch.front().start = seg.start();
  scratch.back().end = seg.end();
  return scratch;
}

void emit_segment(Emitter& e, const Segment& seg, const GcodeWriteOptions& opt, FitCache& cache) {
  const double feed = seg.speed_mm_per_min();
  if (seg.kind() == Segment::Kind::line) {
    e.move(seg.motion() == Motion::rapid ? 0 : 1, seg.end(), feed);
    return;
  }
  const bool xy_circle = seg.is_circular() && std::abs(seg.axis_a().z()) <= 1e-12 &&
                         std::abs(seg.axis_b().z()) <= 1e-12 &&
                         std::abs(seg.drift().x()) <= 1e-12 && std::abs(seg.drift().y()) <= 1e-12;
  if (xy_circle) {
    const Vec3 s = seg.start(), en = seg.end();
    const double r = seg.axis_a().norm();
    // Orientation: A x B along +z with u increasing is counter-clockwise.
    const double orient = seg.axis_a().cross(seg.axis_b()).z() > 0 ? 1.0 : -1.0;
    const double sweep = orient * (seg.u1() - seg.u0());
    const double a0 = std::atan2(s.y() - seg.center().y(), s.x() - seg.center().x());
    emit_arc(e, s, seg.center().x(), seg.center().y(), r, a0, sweep, s.z(), en.z(), feed);
    return;
  }
  if (seg.is_flat_xy() && opt.arc_output == ArcOutput::arcs) {
    std::vector<FitArc> scratch;
    for (const FitArc& arc : cached_biarcs(seg, opt.tolerance_mm, cache, scratch)) {
      if (arc.is_line) {
        e.move(1, arc.end, feed);
      } else {
        const double a0 = std::atan2(arc.start.y() - arc.cy, arc.start.x() - arc.cx);
        emit_arc(e, arc.start, arc.cx, arc.cy, arc.radius_mm, a0, arc.sweep_rad, arc.start.z(),
                 arc.end.z(), feed);
      }
    }
    return;
  }
  for (const Vec3& p : fit_chords(seg, opt.tolerance_mm)) e.move(1, p, feed);
}

std::string coolant_code(Coolant c) {
  switch (c) {
    case Coolant::flood:
      return "M8";
    case Coolant::mist:
      return "M7";
    case Coolant::off:
      return "";
  }
  return "";
}

// The rule that keeps a program from rapiding into the stock: a rapid that moves X or Y runs at
// or above the clearance plane; below it rapids only go straight up or down (the planner's
// descents to the feed-start height, over air). A path that breaks it is a planner bug.
void check_rapids(const ToolPath& path, double clear_z) {
  constexpr double kTol = 1e-9;  // mm: far below the output's 1e-4 mm resolution
  for (std::size_t i = 0; i < path.segments().size(); ++i) {
    const Segment& seg = path.segments()[i];
    if (seg.motion() != Motion::rapid) continue;
    const Vec3 a = seg.start(), b = seg.end();
    const bool moves_xy = std::hypot(b.x() - a.x(), b.y() - a.y()) > kTol;
    if (seg.kind() == Segment::Kind::curve ||
        (moves_xy && std::min(a.z(), b.z()) < clear_z - kTol)) {
      throw Error(fmt::format(
          "G-code writer: rapid {} moves X/Y below the clearance plane Z{:g} (from X{:.4f} Y{:.4f} "
          "Z{:.4f} to X{:.4f} Y{:.4f} Z{:.4f}); refusing to write it: this is a bug",
          i, clear_z, a.x(), a.y(), a.z(), b.x(), b.y(), b.z()));
    }
  }
}

}  // namespace

std::string write_gcode(const Job& job, const ToolPath& path, const GcodeWriteOptions& opt) {
  if (path.empty()) throw Error("cannot write G-code for an empty path");
  if (!(opt.tolerance_mm > 0)) throw InputError("G-code tolerance must be > 0 mm");
  if (opt.decimals < 3 || opt.decimals > 6) throw InputError("G-code decimals must be in [3, 6]");
  const Placement placement = slot_placement(job);
  check_rapids(path, job.machine.safe_z_mm);  // a rigid motion about Z keeps what it checks
  Emitter e(opt, placement);
  // Haas reads Fanuc's programs, Mach3 LinuxCNC's (without the % lines, ending with M30).
  const bool mach3 = opt.dialect == Dialect::mach3;
  const Dialect d = opt.dialect == Dialect::haas ? Dialect::fanuc
                    : mach3                      ? Dialect::linuxcnc
                                                 : opt.dialect;
  if ((d == Dialect::linuxcnc && !mach3) || d == Dialect::fanuc) e.line("%");
  if (d == Dialect::fanuc) e.line(fmt::format("O{:04d}", job.machine.program_number));
  if (job.pocket.defined()) {
    const Pocket& pk = job.pocket;
    e.comment(
        fmt::format("trochomill {}: pocket of layer {}{}, {:g} mm deep, engagement at most "
                    "{:g} degrees, {} milling",
                    kVersion, pk.boundary,
                    pk.islands.empty() ? std::string() : ", islands of layer " + pk.islands,
                    pk.depth_mm, pk.max_engagement_deg, to_string(job.path.direction)));
  } else {
    e.comment(fmt::format("trochomill {}: {} slot {:g} x {:g} x {:g} mm, {} milling", kVersion,
                          to_string(job.path.type), job.slot.width_mm, job.slot.length_mm,
                          job.slot.depth_mm, to_string(job.path.direction)));
  }
  if (job.pocket.defined() && !job.pocket.entry_holes_mm.empty()) {
    // The program feeds straight down these: without them the tool plunges into the stock.
    // Only the holes it goes down (the first of a part is its entry; another in the same part
    // is not used, and an operator drilling it would drill for nothing).
    std::string at;
    std::vector<Vec2> listed;
    for (const Vec2& h : job.pocket.entry_holes_mm) {
      // (A hole given twice, or within 1e-6 mm of one listed, is the same hole.)
      if (std::any_of(listed.begin(), listed.end(),
                      [&](const Vec2& l) { return (l - h).norm() < 1e-6; })) {
        continue;
      }
      const bool used =
          std::any_of(path.segments().begin(), path.segments().end(), [&](const Segment& g) {
            const Vec3 a = g.start(), b = g.end();
            return g.motion() != Motion::rapid && b.z() < a.z() &&
                   (a.head<2>() - h).norm() < 1e-6 && (b.head<2>() - h).norm() < 1e-6;
          });
      if (used) {
        listed.push_back(h);
        at += fmt::format(" X{:.10g} Y{:.10g}", h.x(), h.y());
      }
    }
    if (!at.empty())
      e.comment(fmt::format("NEEDS PRE-DRILLED HOLES at least {:g} mm wide and {:g} mm deep at{}",
                            job.tool.diameter_mm, job.pocket.depth_mm, at));
  }
  e.comment(fmt::format("job: {}", job.source));
  e.comment(fmt::format("path length {:.3f} mm, {:.3f} s at programmed feed, {} dialect",
                        path.length_mm(), path.duration_s(), to_string(opt.dialect)));
  if (!placement.is_identity()) {
    e.comment(fmt::format("slot origin at X{:g} Y{:g}, slot +Y turned {:g} degrees from +Y",
                          placement.origin_x_mm, placement.origin_y_mm, placement.angle_deg));
  }
  if (opt.arc_output == ArcOutput::arcs) {
    e.comment(fmt::format("curves fitted with biarcs within {:g} mm", opt.tolerance_mm));
  } else {
    e.comment(fmt::format("curves as chords within {:g} mm", opt.tolerance_mm));
  }
  for (const auto& [k, v] : job.flat_keys) e.comment(fmt::format("{} = {}", k, v));

  // Set-up: units, plane, absolute, feed per minute, no cutter or length compensation, no
  // canned cycle; then the work offset, the tool and its length offset, spindle, coolant.
  switch (d) {
    case Dialect::linuxcnc:
      e.line("G21 G17 G90 G94 G40 G49 G80");
      e.line("G91.1");
      break;
    case Dialect::fanuc:
      e.line("G21 G17 G90 G94 G40 G49 G80");
      break;
    case Dialect::sinumerik:
      e.line("G71 G17 G90 G94 G40");
      break;
    case Dialect::grbl:
      e.line("G21 G17 G90 G94");
      break;
    case Dialect::haas:
    case Dialect::mach3:
      break;  // written as fanuc and linuxcnc
  }
  e.line(std::string(to_string(job.machine.work_offset)));
  const int t = job.tool.tool_number;
  const int h = job.machine.length_offset > 0 ? job.machine.length_offset : t;
  const bool uses_h = d == Dialect::linuxcnc || d == Dialect::fanuc;
  if (uses_h && h == 0) {
    throw InputError(
        "G43 H0 applies no tool length offset: give [tool] tool_number >= 1 or "
        "[machine] length_offset >= 1");
  }
  if (d == Dialect::sinumerik) {
    e.line(fmt::format("T{} D1", t));  // D1: the tool's length offset, applied on the next Z move
    e.line("M6");
  } else if (d == Dialect::grbl) {
    e.comment(
        fmt::format("tool T{}: D = {:g} mm, Z = {} (change it by hand and touch off Z: "
                    "Grbl has no tool table)",
                    t, job.tool.diameter_mm, job.tool.teeth));
  } else {
    e.line(fmt::format("T{} M6", t));
  }
  const std::string spindle = job.cutting.spindle_direction == SpindleDirection::cw ? "M3" : "M4";
  e.line(fmt::format("S{:.0f} {}", job.cutting.spindle_speed_rpm, spindle));
  if (const std::string c = coolant_code(job.cutting.coolant); !c.empty()) e.line(c);

  // Approach: Z alone to the clearance plane (applying the length offset with that move),
  // then X and Y above the start, then straight down to the start if it is lower.
  const double clear_z = job.machine.safe_z_mm;
  const Vec3 start = path.segments().front().start();
  const double approach_z = std::max(clear_z, start.z());
  e.move_z(0, approach_z, uses_h ? fmt::format("G43 H{}", h) : std::string());
  e.move(0, Vec3(start.x(), start.y(), approach_z), 0);
  if (start.z() < approach_z) e.move(0, start, 0);
  FitCache cache;
  for (const Segment& seg : path.segments()) emit_segment(e, seg, opt, cache);
  // Leave at the clearance plane (every planned path ends there already).
  if (e.z() < clear_z) e.move_z(0, clear_z, std::string());

  if (job.cutting.coolant != Coolant::off) e.line("M9");
  e.line("M5");
  e.line((d == Dialect::linuxcnc && !mach3) || d == Dialect::grbl ? "M2" : "M30");
  if ((d == Dialect::linuxcnc && !mach3) || d == Dialect::fanuc) e.line("%");
  return std::move(e.out());
}

GcodeOptions gcode_options(const Machine& machine) {
  GcodeOptions o;
  o.write.dialect = machine.dialect;
  o.write.arc_output = machine.arc_output;
  o.write.tolerance_mm = machine.arc_tolerance_mm;
  o.read.rapid_rate_mm_per_min = machine.rapid_rate_mm_per_min;
  o.read.dialect = machine.dialect;
  o.read.work_system = static_cast<int>(machine.work_offset) + 1;  // G54 .. G59 = 1 .. 6
  for (std::size_t n = 0; n < machine.origins_mm.size(); ++n) {
    if (const auto& v = machine.origins_mm[n])
      o.read.work_offsets_mm[n] = Vec3((*v)[0], (*v)[1], (*v)[2]);
  }
  if (const auto& v = machine.g28_position_mm)
    o.read.g28_position_mm = Vec3((*v)[0], (*v)[1], (*v)[2]);
  if (const auto& v = machine.g30_position_mm)
    o.read.g30_position_mm = Vec3((*v)[0], (*v)[1], (*v)[2]);
  o.read.home_z_mm = machine.safe_z_mm;
  o.read.tool_table = machine.tool_table;
  o.read.max_path_bytes = kPathShareOfMemory * default_memory_limit_bytes();
  return o;
}

}  // namespace trochomill
