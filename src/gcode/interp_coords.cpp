// The interpreter's coordinate systems: G54-G59.3 and their parameters, G10 L2/L20, G92 and
// G52, G28/G30; program, machine and output coordinates.
#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "interp.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill::gcode_detail {

void Interpreter::init_offsets() {
  if (opt_.work_system < 1 || opt_.work_system > 9) {
    throw InputError(
        fmt::format("work system {} is outside 1 (G54) .. 9 (G59.3)", opt_.work_system));
  }
  for (int n = 1; n <= 9; ++n) {
    const auto& o = opt_.work_offsets_mm[static_cast<std::size_t>(n - 1)];
    for (int a = 0; a < 3; ++a) params_[sys_param(n, a)] = o ? (*o)[a] : 0.0;
    params_[sys_param(n, 9)] = opt_.work_rotation_deg[static_cast<std::size_t>(n - 1)];
  }
  system_ = opt_.work_system;
  params_[5220] = system_;
  out_origin_ = Vec3(params_[sys_param(system_, 0)], params_[sys_param(system_, 1)],
                     params_[sys_param(system_, 2)]);
  out_rotation_ = params_[sys_param(system_, 9)];
  for (int k = 0; k < 6; ++k) {
    xout_origin_[static_cast<std::size_t>(k)] = params_[sys_param(system_, 3 + k)];
  }
  load_system();
  // G28 / G30 positions: given, or X0 Y0 of the output frame at home_z above it.
  auto home = [&](const std::optional<Vec3>& given, std::size_t p) {
    const Vec3 h = given ? *given : out_origin_ + Vec3(0, 0, opt_.home_z_mm);
    for (int a = 0; a < 3; ++a) params_[p + static_cast<std::size_t>(a)] = h[a];
    return given.has_value();
  };
  g28_given_ = home(opt_.g28_position_mm, 5161);
  g30_given_ = home(opt_.g30_position_mm, 5181);
}

void Interpreter::load_system() {
  origin_ = Vec3(params_[sys_param(system_, 0)], params_[sys_param(system_, 1)],
                 params_[sys_param(system_, 2)]) +
            ext_offset_;
  rotation_ = params_[sys_param(system_, 9)];
}

// Machine position of the tool tip for program coordinates p.
Vec3 Interpreter::to_machine_tip(const Vec3& program_point) const {
  const Vec3 p = transformed() ? to_transformed(program_point) : program_point;
  double x = p.x() + g92_.x(), y = p.y() + g92_.y();
  rotate(x, y, rotation_);
  return Vec3(x + origin_.x(), y + origin_.y(), p.z() + g92_.z() + origin_.z());
}

// Program coordinates of a machine tip position (LinuxCNC's find_relative without the tool).
Vec3 Interpreter::from_machine_tip(const Vec3& m) const {
  double x = m.x() - origin_.x(), y = m.y() - origin_.y();
  rotate(x, y, -rotation_);
  const Vec3 p(x - g92_.x(), y - g92_.y(), m.z() - origin_.z() - g92_.z());
  return transformed() ? from_transformed(p) : p;
}

// Fanuc's scaling then rotation of program coordinates.
Vec3 Interpreter::to_transformed(Vec3 p) const {
  if (scale_on_) p = scale_centre_ + scale_k_.cwiseProduct(p - scale_centre_);
  if (rotate_on_) {
    double x = p.x() - rot_cx_, y = p.y() - rot_cy_;
    rotate(x, y, rot_deg_);
    p.x() = x + rot_cx_;
    p.y() = y + rot_cy_;
  }
  return p;
}

Vec3 Interpreter::from_transformed(Vec3 p) const {
  if (rotate_on_) {
    double x = p.x() - rot_cx_, y = p.y() - rot_cy_;
    rotate(x, y, -rot_deg_);
    p.x() = x + rot_cx_;
    p.y() = y + rot_cy_;
  }
  if (scale_on_) p = scale_centre_ + (p - scale_centre_).cwiseQuotient(scale_k_);
  return p;
}

Vec3 Interpreter::to_transformed_dir(Vec3 d) const {
  if (scale_on_) d = scale_k_.cwiseProduct(d);
  if (rotate_on_) {
    double x = d.x(), y = d.y();
    rotate(x, y, rot_deg_);
    d.x() = x;
    d.y() = y;
  }
  return d;
}

// G51 X Y Z (the centre; the current point's where left out) with P (one factor) or I J K
// (one per axis; negative mirrors), G50 off; G68 X Y (the centre) R (degrees,
// counter-clockwise; added to the current angle in G91), G69 off. The tool stays where it
// is: its program coordinates follow the new transform.
void Interpreter::program_transform(int g, std::uint32_t column) {
  comp_.refuse(column, code_name('G', g) + " (scaling or rotation of the program)");
  const Vec3 machine = to_machine_tip(cur_pos_);
  const auto centre = [&](char c, int a) {
    if (!block_.has(c)) return cur_pos_[a];
    return absolute_ ? len(c) : cur_pos_[a] + len(c);
  };
  if (g == 510) {
    double k[3];
    if (block_.has('p')) {
      if (block_.has('i') || block_.has('j') || block_.has('k')) {
        fail_at(block_.col('p'), "G51 takes one factor P or one per axis I J K, not both");
      }
      k[0] = k[1] = k[2] = block_['p'];
    } else if (block_.has('i') || block_.has('j') || block_.has('k')) {
      k[0] = block_.has('i') ? block_['i'] : 1.0;
      k[1] = block_.has('j') ? block_['j'] : 1.0;
      k[2] = block_.has('k') ? block_['k'] : 1.0;
    } else {
      fail_at(column, "G51 needs its factor: P (every axis) or I J K (one per axis)");
    }
    for (const double f : k) {
      if (!(std::abs(f) >= 1e-6 && std::abs(f) <= 1e6)) {
        fail_at(column, fmt::format("G51 factor {:g}: allowed 1e-6 .. 1e6 in size (negative "
                                    "mirrors)",
                                    f));
      }
    }
    scale_centre_ = Vec3(centre('x', 0), centre('y', 1), centre('z', 2));
    scale_k_ = Vec3(k[0], k[1], k[2]);
    scale_on_ = true;
    warn(
        fmt::format("G51: the program is scaled by {:g} {:g} {:g} about X{:g} Y{:g} Z{:g} (P and "
                    "I J K read as factors, 1 = full size, as with a decimal point)",
                    k[0], k[1], k[2], scale_centre_.x() / unit_, scale_centre_.y() / unit_,
                    scale_centre_.z() / unit_));
  } else if (g == 500) {
    scale_on_ = false;
  } else if (g == 680) {
    if (plane_ != Plane::xy) fail_at(column, "G68 turns the XY plane (G17) only here");
    if (!block_.has('r')) fail_at(column, "G68 needs the angle R (degrees)");
    const double r = block_['r'];
    rot_cx_ = centre('x', 0);
    rot_cy_ = centre('y', 1);
    rot_deg_ = absolute_ || !rotate_on_ ? r : rot_deg_ + r;
    rotate_on_ = true;
  } else if (g == 690) {
    rotate_on_ = false;
  }
  cur_pos_ = from_machine_tip(machine);
}

// The output frame (the job's work system as the program started) of program coordinates.
Vec3 Interpreter::to_out(const Vec3& p) const {
  const Vec3 m = to_machine_tip(p);
  double x = m.x() - out_origin_.x(), y = m.y() - out_origin_.y();
  rotate(x, y, -out_rotation_);
  return Vec3(x, y, m.z() - out_origin_.z());
}

// A direction (no translation) from program to output frame.
Vec3 Interpreter::dir_to_out(const Vec3& program_dir) const {
  const Vec3 d = transformed() ? to_transformed_dir(program_dir) : program_dir;
  double x = d.x(), y = d.y();
  rotate(x, y, rotation_ - out_rotation_);
  return Vec3(x, y, d.z());
}

std::string Interpreter::system_name(int n) const {
  static constexpr std::array<std::string_view, 9> kNames{"G54", "G55",   "G56",   "G57",  "G58",
                                                          "G59", "G59.1", "G59.2", "G59.3"};
  if (n <= 9) return std::string(kNames[static_cast<std::size_t>(n - 1)]);
  const int p = n - 9;
  if (haas_) return fmt::format("G154 P{}", p);
  if (mach3_) return fmt::format("G59 P{}", p + 6);
  return fmt::format("G54.1 P{}", p);
}

void Interpreter::note_system_used(int n) {
  const auto k = static_cast<std::size_t>(n - 1);
  const bool given = n <= 9 && opt_.work_offsets_mm[k].has_value();
  if (n != opt_.work_system && !given && !system_warned_[k]) {
    system_warned_[k] = true;
    warn(
        fmt::format("{} is used but its offset is not given ([machine] work_offsets{}): "
                    "assumed equal to {}'s",
                    system_name(n), n <= 9 ? "" : ", or G10 L20 in the program",
                    system_name(opt_.work_system)));
    // Unknown offsets are taken as the output system's (a program moving between systems on
    // one part then keeps its geometry).
    for (int a = 0; a < 10; ++a) params_[sys_param(n, a)] = params_[sys_param(opt_.work_system, a)];
  }
}

// The first word of an axis besides X Y Z: said once, with what the reading does with it.
void Interpreter::note_extra_axes() {
  if (extra_seen_) return;
  extra_seen_ = true;
  std::string letters;
  for (const char c : kExtraAxes) {
    if (block_.has(c)) letters += upper(c);
  }
  warn(
      fmt::format("{}: the program uses axes besides X Y Z: they are read as LinuxCNC reads "
                  "them and carried along (check-gcode: their ranges and --trace), but the "
                  "path is the tool's X Y Z motion alone, as if the part did not turn (A B C) "
                  "and U V W stood still; analyses and simulations of this program leave "
                  "that motion out",
                  letters));
}

// G54 .. G59.3; Fanuc's G54.1 P1 .. P300, Haas's G154 P1 .. P99 and G110 .. G129 (G154 P1 ..
// P20), Mach3's G59 P7 .. P306 (its fixtures 7 ..): the extra systems.
void Interpreter::select_system(int g, std::uint32_t column) {
  static constexpr std::array<int, 9> kCodes{540, 550, 560, 570, 580, 590, 591, 592, 593};
  int n = static_cast<int>(std::find(kCodes.begin(), kCodes.end(), g) - kCodes.begin()) + 1;
  const bool extra_p = g == 541 || g == 1540 || (g == 590 && mach3_ && block_.has('p'));
  if (g >= 1100 && g <= 1290) n = 10 + (g - 1100) / 10;
  if (extra_p) {
    const std::string name = code_name('G', g);
    const int lo = 1, hi = g == 590 ? 254 : g == 1540 ? 99 : kExtraSystems;
    if (!block_.has('p'))
      fail_at(column, fmt::format("{} needs the system's number in P ({} .. {})", name, lo, hi));
    const double p = block_['p'];
    if (p < lo || p > hi || p != std::floor(p)) {
      fail_at(block_.col('p'),
              fmt::format("{} P{:g}: P is a whole number {} .. {}", name, p, lo, hi));
    }
    // Mach3: G59 P1 .. P6 are G54 .. G59, P7 .. its fixtures beyond.
    n = g == 590 ? (p <= 6 ? static_cast<int>(p) : 9 + static_cast<int>(p) - 6)
                 : 9 + static_cast<int>(p);
  }
  select_system_n(n);
}

void Interpreter::select_system_n(int n) {
  if (n == system_) return;
  note_system_used(n);
  const Vec3 machine = to_machine_tip(cur_pos_);
  ExtraAxes xm{};
  for (int k = 0; k < 6; ++k)
    xm[static_cast<std::size_t>(k)] = xmachine(k, xpos_[static_cast<std::size_t>(k)]);
  system_ = n;
  params_[5220] = n;
  load_system();
  cur_pos_ = from_machine_tip(machine);
  for (int k = 0; k < 6; ++k) {
    xpos_[static_cast<std::size_t>(k)] = xfrom_machine(k, xm[static_cast<std::size_t>(k)]);
  }
  xnext_ = xpos_;
}

void Interpreter::non_modal(int g, std::uint32_t column) {
  switch (g) {
    case 100:
      g10(column);
      break;
    case 280:
    case 300:
      home_move(g, column);
      break;
    case 53:
      nurbs_end(column);
      break;
    case 500:
    case 510:
    case 680:
    case 690:
      program_transform(g, column);
      break;
    case 281:
    case 301: {
      // Store the current machine position (of the spindle's gauge line, as LinuxCNC) as
      // the G28 / G30 position.
      const Vec3 m = to_machine_tip(cur_pos_) + Vec3(0, 0, tool_z_);
      const std::size_t p = g == 281 ? 5161 : 5181;
      for (int a = 0; a < 3; ++a) params_[p + static_cast<std::size_t>(a)] = m[a];
      for (int k = 0; k < 6; ++k) {
        params_[p + 3 + static_cast<std::size_t>(k)] =
            xmachine(k, xpos_[static_cast<std::size_t>(k)]);
      }
      (g == 281 ? g28_given_ : g30_given_) = true;
      break;
    }
    case 920: {
      // G92: offsets so that the current point has the given coordinates.
      if (!block_.has_axis()) fail_at(column, "G92 needs at least one axis word");
      for (int a = 0; a < 3; ++a) {
        const char c = static_cast<char>('x' + a);
        if (!block_.has(c)) continue;
        g92_[a] = cur_pos_[a] + g92_[a] - len(c);
        cur_pos_[a] = len(c);
        params_[5211 + static_cast<std::size_t>(a)] = g92_[a];
      }
      for (int k = 0; k < 6; ++k) {
        const auto ku = static_cast<std::size_t>(k);
        if (!block_.has(kExtraAxes[ku])) continue;
        xg92_[ku] = xpos_[ku] + xg92_[ku] - xlen(k);
        xpos_[ku] = xlen(k);
        params_[5214 + ku] = xg92_[ku];
      }
      xnext_ = xpos_;
      params_[5210] = 1;
      break;
    }
    case 520: {
      // G52: a local offset, given directly.
      for (int a = 0; a < 3; ++a) {
        const char c = static_cast<char>('x' + a);
        if (!block_.has(c)) continue;
        cur_pos_[a] += g92_[a] - len(c);
        g92_[a] = len(c);
        params_[5211 + static_cast<std::size_t>(a)] = g92_[a];
      }
      for (int k = 0; k < 6; ++k) {
        const auto ku = static_cast<std::size_t>(k);
        if (!block_.has(kExtraAxes[ku])) continue;
        xpos_[ku] += xg92_[ku] - xlen(k);
        xg92_[ku] = xlen(k);
        params_[5214 + ku] = xg92_[ku];
      }
      xnext_ = xpos_;
      params_[5210] = 1;
      break;
    }
    case 921:
    case 922:
      cur_pos_ += g92_;
      g92_.setZero();
      for (std::size_t k = 0; k < 6; ++k) xpos_[k] += xg92_[k];
      xg92_ = {};
      xnext_ = xpos_;
      params_[5210] = 0;
      if (g == 921) {
        for (std::size_t p = 5211; p <= 5219; ++p) params_[p] = 0;
      }
      break;
    case 923:
      params_[5210] = 1;
      for (int a = 0; a < 3; ++a) {
        const double o = params_[5211 + static_cast<std::size_t>(a)];
        cur_pos_[a] += g92_[a] - o;
        g92_[a] = o;
      }
      for (std::size_t k = 0; k < 6; ++k) {
        const double o = params_[5214 + k];
        xpos_[k] += xg92_[k] - o;
        xg92_[k] = o;
      }
      xnext_ = xpos_;
      break;
    default:
      break;
  }
}

// Fanuc's and Haas's G10 data setting (their manuals' forms): L2 P1 .. P6 the offsets of G54 ..
// G59 (P0: Fanuc's external offset, added to every system; Haas's G52), L20 P the extra systems
// (G54.1 P, G154 P), X Y Z and the other axes the offset, added to it in G91; L10 .. L13 P R
// the offset registers (H geometry and wear, D geometry and wear; added in G91), Haas's L1 its
// L11 and Fanuc's L1 (memory A) the one value of H and D.
void Interpreter::fanuc_g10(std::uint32_t column) {
  const double lv = block_['l'];
  const int l = static_cast<int>(lv);
  const bool registers = l == 1 || (l >= 10 && l <= 13);
  if (!registers && l != 2 && l != 20) {
    fail_at(block_.col('l'),
            fmt::format("G10 L{} is not read ({}: L2 and L20 set work offsets, L1 and L10 .. L13 "
                        "offset registers)",
                        l, haas_ ? "Haas" : "Fanuc"));
  }
  if (!block_.has('p')) fail_at(column, fmt::format("G10 L{} needs P", l));
  const double pv = block_['p'];
  if (registers) {
    if (pv < 0 || pv != std::floor(pv) || pv > 9999) {
      fail_at(block_.col('p'),
              fmt::format("G10 L{} P{:g}: P is an offset number 0 .. 9999", l, pv));
    }
    if (!block_.has('r')) fail_at(column, fmt::format("G10 L{} needs the value in R", l));
    OffsetRegister& reg = registers_[static_cast<int>(pv)];
    const double v = len('r');
    const auto set = [&](std::optional<double>& slot) {
      slot = absolute_ ? v : slot.value_or(0.0) + v;
    };
    if (l == 10) set(reg.h_geometry);
    if (l == 11 || (l == 1 && haas_)) set(reg.h_wear);
    if (l == 12) set(reg.d_geometry);
    if (l == 13) set(reg.d_wear);
    if (l == 1 && !haas_) {
      set(reg.h_geometry);
      set(reg.d_geometry);
    }
    return;
  }
  const int hi = l == 2 ? 6 : haas_ ? 99 : kExtraSystems;
  if (pv < 0 || pv > hi || pv != std::floor(pv) || (l == 20 && pv < 1)) {
    fail_at(block_.col('p'),
            fmt::format("G10 L{} P{:g}: P is {} .. {}{}", l, pv, l == 2 ? 0 : 1, hi,
                        l == 2  ? (haas_ ? " (0: G52)" : " (0: the external offset)")
                        : haas_ ? " (G154 P)"
                                : " (G54.1 P)"));
  }
  if (block_.has('r')) fail_at(block_.col('r'), fmt::format("R is not a word of G10 L{}", l));
  const int p = static_cast<int>(pv);
  comp_.refuse(column, "a change of a work offset (G10)");
  const Vec3 machine = to_machine_tip(cur_pos_);
  ExtraAxes xm{};
  for (int k = 0; k < 6; ++k)
    xm[static_cast<std::size_t>(k)] = xmachine(k, xpos_[static_cast<std::size_t>(k)]);
  if (l == 2 && p == 0 && haas_) {
    // Haas: the G52 offset.
    for (int a = 0; a < 3; ++a) {
      const char c = static_cast<char>('x' + a);
      if (!block_.has(c)) continue;
      const double now = absolute_ ? len(c) : g92_[a] + len(c);
      cur_pos_[a] += g92_[a] - now;
      g92_[a] = now;
      params_[5211 + static_cast<std::size_t>(a)] = now;
    }
    params_[5210] = 1;
    return;
  }
  if (l == 2 && p == 0) {
    for (int a = 0; a < 3; ++a) {
      const char c = static_cast<char>('x' + a);
      if (block_.has(c)) ext_offset_[a] = absolute_ ? len(c) : ext_offset_[a] + len(c);
    }
  } else {
    const int n = l == 2 ? p : 9 + p;
    for (int a = 0; a < 3; ++a) {
      const char c = static_cast<char>('x' + a);
      if (block_.has(c))
        params_[sys_param(n, a)] = (absolute_ ? 0 : params_[sys_param(n, a)]) + len(c);
    }
    for (int k = 0; k < 6; ++k) {
      if (block_.has(kExtraAxes[static_cast<std::size_t>(k)])) {
        params_[sys_param(n, 3 + k)] = (absolute_ ? 0 : params_[sys_param(n, 3 + k)]) + xlen(k);
      }
    }
    note_given(n);
    if (n != system_) return;
  }
  // The active system moved: the machine position stays, the program's coordinates follow.
  load_system();
  cur_pos_ = from_machine_tip(machine);
  for (int k = 0; k < 6; ++k) {
    xpos_[static_cast<std::size_t>(k)] = xfrom_machine(k, xm[static_cast<std::size_t>(k)]);
  }
  xnext_ = xpos_;
}

void Interpreter::g10(std::uint32_t column) {
  if (!block_.has('l')) fail_at(column, "G10 needs L (L1 tool table, L2 or L20 work offsets)");
  const double lv = block_['l'];
  if (lv != std::floor(lv) || lv < 0 || lv > 100) {
    fail_at(block_.col('l'), fmt::format("G10 L{:g}: L is 1, 2, 10, 11 or 20", lv));
  }
  if (fanuc_) {
    fanuc_g10(column);
    return;
  }
  const int l = static_cast<int>(lv);
  if (l == 1 || l == 10 || l == 11) {
    // Tool table entries: the length matters only to machine-coordinate moves.
    if (!block_.has('p')) fail_at(column, fmt::format("G10 L{} needs the tool number in P", l));
    const double tool = block_['p'];
    if (tool < 0 || tool != std::floor(tool) || tool > 1e6) {
      fail_at(block_.col('p'), fmt::format("G10 L{} P{:g}: P is a tool number 0 .. 1e6", l, tool));
    }
    ToolTableEntry& t = tools_[static_cast<int>(tool)];
    if (l == 1) {
      if (block_.has('z')) t.length_mm = len('z');
      if (block_.has('r')) t.diameter_mm = 2 * len('r');
    } else {
      // L10/L11: the length so that the current point would be at the given Z.
      if (block_.has('z')) t.length_mm = cur_pos_.z() + tool_z_ - len('z');
    }
    return;
  }
  if (l != 2 && l != 20) {
    fail_at(block_.col('l'), fmt::format("G10 L{} is not supported (L1 L2 L10 L11 L20 are)", l));
  }
  if (!block_.has('p')) fail_at(column, fmt::format("G10 L{} needs the coordinate system in P", l));
  const double pv = block_['p'];
  const bool in_range = pv >= 0 && pv <= 9.0001;  // checked before the conversion
  int n = in_range ? static_cast<int>(pv + 0.0001) : -1;
  if (!in_range || std::abs(pv - n) > 1e-4) {
    fail_at(block_.col('p'),
            fmt::format("G10 L{} P{:g}: P is 0 (the active system) or 1 .. 9", l, pv));
  }
  if (n == 0) n = system_;
  if (n == system_) comp_.refuse(column, "a change of the active system's origin (G10)");
  // The machine position stays; the active system's coordinates follow the new origin.
  const Vec3 machine = to_machine_tip(cur_pos_);
  ExtraAxes xm{};
  for (int k = 0; k < 6; ++k)
    xm[static_cast<std::size_t>(k)] = xmachine(k, xpos_[static_cast<std::size_t>(k)]);
  const double r = block_.has('r') ? block_['r'] : params_[sys_param(n, 9)];
  if (block_.has('r')) {
    if (l == 20) fail_at(block_.col('r'), "R is not allowed in G10 L20");
    params_[sys_param(n, 9)] = r;
  }
  if (l == 2) {
    for (int a = 0; a < 3; ++a) {
      const char c = static_cast<char>('x' + a);
      if (block_.has(c)) params_[sys_param(n, a)] = len(c);
    }
    for (int k = 0; k < 6; ++k) {
      if (block_.has(kExtraAxes[static_cast<std::size_t>(k)]))
        params_[sys_param(n, 3 + k)] = xlen(k);
    }
  } else {
    // L20: the origin such that the current point has the given coordinates in system n.
    // The current point in system n (without G92, as LinuxCNC's find_current_in_system).
    Vec3 in_n = machine;
    in_n.x() -= params_[sys_param(n, 0)];
    in_n.y() -= params_[sys_param(n, 1)];
    in_n.z() -= params_[sys_param(n, 2)];
    double cx = in_n.x(), cy = in_n.y();
    rotate(cx, cy, -r);
    double x = block_.has('x') ? len('x') : cx, y = block_.has('y') ? len('y') : cy;
    double ox = cx, oy = cy;
    rotate(ox, oy, r);
    rotate(x, y, r);
    params_[sys_param(n, 0)] += ox - x;
    params_[sys_param(n, 1)] += oy - y;
    if (block_.has('z')) params_[sys_param(n, 2)] += in_n.z() - len('z');
    for (int k = 0; k < 6; ++k) {
      // The current point in system n without G92, as X Y Z above.
      if (block_.has(kExtraAxes[static_cast<std::size_t>(k)])) {
        params_[sys_param(n, 3 + k)] = xm[static_cast<std::size_t>(k)] - xlen(k);
      }
    }
  }
  note_given(n);
  if (n == system_) {
    load_system();
    cur_pos_ = from_machine_tip(machine);
    for (int k = 0; k < 6; ++k) {
      xpos_[static_cast<std::size_t>(k)] = xfrom_machine(k, xm[static_cast<std::size_t>(k)]);
    }
    xnext_ = xpos_;
  }
}

// G28 / G30: rapid to the waypoint (the axis words, in the current mode), then to the stored
// position for those axes (all three when none is given).
void Interpreter::home_move(int g, std::uint32_t column) {
  const bool given = g == 280 ? g28_given_ : g30_given_;
  if (!given && !home_warned_) {
    home_warned_ = true;
    const std::size_t p = g == 280 ? 5161 : 5181;
    const Vec3 h(params_[p], params_[p + 1], params_[p + 2]);
    const Vec3 o = to_out(from_machine_tip(h));
    warn(
        fmt::format("{}: the machine's {} position is not given ([machine] {}_position): "
                    "assumed X{:g} Y{:g} Z{:g} in the program's frame",
                    code_name('G', g), g == 280 ? "G28" : "G30", g == 280 ? "g28" : "g30", o.x(),
                    o.y(), o.z()));
  }
  ++prog_.info.motion_blocks;
  note_tool_length(g == 280 ? "G28" : "G30");
  const Vec3 waypoint = ends(false);
  emit_line(waypoint, true, column);
  cur_pos_ = waypoint;
  xpos_ = xnext_;
  const std::size_t p = g == 280 ? 5161 : 5181;
  // The stored position is of the gauge line: the tip is the tool length below it.
  const Vec3 home = from_machine_tip(Vec3(params_[p], params_[p + 1], params_[p + 2] - tool_z_));
  Vec3 target = cur_pos_;
  const bool any = block_.has_axis();
  for (int a = 0; a < 3; ++a) {
    if (!any || block_.has(static_cast<char>('x' + a))) target[a] = home[a];
  }
  for (int k = 0; k < 6; ++k) {
    const auto ku = static_cast<std::size_t>(k);
    if (!any || block_.has(kExtraAxes[ku])) {
      xnext_[ku] = xfrom_machine(k, params_[p + 3 + ku]);
    }
  }
  emit_line(target, true, column, !any);
  cur_pos_ = target;
  xpos_ = xnext_;
}

}  // namespace trochomill::gcode_detail
