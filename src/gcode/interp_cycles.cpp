// Canned cycles (G73 G74 G76 G81-G89, G98/G99, L) as LinuxCNC and Fanuc run them, in any
// plane.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "interp.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill::gcode_detail {

// LinuxCNC's cycles in every plane: the hole's position on the plane's axes (i1, i2), the
// drilling along its normal (in; Z in G17, Y in G18, X in G19), R and the bottom on it.

void Interpreter::canned_cycle(int g, std::uint32_t column) {
  const ArcData ax = plane_axes();
  const int i1 = ax.i1, i2 = ax.i2, in = ax.in;
  const char w1 = static_cast<char>('x' + i1), w2 = static_cast<char>('x' + i2),
             wn = static_cast<char>('x' + in);
  const std::string name = code_name('G', g);
  if (feed_mode_ == FeedMode::inverse_time) {
    fail_at(column, "canned cycles cannot run in inverse-time feed (G93)");
  }
  const bool first = g != cycle_motion_;
  if (first && !block_.has(wn)) {
    fail_at(column, fmt::format("{} needs {} (the bottom of the hole) in its first block", name,
                                upper(wn)));
  }
  cycle_motion_ = g;
  const double bottom_word = block_.has(wn) ? len(wn) : cycle_z_;
  if (block_.has('r')) {
    cycle_r_ = len('r');
  } else if (first && haas_) {
    cycle_r_ = absolute_ ? cur_pos_[in] : 0.0;  // Haas: R left out is the initial level
  } else if (first) {
    fail_at(column, fmt::format("{} needs R (the retract plane)", name));
  }
  double current = cur_pos_[in];
  double old;
  if (cycle_il_flag_) {
    old = cycle_il_;
  } else {
    old = cycle_il_ = current;
    cycle_il_flag_ = true;
  }
  double r, bottom, a, b, da = 0, db = 0;
  if (absolute_) {
    r = cycle_r_;
    bottom = bottom_word;
    a = block_.has(w1) ? len(w1) : cur_pos_[i1];
    b = block_.has(w2) ? len(w2) : cur_pos_[i2];
    if (block_.has_polar()) polar_end(a, b);
  } else {
    if (block_.has(w1)) da = len(w1);
    if (block_.has(w2)) db = len(w2);
    r = cycle_r_ + old;
    bottom = r + bottom_word;
    a = cur_pos_[i1];
    b = cur_pos_[i2];
  }
  const bool back_bore_fanuc = fanuc_ && g == 870;
  if (r < bottom && !back_bore_fanuc) {
    fail_at(column, fmt::format("the R plane ({:g}) is below the bottom {} ({:g})", r / unit_,
                                upper(wn), bottom / unit_));
  }
  double q = 0;
  if (g == 730 || g == 830) {
    if (block_.has('q')) {
      cycle_q_ = len('q');
    } else if (cycle_q_ <= 0 || first) {
      fail_at(column, fmt::format("{} needs Q (the peck depth)", name));
    }
    q = cycle_q_;
    if (q <= 0) fail_at(block_.col('q'), "the peck depth Q must be > 0");
  }
  if (g == 760 || back_bore_fanuc) {
    if (block_.has('q')) cycle_q_ = len('q');
    q = cycle_q_;  // the shift off the bore's wall (0: none)
    if (q < 0) fail_at(block_.col('q'), fmt::format("{}'s shift Q must be >= 0", name));
    note_fanuc_shift(name);
  }
  if (g == 820 || g == 860 || g == 880 || g == 890) {
    if (block_.has('p')) {
      cycle_p_ = block_['p'];
    } else if (first && fanuc_) {
      cycle_p_ = 0;  // Fanuc and Haas: no P, no dwell
    } else if (first) {
      fail_at(column, fmt::format("{} needs P (the dwell, s)", name));
    }
  } else if ((g == 740 || g == 840 || g == 760) && block_.has('p')) {
    cycle_p_ = block_['p'];
  }
  // The spindle the cycle needs (dwells take time the path does not model).
  if ((g == 840 || g == 740) && !fanuc_) {
    if (spindle_dir_ == 0) fail_at(column, fmt::format("{} with the spindle stopped", name));
    if (g == 840 && spindle_dir_ < 0) {
      fail_at(column, "G84 (right-hand tapping) with the spindle turning counterclockwise (M4)");
    }
    if (g == 740 && spindle_dir_ > 0) {
      fail_at(column, "G74 (left-hand tapping) with the spindle turning clockwise (M3)");
    }
  }
  if ((g == 860 || g == 870 || g == 880) && spindle_dir_ == 0 && !fanuc_) {
    fail_at(column, fmt::format("{} with the spindle stopped (M3 or M4 first)", name));
  }
  // G87: the offset to pass the bar through the hole, and the top of the back bore.
  double o1 = 0, o2 = 0, middle = 0;
  if (g == 870 && !fanuc_) {
    const char l1 = static_cast<char>('i' + i1), l2 = static_cast<char>('i' + i2),
               ln = static_cast<char>('i' + in);
    for (const char c : {l1, l2, ln}) {
      if (first && !block_.has(c)) {
        fail_at(column, fmt::format("G87 needs {} in its first block (I J K: the offset along "
                                    "the plane's axes, the top of the back bore)",
                                    upper(c)));
      }
    }
    const std::size_t k1 = static_cast<std::size_t>(i1), k2 = static_cast<std::size_t>(i2),
                      kn = static_cast<std::size_t>(in);
    for (const std::size_t k : {k1, k2, kn}) {
      const char c = static_cast<char>('i' + k);
      if (block_.has(c)) cycle_ijk_[k] = len(c);
    }
    o1 = cycle_ijk_[k1];
    o2 = cycle_ijk_[k2];
    middle = absolute_ ? cycle_ijk_[kn] : bottom + cycle_ijk_[kn];
  }
  int repeats = 1;
  if (block_.has('l')) {
    const double l = block_['l'];
    if (l < 0 || l != std::floor(l) || l > 1e6) {
      fail_at(block_.col('l'), "the repeat count L must be a whole number 0 .. 1e6");
    }
    repeats = static_cast<int>(l);
  }
  auto at = [&](double pa, double pb, double pn) {
    Vec3 v = Vec3::Zero();
    v[i1] = pa;
    v[i2] = pb;
    v[in] = pn;
    return v;
  };
  // Below the R plane: rapid straight up to it first.
  if (old < r) {
    line_to(at(cur_pos_[i1], cur_pos_[i2], r), true, column);
    old = r;
    current = r;
  }
  const double clear = retract_r_ ? r : old;
  // Fanuc's shifted cycles: the shift is along the plane's first axis (+X in G17).
  const double s1 = q;
  for (int k = 0; k < repeats; ++k) {
    a += da;
    b += db;
    // G91's polar words step each repeat round the origin (LinuxCNC's hole circles).
    if (!absolute_ && block_.has_polar()) polar_end(a, b);
    if (back_bore_fanuc) {
      // At the initial level: orient, shift, rapid down to R (the bore's bottom), shift
      // back, feed up to the bottom word (the bore's top), orient, shift, rapid out.
      line_to(at(a, b, current), true, column);
      line_to(at(a + s1, b, current), true, column);
      line_to(at(a + s1, b, r), true, column);
      line_to(at(a, b, r), true, column);
      line_to(at(a, b, bottom), false, column);
      line_to(at(a + s1, b, bottom), true, column);
      line_to(at(a + s1, b, old), true, column);
      line_to(at(a, b, old), true, column);
      continue;
    }
    if (k == 0 && current > r) {
      line_to(at(a, b, current), true, column);
      line_to(at(a, b, r), true, column);
    } else {
      line_to(at(a, b, clear), true, column);
      if (clear > r) line_to(at(a, b, r), true, column);
    }
    switch (g) {
      case 810:
      case 820:
      case 860:
        line_to(at(a, b, bottom), false, column);
        line_to(at(a, b, clear), true, column);
        break;
      case 850:
        line_to(at(a, b, bottom), false, column);
        line_to(at(a, b, r), false, column);
        line_to(at(a, b, clear), true, column);
        break;
      case 890:
        line_to(at(a, b, bottom), false, column);
        line_to(at(a, b, clear), false, column);
        break;
      case 740:
      case 840:
        // In at the feed, the spindle reversed, out at the feed (Fanuc: out to R, then a
        // rapid to the initial level).
        line_to(at(a, b, bottom), false, column);
        if (fanuc_) {
          line_to(at(a, b, r), false, column);
          if (clear > r) line_to(at(a, b, clear), true, column);
        } else {
          line_to(at(a, b, clear), false, column);
        }
        break;
      case 760:
        // Fanuc's fine boring: in at the feed, the spindle oriented, shifted off the wall,
        // out at rapid, shifted back.
        line_to(at(a, b, bottom), false, column);
        line_to(at(a + s1, b, bottom), true, column);
        line_to(at(a + s1, b, clear), true, column);
        line_to(at(a, b, clear), true, column);
        break;
      case 870:
        // LinuxCNC's back boring: through the hole at the offset with the spindle oriented,
        // over to the axis, feed up to the top of the bore and back down, out at the offset.
        line_to(at(a + o1, b + o2, r), true, column);
        line_to(at(a + o1, b + o2, bottom), true, column);
        line_to(at(a, b, bottom), true, column);
        line_to(at(a, b, middle), false, column);
        line_to(at(a, b, bottom), false, column);
        line_to(at(a + o1, b + o2, bottom), true, column);
        line_to(at(a + o1, b + o2, clear), true, column);
        line_to(at(a, b, clear), true, column);
        break;
      case 880:
        // In at the feed; the program stops and the operator retracts by hand: modelled as
        // a rapid to the clear plane, named in a warning.
        line_to(at(a, b, bottom), false, column);
        if (!g88_warned_) {
          g88_warned_ = true;
          warn(
              "G88 stops the program for the operator to retract the spindle by hand: "
              "modelled as a rapid straight out to the clear plane");
        }
        line_to(at(a, b, clear), true, column);
        break;
      case 730:
      case 830: {
        const double back = opt_.peck_clearance_mm;
        for (double depth = r - q; depth > bottom; depth -= q) {
          line_to(at(a, b, depth), false, column);
          if (g == 830) {
            line_to(at(a, b, r), true, column);
            line_to(at(a, b, depth + back), true, column);
          } else {
            line_to(at(a, b, depth + back), true, column);
          }
        }
        line_to(at(a, b, bottom), false, column);
        line_to(at(a, b, clear), true, column);
        break;
      }
      default:
        break;
    }
  }
  cur_pos_ = at(a, b, back_bore_fanuc ? old : clear);
  cycle_z_ = bottom_word;
}

// The plane's axes: i1, i2 on it, in along its normal.
ArcData Interpreter::plane_axes() const {
  ArcData d;
  if (plane_ == Plane::zx) {
    d.i1 = 2;
    d.i2 = 0;
    d.in = 1;
  } else if (plane_ == Plane::yz) {
    d.i1 = 1;
    d.i2 = 2;
    d.in = 0;
  }
  return d;
}

void Interpreter::note_fanuc_shift(const std::string& name) {
  if (shift_warned_) return;
  shift_warned_ = true;
  warn(
      fmt::format("{}: the shift Q off the bore's wall goes along +{} (Fanuc's parameter "
                  "5101 RD1 = RD2 = 0; the machine's own setting may differ)",
                  name,
                  plane_ == Plane::xy   ? 'X'
                  : plane_ == Plane::zx ? 'Z'
                                        : 'Y'));
}

void Interpreter::line_to(const Vec3& target, bool rapid, std::uint32_t column) {
  emit_line(target, rapid, column, true);
  cur_pos_ = target;
}

// ---- threading ------------------------------------------------------------------------------

// G33 (a straight move synchronized with the spindle: K per revolution), G33.1 (rigid
// tapping: in to the end point and back out to where it started, the way out I times faster)
// and LinuxCNC's G76 (threading_cycle), as LinuxCNC 2.9's convert_straight runs them: their
// speed is the pitch times the spindle speed S (mm/min); F is not theirs.
void Interpreter::thread(std::uint32_t column) {
  const std::string name = code_name('G', motion_);
  if (motion_ == 760) {
    threading_cycle(column);
    return;
  }
  comp_.refuse(column, name + " (spindle-synchronized motion)");
  if (!block_.has('k')) fail_at(column, "K word missing with g33/g33.1");
  if (block_.has('f')) fail_at(block_.col('f'), "F word used with a g33/g33.1");
  if (spindle_dir_ == 0) fail_at(column, fmt::format("Spindle not turning in {}", name));
  if (feed_mode_ == FeedMode::inverse_time) {
    fail_at(column, fmt::format("{} in inverse time (G93): its speed is K per revolution", name));
  }
  const double f = len('k') * spindle_rpm(column);  // mm per revolution times rpm
  if (!(f > 0)) {
    fail_at(column, fmt::format("{} at K{:g} and S{:g}: the move would never end (K > 0 and "
                                "S > 0 give its speed)",
                                name, block_['k'], speed_));
  }
  const Vec3 start = cur_pos_, target = ends(false);
  if (motion_ == 331 && xnext_ != xpos_) {
    fail_at(column, "G33.1 (rigid tapping) moves X Y Z only");
  }
  const bool xy = block_.has('x') || block_.has('y') || block_.has_polar();
  put_line(to_out(target), false, f, column, cur_.source, cur_.line_no, xy);
  if (motion_ == 330) {
    cur_pos_ = target;
    xpos_ = xnext_;
    return;
  }
  // Rigid tapping returns to its start, I times faster (I >= 1).
  const double scale = block_.has('i') ? std::max(1.0, block_['i']) : 1.0;
  put_line(to_out(start), false, f * scale, column, cur_.source, cur_.line_no, xy);
}

// LinuxCNC's G76 threading cycle (its convert_threading_cycle and threading_pass): passes
// along Z at the pitch P per revolution, each deeper along X (I the thread's offset from the
// start, its sign the side: > 0 boring; J the first cut's depth, K the full depth, R the
// degression of the depths, Q the compound angle in degrees, H the spring passes, E and L the
// entry/exit tapers), back at rapid, then to the block's end point. The spindle turns; no
// cutter compensation, no A B C U V W motion.
void Interpreter::threading_cycle(std::uint32_t column) {
  if (comp_.on())
    fail_at(column, "Cannot use G76 threading cycle with cutter radius compensation on");
  if (!block_.has('p')) fail_at(column, "P word missing with G76");
  if (!block_.has('i') || !block_.has('j') || !block_.has('k')) {
    fail_at(column, "I J or K words missing with G76");
  }
  if (spindle_dir_ == 0) fail_at(column, "Chosen spindle (0) not turning in G76");
  if (feed_mode_ == FeedMode::inverse_time) {
    fail_at(column, "G76 in inverse time (G93): its speed is P per revolution");
  }
  const Vec3 start = cur_pos_, end = ends(false);
  if (xnext_ != xpos_) fail_at(column, "Cannot move rotary axes with G76");
  const double i = len('i'), j = len('j'), k = len('k');
  if (i == 0) fail_at(block_.col('i'), "In G76, I must not be 0");
  if (j <= 0) fail_at(block_.col('j'), "In G76, J must be greater than 0");
  if (k <= j) fail_at(block_.col('k'), "In G76, K must be greater than J");
  const double pitch = len('p');
  if (!(pitch > 0) || !(speed_ > 0)) {
    fail_at(column, fmt::format("G76 at P{:g} and S{:g}: the passes would never end (P > 0 and "
                                "S > 0 give their speed)",
                                block_['p'], speed_));
  }
  const bool boring = i > 0;
  const double safe_x = start.x(), full_dia_depth = std::abs(i), start_depth = std::abs(i) + j;
  const double full_height = k, end_depth = k + std::abs(i);
  double angle = block_.has('q') ? block_['q'] * kPi / 180 : 0.0;
  if (end.z() > start.z()) angle = -angle;
  // H spring passes and L taper flags: whole numbers in a range before they become ints.
  if (block_.has('h') && !(block_['h'] >= 0 && block_['h'] <= 1000)) {
    fail_at(block_.col('h'), "G76's spring passes H must be 0 .. 1000");
  }
  if (block_.has('l') && !(block_['l'] >= -1 && block_['l'] <= 3)) {
    fail_at(block_.col('l'), "G76's taper flags L must be 0 .. 3 (1 entry, 2 exit, 3 both)");
  }
  const int spring = block_.has('h') ? static_cast<int>(block_['h']) : 0;
  const double degression = block_.has('r') && block_['r'] >= 1 ? block_['r'] : 1.0;
  double taper = block_.has('e') ? std::max(0.0, len('e')) : 0.0;
  const double taper_pitch = taper > 0 ? pitch * std::hypot(taper, full_height) / taper : pitch;
  if (end.z() > start.z()) taper = -taper;
  const int flags = block_.has('l') ? std::max(0, static_cast<int>(block_['l'])) : 0;
  const bool entry_taper = taper != 0 && (flags & 1) != 0,
             exit_taper = taper != 0 && (flags & 2) != 0;
  const double target_z = end.z() + k * std::tan(angle);
  // The passes: depth = |I| + J pass^(1/R) until the full depth, then H + 1 at it.
  const double passes = std::pow(k / j, degression) + spring + 2;
  if (passes > 1e5) {
    fail_at(column, fmt::format("G76 would cut {:.3g} passes (K/J = {:g} to the power R = {:g})",
                                passes, k / j, degression));
  }
  const double rpm = spindle_rpm(column);
  const double f = pitch * rpm, f_taper = taper_pitch * rpm;
  const auto x_at = [&](double d) { return boring ? safe_x + d : safe_x - d; };
  const auto at = [&](double x, double z) { return Vec3(x, start.y(), z); };
  const auto go = [&](const Vec3& p, bool rapid, double feed) {
    put_line(to_out(p), rapid, feed, column, cur_.source, cur_.line_no, true);
    cur_pos_ = p;
  };
  const auto pass = [&](double depth, double zoff) {
    go(at(x_at(depth - end_depth), start.z() - zoff), true, 0);  // back
    if (entry_taper) {
      go(at(x_at(depth - full_height), start.z() - zoff), false, f_taper);  // in
      go(at(x_at(depth), start.z() - zoff - taper), false, f_taper);        // angled in
    } else {
      go(at(x_at(depth), start.z() - zoff), true, 0);  // in
    }
    if (exit_taper) {
      go(at(x_at(depth), target_z - zoff + taper), false, f);              // over
      go(at(x_at(depth - full_height), target_z - zoff), false, f_taper);  // angled out
    } else {
      go(at(x_at(depth), target_z - zoff), false, f);  // over
    }
    go(at(x_at(depth - end_depth), target_z - zoff), true, 0);  // out
  };
  double depth = start_depth;
  int n = 1;
  while (depth < end_depth) {
    pass(depth, (depth - full_dia_depth) * std::tan(angle));
    depth = full_dia_depth + j * std::pow(++n, 1.0 / degression);
  }
  for (int s = 0; s <= spring; ++s) pass(end_depth, (end_depth - full_dia_depth) * std::tan(angle));
  go(end, true, 0);
}

}  // namespace trochomill::gcode_detail
