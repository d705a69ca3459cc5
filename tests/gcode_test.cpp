// G-code: biarc and chord fits never deviate more than the tolerance (checked against the
// curve with an independent nearest-point search), writer -> reader round trips for every
// dialect and family, the reader's geometry against closed forms, and every malformed
// program in tests/data/bad_gcode gives the message its first line expects.
#include "trochomill/gcode.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>
#include <sstream>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/io.hpp"
#include "trochomill/units.hpp"

namespace trochomill {
namespace {

// Distance from q to the curve: a dense parameter scan, then golden-section refinement around
// every local minimum of the scan (a trochoid's branches pass within micrometres of each other,
// so refining only the best sample can land on the wrong branch). Independent of the fitter.
double distance_to_curve(const Segment& c, const Vec3& q) {
  const int n = 4000;
  const double du = (c.u1() - c.u0()) / n;
  std::vector<double> d(n + 1);
  for (int i = 0; i <= n; ++i) d[i] = (c.point_u(c.u0() + du * i) - q).norm();
  double best = *std::min_element(d.begin(), d.end());
  const double g = (std::sqrt(5.0) - 1) / 2;
  for (int i = 0; i <= n; ++i) {
    const bool local_min = (i == 0 || d[i] <= d[i - 1]) && (i == n || d[i] <= d[i + 1]);
    if (!local_min) continue;
    double lo = c.u0() + du * std::max(0, i - 1), hi = c.u0() + du * std::min(n, i + 1);
    if (lo > hi) std::swap(lo, hi);
    for (int it = 0; it < 80; ++it) {
      const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
      if ((c.point_u(m1) - q).norm() < (c.point_u(m2) - q).norm())
        hi = m2;
      else
        lo = m1;
    }
    best = std::min(best, (c.point_u(0.5 * (lo + hi)) - q).norm());
  }
  return best;
}

std::vector<Segment> test_curves() {
  std::vector<Segment> out;
  for (double ratio : {0.5, 0.8, 1.0, 1.2}) {
    out.push_back(Segment::curve(Vec3(0, 0, -6), Vec3(-5, 0, 0), Vec3(0, 5 * ratio, 0),
                                 Vec3(0, 1.0 / kTwoPi, 0), 0, kTwoPi, Motion::feed, 600));
  }
  // Half ellipse of linear-elliptical, a strongly eccentric ellipse, a reversed sweep.
  out.push_back(Segment::curve(Vec3(0, 0, 0), Vec3(-5, 0, 0), Vec3(0, 4, 0),
                               Vec3(0, 1.0 / kTwoPi, 0), kPi, kTwoPi, Motion::feed, 600));
  out.push_back(Segment::curve(Vec3(1, 2, 0), Vec3(-17, 0, 0), Vec3(0, 2, 0), Vec3::Zero(), 0,
                               kTwoPi, Motion::feed, 600));
  out.push_back(Segment::curve(Vec3(0, 0, 0), Vec3(3, 0, 0), Vec3(0, 2, 0), Vec3(0.1, 0, 0), 1, -4,
                               Motion::feed, 600));
  return out;
}

TEST(Biarc, DeviationNeverAboveTolerance) {
  for (double tol : {1e-2, 1e-3, 1e-4}) {
    for (const Segment& c : test_curves()) {
      const auto arcs = fit_biarcs(c, tol);
      ASSERT_FALSE(arcs.empty());
      EXPECT_LE((arcs.front().start - c.start()).norm(), 1e-12);
      EXPECT_LE((arcs.back().end - c.end()).norm(), 1e-12);
      double worst = 0;
      for (std::size_t k = 0; k < arcs.size(); ++k) {
        const FitArc& a = arcs[k];
        if (k > 0) {
          EXPECT_LE((a.start - arcs[k - 1].end).norm(), 1e-12);  // continuous
        }
        // 20 points along each arc (arcs -> curve direction).
        for (int i = 0; i <= 20; ++i) {
          Vec3 p;
          if (a.is_line) {
            p = a.start + (a.end - a.start) * (i / 20.0);
          } else {
            const double a0 =
                std::atan2(a.start.y() - a.cy, a.start.x() - a.cx) + a.sweep_rad * i / 20.0;
            p = Vec3(a.cx + a.radius_mm * std::cos(a0), a.cy + a.radius_mm * std::sin(a0),
                     a.start.z());
          }
          worst = std::max(worst, distance_to_curve(c, p));
        }
      }
      EXPECT_LE(worst, tol) << "tol " << tol << ", " << arcs.size()
                            << " arcs, curve a=" << c.axis_a().transpose()
                            << " b=" << c.axis_b().transpose() << " v=" << c.drift().transpose()
                            << " u " << c.u0() << ".." << c.u1();
      // Not absurdly fine either: the worst deviation uses a fair share of the tolerance.
      EXPECT_GT(worst, 0.05 * tol);
    }
  }
}

TEST(Biarc, ChordsNeverAboveTolerance) {
  for (double tol : {1e-2, 1e-3}) {
    for (const Segment& c : test_curves()) {
      const auto pts = fit_chords(c, tol);
      Vec3 prev = c.start();
      double worst = 0;
      for (const Vec3& p : pts) {
        for (int i = 0; i <= 10; ++i)
          worst = std::max(worst, distance_to_curve(c, prev + (p - prev) * (i / 10.0)));
        prev = p;
      }
      EXPECT_LE((pts.back() - c.end()).norm(), 1e-12);
      EXPECT_LE(worst, tol) << pts.size() << " chords, curve a=" << c.axis_a().transpose()
                            << " b=" << c.axis_b().transpose() << " v=" << c.drift().transpose();
    }
  }
}

// Writer -> reader: the read path stays within tolerance + coordinate rounding of the
// planned path in both directions (Hausdorff, via ordered polyline distances on samples
// 0.01 mm apart, whose chord error is below 0.01^2 / (8 * 4 mm) = 3e-6 mm).
TEST(Gcode, RoundTripEveryDialectAndFamily) {
  const double tol = 0.001;
  const double rounding = 0.5e-4 * std::sqrt(3.0);  // 4 decimals on three axes
  for (const Dialect d : {Dialect::linuxcnc, Dialect::fanuc, Dialect::sinumerik, Dialect::grbl,
                          Dialect::haas, Dialect::mach3}) {
    for (const std::string type :
         {"trochoidal", "circular", "elliptical", "linear-elliptical", "linear"}) {
      for (const ArcOutput mode : {ArcOutput::arcs, ArcOutput::chords}) {
        std::vector<Override> ov = {
            parse_override("slot.length=6"),
            parse_override(
                "path.aspect_ratio=" +
                std::string(type == "elliptical" || type == "linear-elliptical" ? "0.8" : "1")),
            parse_override("path.linear_distance=1"),
            parse_override("path.entry=" + std::string(type == "linear" ? "ramp" : "helix"))};
        if (type == "trochoidal" || type == "circular" || type == "linear")
          ov.erase(ov.begin() + 1);
        const Job job = test::wagih_job(type, ov);
        const PlannedPath pp = plan_path(job);
        GcodeWriteOptions wo;
        wo.dialect = d;
        wo.arc_output = mode;
        wo.tolerance_mm = tol;
        const std::string code = write_gcode(job, pp.path, wo);
        GcodeReadOptions ro;
        ro.rapid_rate_mm_per_min = job.machine.rapid_rate_mm_per_min;
        if (d == Dialect::haas || d == Dialect::mach3) ro.dialect = d;  // read as its control
        const GcodeProgram prog = read_gcode(code, "roundtrip.ngc", ro);
        const std::string label = std::string(to_string(d)) + " " + type +
                                  (mode == ArcOutput::arcs ? " arcs" : " chords");
        const PathSamples a = sample_by_length(pp.path, 0.01),
                          b = sample_by_length(prog.path, 0.01);
        std::size_t hint = 0;
        double worst = 0;
        for (std::size_t i = 0; i < b.size(); ++i) {
          worst = std::max(worst, test::distance_to_polyline(
                                      a, Vec3(b.x_mm[i], b.y_mm[i], b.z_mm[i]), hint, 400));
        }
        hint = 0;
        for (std::size_t i = 0; i < a.size(); ++i) {
          worst = std::max(worst, test::distance_to_polyline(
                                      b, Vec3(a.x_mm[i], a.y_mm[i], a.z_mm[i]), hint, 400));
        }
        EXPECT_LE(worst, tol + rounding + 1e-5) << label;
        // Length and time agree to the fit: the biarcs' length differs by O(tol) per arc.
        EXPECT_NEAR(prog.path.length_mm(), pp.path.length_mm(), 1e-4 * pp.path.length_mm())
            << label;
        EXPECT_NEAR(prog.path.duration_s(), pp.path.duration_s(), 1e-4 * pp.path.duration_s())
            << label;
        EXPECT_EQ(prog.info.max_spindle_rpm, 2000.0) << label;
        if (d == Dialect::grbl) {
          for (const auto& seg : prog.path.segments()) {
            if (seg.kind() == Segment::Kind::curve) {
              EXPECT_LT(std::abs(seg.u1() - seg.u0()), kPi) << label;
            }
          }
        }
      }
    }
  }
}

// A pocket's pass can end in an arc shorter than the written precision. Its two ends then
// print as one point, and every control reads G2/G3 with its end at its start as a full
// circle: here one of radius 2.8 mm, sweeping 17.6 mm through the stock (a 1 mm tool's
// pocket once did so through its island). Such an arc is written as a line, a move that
// changes nothing at the precision is not written, and read back the program is as long as
// the path.
TEST(Gcode, AnArcShorterThanThePrecisionIsNeverAFullCircle) {
  const Job job = test::wagih_job("trochoidal", {});
  ToolPath path;
  const double F = 1200;
  path.append(Segment::line(Vec3(0, 0, -1), Vec3(5, 0, -1), Motion::feed, F));
  // Centre 2.8 mm off, a sweep of 1e-5 rad: a chord of 2.8e-5 mm, under the 1e-4 mm of
  // 4 decimals (both ends print as X5 Y0).
  path.append(Segment::arc_xy(5, 2.8, 2.8, -0.5 * kPi, 1e-5, -1, -1, Motion::feed, F));
  const Vec3 e = path.segments().back().end();
  path.append(Segment::line(e, e, Motion::feed, F));  // a line that goes nowhere
  path.append(Segment::line(e, Vec3(5, 3, -1), Motion::feed, F));
  for (const Dialect d : {Dialect::linuxcnc, Dialect::fanuc, Dialect::sinumerik, Dialect::grbl,
                          Dialect::haas, Dialect::mach3}) {
    GcodeWriteOptions wo;
    wo.dialect = d;
    const std::string code = write_gcode(job, path, wo);
    std::istringstream lines(code);
    for (std::string l; std::getline(lines, l);) {
      EXPECT_FALSE(l.rfind("G2 ", 0) == 0 || l.rfind("G3 ", 0) == 0) << to_string(d) << ": " << l;
      EXPECT_FALSE(l == "G1" || l == "G0") << to_string(d) << ": a move of nothing";
    }
    GcodeReadOptions ro;
    if (d == Dialect::haas || d == Dialect::mach3) ro.dialect = d;
    const GcodeProgram prog = read_gcode(code, "tiny-arc.ngc", ro);
    // The feed moves: 5 mm, the arc's 2.8e-5 mm, 3 mm (within the rounding of 4 decimals).
    double feed_mm = 0;
    for (const Segment& s : prog.path.segments()) {
      if (s.motion() == Motion::feed && s.start().z() < 0 && s.end().z() < 0)
        feed_mm += s.length_mm();
    }
    EXPECT_NEAR(feed_mm, 8.0, 2e-4) << to_string(d);
  }
}

TEST(Gcode, HeadersFollowTheDialect) {
  const Job job = test::wagih_job("elliptical", {parse_override("cutting.coolant=flood")});
  const PlannedPath pp = plan_path(job);
  auto write = [&](Dialect d) {
    GcodeWriteOptions o;
    o.dialect = d;
    return write_gcode(job, pp.path, o);
  };
  const std::string lcnc = write(Dialect::linuxcnc), fanuc = write(Dialect::fanuc),
                    sin = write(Dialect::sinumerik), grbl = write(Dialect::grbl);
  EXPECT_NE(lcnc.find("G21 G17 G90 G94"), std::string::npos);
  EXPECT_NE(lcnc.find("G91.1"), std::string::npos);
  EXPECT_NE(lcnc.find("\nM2\n%"), std::string::npos);
  EXPECT_NE(fanuc.find("%\nO1000\n"), std::string::npos);
  EXPECT_NE(fanuc.find("\nM30\n%"), std::string::npos);
  EXPECT_NE(sin.find("G71 G17 G90 G94"), std::string::npos);
  EXPECT_NE(sin.find("; trochomill"), std::string::npos);
  EXPECT_NE(sin.find("T1 D1\nM6"), std::string::npos);
  EXPECT_EQ(grbl.find("M6"), std::string::npos);  // Grbl has no tool changer
  for (const std::string* s : {&lcnc, &fanuc, &sin, &grbl}) {
    EXPECT_NE(s->find("S2000 M3"), std::string::npos);
    EXPECT_NE(s->find("M8"), std::string::npos);
    EXPECT_NE(s->find("F600"), std::string::npos);
    EXPECT_NE(s->find("path.step = 1.0"), std::string::npos);  // job parameters recorded
  }
}

GcodeProgram read(const std::string& text) { return read_gcode(text, "t.ngc"); }

TEST(GcodeReader, ArcFormsAndModes) {
  // Quarter circle, I/J form, radius 5: length 5 pi / 2.
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG3 X-5 Y5 I-5 J0 F100").path.length_mm(), 5 * kPi / 2, 1e-12);
  // R form: R+5 takes the short way (90 deg), R-5 the long way (270 deg).
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG2 X5 Y5 R5 F100").path.length_mm(), 5 * kPi / 2, 1e-12);
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG2 X5 Y5 R-5 F100").path.length_mm(), 15 * kPi / 2, 1e-12);
  // Sinumerik CR= form.
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG2 X5 Y5 CR=5 F100").path.length_mm(), 5 * kPi / 2, 1e-12);
  // Full circle (end = start) and P turns with a helical drop.
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG2 X0 Y0 I5 J0 F100").path.length_mm(), 10 * kPi, 1e-12);
  EXPECT_NEAR(read("G0 X0 Y0 Z0\nG2 X0 Y0 Z-3 I5 J0 P3 F100").path.length_mm(),
              std::hypot(30 * kPi, 3.0), 1e-12);
  // Absolute arc centres (G90.1).
  EXPECT_NEAR(read("G90.1\nG0 X10 Y0 Z0\nG3 X0 Y10 I0 J0 F100").path.length_mm(), 5 * kPi, 1e-12);
  // G18 (ZX plane) arc of radius 2, a half turn: length 2 pi; it stays in y = 0.
  const GcodeProgram zx = read("G18\nG0 X0 Y0 Z0\nG2 X4 Z0 I2 K0 F100");
  EXPECT_NEAR(zx.path.length_mm(), 2 * kPi, 1e-12);
  EXPECT_NEAR(zx.path.point_at_length(kPi).y(), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(zx.path.point_at_length(kPi).z()), 2.0, 1e-12);
  // G19 (YZ plane) quarter arc.
  EXPECT_NEAR(read("G19\nG0 X0 Y0 Z0\nG3 Y2 Z2 J0 K2 F100").path.length_mm(), kPi, 1e-12);
}

TEST(GcodeReader, UnitsDistanceModesCommentsAndLineNumbers) {
  // Inches: G20 with F in inch/min; a 1 inch move at 10 in/min takes 6 s.
  const GcodeProgram in = read("G20\nG0 X0 Y0 Z0\nG1 X1 F10");
  EXPECT_NEAR(in.path.length_mm(), 25.4, 1e-12);
  EXPECT_NEAR(in.path.duration_s(), 6.0, 1e-12);
  EXPECT_TRUE(in.info.inch_units_seen);
  // Incremental moves, line numbers, both comment styles, block delete, lower case.
  const GcodeProgram inc = read(
      "N10 G21 G90 (set up)\nN20 g0 x0 y0 z0 ; start\n/N30 G91 G1 X3 F600\nN40 Y4\nN50 G90 X0 Y0");
  EXPECT_NEAR(inc.path.length_mm(), 3 + 4 + 5, 1e-12);
  EXPECT_NEAR(inc.path.duration_s(), 12.0 / 10.0, 1e-12);
  // Sinumerik units G71 and tolerated codes; M30 ends the program (later blocks ignored).
  const GcodeProgram sin =
      read("G71 G17 G90 G94 G40\nT1 D1\nM6\nS1000 M3\nG0 X0 Y0 Z0\nG1 X10 F100\nM30\nG1 X1000");
  EXPECT_NEAR(sin.path.length_mm(), 10.0, 1e-12);
  // Rapids take the rapid rate.
  GcodeReadOptions ro;
  ro.rapid_rate_mm_per_min = 6000;
  EXPECT_NEAR(read_gcode("G0 X0 Y0 Z0\nG0 X100", "r", ro).path.duration_s(), 1.0, 1e-12);
}

// Data-driven: first line "; expect: LINE:COL: message"; the error must read
// "<file>:LINE:COL: message".
// Lines are counted as `wc -l` and editors count them: a final newline ends the last line,
// M30 ends the program, and a last line without a newline still counts.
TEST(GcodeReader, CountsTheProgramsLines) {
  const std::string body = "G21 G90\nG1 X1 F100\nG1 X2\n";
  EXPECT_EQ(read_gcode(body, "a.ngc").info.lines, 3u);
  EXPECT_EQ(read_gcode(body + "M30\n", "b.ngc").info.lines, 4u);
  EXPECT_EQ(read_gcode(body + "M30\n(after the end)\n", "c.ngc").info.lines, 4u);
  EXPECT_EQ(read_gcode("G21 G90\nG1 X1 F100\nG1 X2", "d.ngc").info.lines, 3u);
  EXPECT_EQ(read_gcode(body + "\n", "e.ngc").info.lines, 4u);  // a blank last line is a line
}

TEST(GcodeReader, MalformedProgramsGiveTheExpectedMessage) {
  const auto files = test::files_in(test::source_dir() / "tests/data/bad_gcode", ".ngc");
  ASSERT_GE(files.size(), 60u);
  // A small block budget: loop_without_end.ngc must stop within the test's time.
  GcodeReadOptions ro;
  ro.max_blocks = 100'000;
  for (const auto& f : files) {
    std::string expect = test::first_line(f);
    expect = expect.substr(std::string("; expect: ").size());
    try {
      (void)read_gcode_file(f, ro);
      ADD_FAILURE() << f << ": read without error, expected: " << expect;
    } catch (const InputError& e) {
      const std::string want = std::isdigit(static_cast<unsigned char>(expect[0]))
                                   ? f.string() + ":" + expect
                                   : f.string() + ": " + expect;
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos)
          << "\n  expected: " << want << "\n  got:      " << e.what();
    }
  }
}

// A program's header names the job it was written for: read back with that job nothing
// differs; with another step, placement or tool each changed key is named once, with both
// values; numbers equal as numbers ("1" and "1.0") agree; a program without a header
// (written by hand or another CAM) has nothing to compare.
TEST(GcodeHeader, MismatchesNameEachChangedKey) {
  const Job job = test::wagih_job("trochoidal", {{"slot.length", "4", {}}});
  const std::string code = write_gcode(job, plan_path(job).path, gcode_options(job.machine).write);
  const GcodeProgram prog = read_gcode(code, "p.ngc");
  EXPECT_TRUE(header_mismatches(job, prog, "p.ngc").empty());
  const Job other = test::wagih_job("trochoidal", {{"slot.length", "4", {}},
                                                   {"path.step", "0.8", {}},
                                                   {"slot.angle", "30", {}},
                                                   {"machine.work_offset", "G55", {}}});
  const std::vector<std::string> d = header_mismatches(other, prog, "p.ngc");
  ASSERT_EQ(d.size(), 2u);  // [machine] is how the program is formatted, not what it cuts
  EXPECT_NE(d[0].find("path.step = 1"), std::string::npos) << d[0];
  EXPECT_NE(d[0].find("the job has 0.8"), std::string::npos) << d[0];
  EXPECT_NE(d[1].find("slot.angle"), std::string::npos) << d[1];
  const Job same = test::wagih_job("trochoidal", {{"slot.length", "4.0", {}}});
  EXPECT_TRUE(header_mismatches(same, prog, "p.ngc").empty());
  const GcodeProgram plain = read_gcode("G0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\n", "hand.ngc");
  EXPECT_TRUE(header_mismatches(other, plain, "hand.ngc").empty());
}

// ---- the interpreter's machine: offsets, home positions, tool table from the job -------------

TEST(GcodeInterp, JobMachineKeysPlaceOffsetsHomeAndToolLengths) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("trochomill-interp-" + std::to_string(static_cast<long>(getpid())));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "tools.tbl") << "T1 P1 Z50 D10 ;end mill\nT2 P2 Z80.5 D6\n";
  const Job job = test::wagih_job(
      "trochoidal",
      {parse_override("machine.origin_g55=[100.0, 0.0, -20.0]"),
       parse_override("machine.g28_position=[0.0, 0.0, 120.0]"),
       parse_override("machine.tool_table=\"" + (dir / "tools.tbl").string() + "\"")});
  EXPECT_EQ(job.machine.tool_table, dir / "tools.tbl");
  const GcodeReadOptions ro = gcode_options(job.machine).read;
  // G54 (the job's work_offset) is not given: machine coordinates are G54's.
  const GcodeProgram p = read_gcode(
      "G21 G90 G0 X0 Y0 Z5\nG55 G0 X1 Y2\nG1 Z-3 F300\nG43 H2\nG28 G91 Z0\nG90 G53 G0 Z0\nM2\n",
      "machine.ngc", ro);
  const auto& seg = p.path.segments();
  ASSERT_EQ(seg.size(), 5u);
  // G55's origin (100, 0, -20): X1 Y2 in G55 is (101, 2) in G54; Z5 stays where it was.
  EXPECT_LE((seg[0].end() - Vec3(101, 2, 5)).norm(), 1e-12);
  EXPECT_LE((seg[1].end() - Vec3(101, 2, -23)).norm(), 1e-12);  // Z-3 in G55
  // G28 Z: the gauge line to machine Z120, the tip a tool length (80.5 mm) below it.
  EXPECT_LE((seg[3].end() - Vec3(101, 2, 120 - 80.5)).norm(), 1e-12);
  // G53 Z0: the gauge line to machine zero.
  EXPECT_LE((seg[4].end() - Vec3(101, 2, -80.5)).norm(), 1e-12);
  EXPECT_TRUE(p.info.warnings.empty()) << p.info.warnings.front();
  std::filesystem::remove_all(dir);
}

TEST(GcodeInterp, AssumptionsAreNamedInWarnings) {
  const GcodeProgram p =
      read_gcode("G0 X0 Y0 Z5\nG56 G0 X1 Y1\nG28\nT3 M6 G43 H3\nG53 G0 Z0\nM2\n", "assume.ngc");
  ASSERT_EQ(p.info.warnings.size(), 3u);
  EXPECT_NE(p.info.warnings[0].find("assume.ngc:2: G56 is used but its offset is not given"),
            std::string::npos)
      << p.info.warnings[0];
  EXPECT_NE(p.info.warnings[1].find("assume.ngc:3: G28: the machine's G28 position is not given"),
            std::string::npos)
      << p.info.warnings[1];
  EXPECT_NE(p.info.warnings[2].find("assume.ngc:5: G53 with G43 H3: tool 3 is not in the tool "
                                    "table"),
            std::string::npos)
      << p.info.warnings[2];
  // The assumptions: G56 as G54, G28 at X0 Y0 5 mm above the work origin.
  EXPECT_LE((p.path.segments()[1].end() - Vec3(0, 0, 5)).norm(), 1e-12);
}

TEST(GcodeInterp, ToolTableErrorsNameLineAndColumn) {
  const auto file = std::filesystem::temp_directory_path() /
                    ("trochomill-tbl-" + std::to_string(static_cast<long>(getpid())) + ".tbl");
  std::ofstream(file) << "T1 P1 Z50\nT2 P2 Zx\n";
  try {
    (void)read_tool_table(file);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string() + ":2:7: 'Z' needs a number after it"),
              std::string::npos)
        << e.what();
  }
  std::filesystem::remove(file);
}

// Loops and calls: the interpreter keeps LinuxCNC's semantics where a reading could differ.
TEST(GcodeInterp, ParametersTakeEffectAfterTheLineAndLocalsBelongToTheCall) {
  const GcodeProgram p = read_gcode(
      "#1 = 2\n#1 = 7 #2 = #1\nG0 X0 Y0 Z0\nG1 X#2 F100\n"
      "o1 sub\n  #1 = 50\n  G1 X#1\no1 endsub\no1 call [3]\nG1 X#1\n",
      "semantics.ngc");
  const auto& seg = p.path.segments();
  ASSERT_EQ(seg.size(), 3u);
  EXPECT_EQ(seg[0].end().x(), 2.0);   // #2 took #1's value before the line
  EXPECT_EQ(seg[1].end().x(), 50.0);  // inside the call
  EXPECT_EQ(seg[2].end().x(), 7.0);   // #1 restored after it
}

// ---- cutter radius compensation (closed forms; tests/ngc compares it with LinuxCNC) ----------

// The outside of a W x H rectangle run clockwise with the tool on the left (G41.1 D = 2r): the
// tool centre runs the rectangle's edges a radius out and a quarter circle of radius r about
// each corner, so the compensated loop is 2 (W + H) + 2 pi r long, whatever the radius.
TEST(GcodeComp, OutsideCornersAreArcsAboutTheProgrammedCorners) {
  for (const double d : {2.0, 8.0, 13.0}) {
    const double r = d / 2, w = 40, h = 30;
    const std::string prog = fmt::format(
        "G21 G17 G90 G94\nG0 X-20 Y-20 Z5\nG1 Z-2 F800\nG41.1 D{}\nG1 X0 Y0\nG1 Y{}\n"
        "G1 X{}\nG1 Y0\nG1 X0\nG1 Y1\nG40\nG1 X-20 Y-20\nM2\n",
        d, h, w);
    const GcodeProgram p = read_gcode(prog, "outside.ngc");
    const auto& seg = p.path.segments();
    // The corner at (0, 0) between the entry and the first edge is concave; then each of the
    // corners (0, 30), (40, 30), (40, 0), (0, 0) is an arc of radius r about it.
    std::vector<std::size_t> arcs;
    for (std::size_t i = 0; i < seg.size(); ++i) {
      if (seg[i].kind() != Segment::Kind::curve) continue;
      arcs.push_back(i);
      EXPECT_TRUE(seg[i].is_circular());
      EXPECT_NEAR(seg[i].axis_a().norm(), r, 1e-12);  // radius r about the corner
      EXPECT_NEAR(std::abs(seg[i].u1() - seg[i].u0()), kPi / 2, 1e-12);
      const Vec3 c = seg[i].center();
      const bool at_corner = (std::abs(c.x()) < 1e-12 || std::abs(c.x() - w) < 1e-12) &&
                             (std::abs(c.y()) < 1e-12 || std::abs(c.y() - h) < 1e-12);
      EXPECT_TRUE(at_corner) << c.transpose();
    }
    ASSERT_EQ(arcs.size(), 4u) << "d = " << d;
    // From the first corner arc to the move after the last one (up to Y1): the top, right
    // and bottom edges, 1 mm up the left one and four quarter circles (1e-9 mm: sums of
    // exact pieces, each to ~1e-12 mm).
    double loop = 0;
    for (std::size_t i = arcs.front(); i <= arcs.back() + 1; ++i) loop += seg[i].length_mm();
    EXPECT_NEAR(loop, w + h + w + 1 + 2 * kPi * r, 1e-9) << "d = " << d;
  }
}

// The inside of the rectangle run counterclockwise with the tool on the left: concave corners,
// each move ends where the two offset edges cross, so the tool centre runs the rectangle
// shrunk by r on every side, corners (r, r), (W - r, r), (W - r, H - r), (r, H - r).
TEST(GcodeComp, InsideCornersEndWhereTheOffsetEdgesCross) {
  const double r = 5, w = 40, h = 30;
  const GcodeProgram p = read_gcode(
      "G21 G17 G90 G94\nG0 X-20 Y20 Z5\nG1 Z-3 F600\nG41.1 D10\nG1 X0 Y0\nG1 X40\n"
      "G1 Y30\nG1 X0\nG1 Y0\nG40\nG1 X-20 Y20\nM2\n",
      "inside.ngc");
  std::vector<Vec3> e;
  for (const Segment& sg : p.path.segments()) e.push_back(sg.end());
  ASSERT_EQ(e.size(), 7u);
  // The entry (from (-20, 20) to (0, 0), offset r to its left, along (r, r) / sqrt 2) makes a
  // concave corner with the first edge too: it ends where its offset line meets y = r, at
  // x = r (sqrt 2 - 1). G40 ends the last edge r beside (0, 0).
  const std::vector<Vec3> want{{r * (std::sqrt(2.0) - 1), r, -3},
                               {w - r, r, -3},
                               {w - r, h - r, -3},
                               {r, h - r, -3},
                               {r, 0, -3},
                               {-20, 20, -3}};
  for (std::size_t i = 0; i < want.size(); ++i) {
    // 1e-12 mm: each corner is one tangent and one cosine of exact angles.
    EXPECT_LE((e[i + 1] - want[i]).norm(), 1e-12) << i << ": " << e[i + 1].transpose();
  }
}

// A circle run inside (G3 with the tool left) is a circle r smaller; outside (G2 with the tool
// left), r larger; a negative diameter turns G41.1 into G42.1.
TEST(GcodeComp, CirclesShrinkOrGrowByTheRadiusAndNegativeDiametersSwapSides) {
  auto last_arc = [](const std::string& body) {
    const GcodeProgram p =
        read_gcode("G21 G17 G90 G94\nG0 X0 Y0 Z0\nF500\n" + body + "M2\n", "circle.ngc");
    const auto& seg = p.path.segments();
    for (auto it = seg.rbegin(); it != seg.rend(); ++it) {
      if (it->kind() == Segment::Kind::curve) return *it;
    }
    throw std::runtime_error("no arc");
  };
  // An entry along the circle's tangent at (20, 0), then a full circle of radius 20 about the
  // origin: the tool runs all of it, a circle of radius 20 -+ 3 (1e-12 mm: exact trig).
  const Segment in = last_arc("G0 X20 Y-20\nG41.1 D6\nG1 Y0\nG3 X20 Y0 I-20 J0\nG40\nG1 X0\n");
  EXPECT_NEAR(in.axis_a().norm(), 17, 1e-12);
  EXPECT_NEAR(in.u1() - in.u0(), 2 * kPi, 1e-12);
  const Segment out = last_arc("G0 X20 Y20\nG41.1 D6\nG1 Y0\nG2 X20 Y0 I-20 J0\nG40\nG1 X0\n");
  EXPECT_NEAR(out.axis_a().norm(), 23, 1e-12);
  EXPECT_NEAR(out.u1() - out.u0(), -2 * kPi, 1e-12);
  const Segment swapped =
      last_arc("G0 X20 Y-20\nG41.1 D-6\nG1 Y0\nG3 X20 Y0 I-20 J0\nG40\nG1 X0\n");
  EXPECT_NEAR(swapped.axis_a().norm(), 23, 1e-12);  // right of a ccw circle: outside
}

TEST(GcodeComp, TheToolTableGivesTheRadiusAndFanucIsWarned) {
  GcodeReadOptions o;
  o.tools[4] = ToolTableEntry{50, 12};
  const std::string body =
      "G21 G17 G90 G94\nG0 X20. Y-20. Z0.\nF500.\nG41 D4\nG1 Y0.\nG3 X20. Y0. I-20. J0.\n"
      "G40\nG1 X0.\nM30\n";
  GcodeProgram p = read_gcode(body, "table.ngc", o);
  ASSERT_EQ(p.path.segments().size(), 3u);
  EXPECT_NEAR(p.path.segments()[1].axis_a().norm(), 14, 1e-12);  // 20 - 12 / 2
  EXPECT_TRUE(p.info.warnings.empty());
  o.dialect = Dialect::fanuc;
  p = read_gcode(body, "table.nc", o);
  ASSERT_EQ(p.path.segments().size(), 3u);
  EXPECT_NEAR(p.path.segments()[1].axis_a().norm(), 14, 1e-12);
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(p.info.warnings[0].find("table.nc:4: G41 read with LinuxCNC's rules"),
            std::string::npos)
      << p.info.warnings[0];
  // A tool the table lacks: LinuxCNC's diameter 0 (the path as programmed), or the job's
  // tool where one is given, each with a warning.
  o = GcodeReadOptions{};
  p = read_gcode(body, "missing.ngc", o);
  ASSERT_EQ(p.path.segments().size(), 3u);
  EXPECT_NEAR(p.path.segments()[1].axis_a().norm(), 20, 1e-12);
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(p.info.warnings[0].find("G41: tool 4 is not in the tool table "
                                    "([machine] tool_table): its diameter is taken as 0 (as "
                                    "LinuxCNC does): the path is not compensated"),
            std::string::npos)
      << p.info.warnings[0];
  o.missing_tool_diameter_mm = 8;
  p = read_gcode(body, "missing.ngc", o);
  ASSERT_EQ(p.path.segments().size(), 3u);
  EXPECT_NEAR(p.path.segments()[1].axis_a().norm(), 16, 1e-12);  // 20 - 8 / 2
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(p.info.warnings[0].find("its diameter is taken as the job's tool's, 8 mm"),
            std::string::npos)
      << p.info.warnings[0];
}

// A polar move fixes X and Y as X and Y words do: a program whose first move is polar has its
// path from there (the moves after it are counted), in closed form.
TEST(GcodeReader, AFirstPolarMoveStartsThePath) {
  const GcodeProgram p =
      read_gcode("G21 G17 G90\nG0 @10 ^45\nG1 F100 Z-1\nG91 G1 @5 ^90\nM2\n", "p.ngc");
  ASSERT_EQ(p.path.segments().size(), 2u);
  const double a = kPi / 4, b = 3 * kPi / 4;  // 45 and 45 + 90 degrees
  const Vec3 end(15 * std::cos(b), 15 * std::sin(b), -1);
  EXPECT_LE((p.path.segments().back().end() - end).norm(), 1e-12);
  const double across = std::hypot(end.x() - 10 * std::cos(a), end.y() - 10 * std::sin(a));
  EXPECT_NEAR(p.path.length_mm(), 1 + across, 1e-9);
}

// A program without motion reads, with a warning (LinuxCNC runs it); what analyses the path
// refuses it, naming the file.
TEST(GcodeReader, AProgramWithoutMotionReadsWithAWarning) {
  const GcodeProgram p = read_gcode("G21 G90 (just a header)\nM3 S1000\nM2\n", "nm.ngc");
  EXPECT_TRUE(p.path.empty());
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_EQ(p.info.warnings[0], "nm.ngc: the program has no motion (no G0/G1/G2/G3 moves)");
}

// The axes besides X Y Z are carried, not drawn: the path is the X Y Z motion (its time along
// X Y Z at F, as LinuxCNC reads F when X Y Z move), the moves of A B C or U V W alone take
// their own time (A B C at F degrees/min, U V W at F mm/min, G93 1/F min), in closed form.
TEST(GcodeReader, OtherAxesAreCarriedWithTheirOwnTime) {
  const GcodeProgram p = read_gcode(
      "G21 G90 G17\nG0 X0 Y0 Z1\nG1 F600 X10 A90\n"  // 10 mm at 600 mm/min: 1 s of path
      "G1 A180\n"                                    // 90 deg at 600 deg/min: 9 s
      "G1 U6 A0\n"                                   // U moves: 6 mm at 600 mm/min: 0.6 s
      "G20 G1 B10\nG21\n"                            // F keeps its speed: 600/25.4 deg/min
      "G93 G1 C30 F2\nG94\n"                         // 1/2 min: 30 s
      "G0 A45\nM2\n",                                // a rapid: no time counted
      "x.ngc");
  ASSERT_EQ(p.path.segments().size(), 1u);
  EXPECT_NEAR(p.path.duration_s(), 1.0, 1e-12);
  EXPECT_EQ(p.info.extra_axes, "ABCU");
  const double b_s = 10 / (600 / 25.4) * 60;
  EXPECT_NEAR(p.info.extra_only_time_s, 9 + 0.6 + b_s + 30, 1e-9);
  EXPECT_EQ(p.info.extra_min[0], 0);
  EXPECT_EQ(p.info.extra_max[0], 180);
  EXPECT_EQ(p.info.extra_max[3], 6);
  ASSERT_FALSE(p.info.warnings.empty());
  EXPECT_NE(p.info.warnings[0].find("x.ngc:3: A: the program uses axes besides X Y Z"),
            std::string::npos)
      << p.info.warnings[0];
}

// Threading runs at the pitch times the spindle speed, not at F: G33 K1.5 at S600 is 900
// mm/min; G33.1 taps in at K S and comes out I times faster to where it started (closed form).
TEST(GcodeReader, ThreadingRunsAtThePitchTimesTheSpindleSpeed) {
  const GcodeProgram p = read_gcode(
      "G21 G90 G17\nG0 X0 Y0 Z5\nS600 M3 F100\nG33 Z-10 K1.5\nG0 Z5\nG33.1 Z-3 K1.25 I2\nM2\n",
      "t.ngc");
  const auto& s = p.path.segments();
  ASSERT_EQ(s.size(), 4u);
  EXPECT_DOUBLE_EQ(s[0].speed_mm_per_min(), 900);
  EXPECT_DOUBLE_EQ(s[2].speed_mm_per_min(), 750);
  EXPECT_DOUBLE_EQ(s[3].speed_mm_per_min(), 1500);
  EXPECT_LE((s[3].end() - Vec3(0, 0, 5)).norm(), 1e-12);  // back where the tap started
  const double t = 15.0 / 900 * 60 + 8.0 / 750 * 60 + 8.0 / 1500 * 60;
  EXPECT_NEAR(p.path.duration_s() - 15.0 / 10000 * 60, t, 1e-9);  // less the rapid up
}

// --trace writes its numbers with append_fixed: character for character fmt's "{:.9f}" (and
// the other widths) on random values over 21 decades, on exact ties (odd multiples of 2^-11,
// 2^-20: ties to even) and on the values beyond its range that go to fmt itself.
TEST(GcodeTrace, FixedNumbersAreFmtsCharacterForCharacter) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> mag(-12.0, 9.0), unit(0.0, 1.0);
  std::vector<double> values{0.0, -0.0, 1e-10, -1e-10,
                             0.5, 1.5,  2.5,   999999999.9999999,
                             1e9, -1e9, 1e15,  std::numeric_limits<double>::infinity()};
  for (int k = 1; k < 4096; k += 2) {
    values.push_back(k / 2048.0);
    values.push_back(-k / 1048576.0);
  }
  for (int k = 0; k < 200000; ++k) {
    const double v = std::pow(10.0, mag(rng)) * (unit(rng) < 0.5 ? -1 : 1);
    values.push_back(v);
  }
  std::size_t checked = 0;
  for (const double v : values) {
    for (const int d : {0, 1, 4, 6, 9}) {
      std::string ours;
      append_fixed(ours, v, d);
      ASSERT_EQ(ours, fmt::format("{:.{}f}", v, d)) << v << " " << d;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000000u);
}

// ---- Fanuc Macro B (hand-computed motion: LinuxCNC does not read these) ----------------------

std::vector<Vec3> ends_of(const GcodeProgram& p) {
  std::vector<Vec3> e;
  for (const Segment& s : p.path.segments()) e.push_back(s.end());
  return e;
}

// The program's segment ends are `want`, one for one (1e-12 mm: hand-computed motion of
// exact numbers).
void expect_ends(const GcodeProgram& p, const std::vector<Vec3>& want) {
  const std::vector<Vec3> got = ends_of(p);
  ASSERT_EQ(got.size(), want.size());
  for (std::size_t k = 0; k < want.size(); ++k) {
    EXPECT_LE((got[k] - want[k]).norm(), 1e-12) << k << ": " << got[k].transpose();
  }
}

TEST(GcodeFanuc, MacroBLoopsJumpsSubprogramsAndMacroCalls) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const std::string prog = R"(%
O1000 (MAIN)
G21 G90 G17 G94
G54 G0 X0. Y0. Z5.
#100 = 0
WHILE [#100 LT 3] DO 1
  G1 X[#100 * 10.] Y0. F500.
  #100 = #100 + 1
END 1
IF [#100 EQ 3] GOTO 50
G1 X999.
N50 G1 Y5.
IF [#1 EQ #0] THEN #2 = 7.
G1 Y#2
M98 P2000 L2
G65 P3000 A1. B2.
G1 X#24 Y#500
#3 = 2 + 3 * 4 AND 6 OR 1
G1 X#3
M30
O2000 (SUB)
G91 G1 X1.
G90
M99
O3000 (MACRO)
G1 X#1 Y#2
#24 = 42.
#500 = 9.
M99
%
)";
  const GcodeProgram p = read_gcode(prog, "fanuc.nc", ro);
  // By hand: the loop draws X0, X10, X20; the jump skips X999; #1 is vacant, so #2 = 7; M98
  // L2 steps X twice by 1; G65 moves to (A, B) = (1, 2) and sets its own #24 (gone at M99)
  // and the common #500; the vacant #24 leaves X out of the next block; 2 + [3 * 4 AND 6] OR 1
  // = 2 + [12 AND 6 = 4] = 6, OR 1 = 7 (Fanuc: AND binds like *, OR like +).
  const std::vector<Vec3> want = {{10, 0, 5}, {20, 0, 5}, {20, 5, 5}, {20, 7, 5}, {21, 7, 5},
                                  {22, 7, 5}, {1, 2, 5},  {1, 9, 5},  {7, 9, 5}};
  expect_ends(p, want);
}

// Fanuc as posts and people write it: WH for WHILE, G65's M and E arguments (#13, #8), the
// spindle-and-coolant M13/M14 (read as M3/M4, said) and a machine maker's M-code (said, not
// refused); LinuxCNC's dialect still refuses M13, as LinuxCNC does. Positions by hand.
TEST(GcodeFanuc, AbbreviationsArgumentsAndMachineMCodes) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const std::string prog = R"(%
O1000
G21 G90 G17 G94
G0 X0. Y0. Z5.
M13 S1000
#1 = 0
WH [#1 LT 2] DO 1
  #1 = #1 + 1
  G1 X#1 F100.
END 1
M10
G65 P2000 E3. M4.
M14
M30
O2000
G1 X#8 Y#13
M99
%
)";
  const GcodeProgram p = read_gcode(prog, "f.nc", ro);
  const std::vector<Vec3> want = {{1, 0, 5}, {2, 0, 5}, {3, 4, 5}};
  expect_ends(p, want);
  const auto warned = [&](const std::string& what) {
    return std::count_if(p.info.warnings.begin(), p.info.warnings.end(),
                         [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_EQ(warned("f.nc:5: M13: read as M3 with coolant on"), 1);
  EXPECT_EQ(warned("f.nc:13: M14: read as M4 with coolant on"), 1);
  EXPECT_EQ(warned("f.nc:11: M10 (the machine maker's M-code on a Fanuc control) was ignored"), 1);
  EXPECT_THROW((void)read_gcode("G0 X0 Y0 Z5\nM13\nM2\n", "l.ngc"), InputError);
  try {
    (void)read_gcode(":\nG0 X1.\n", "c.nc", ro);
    ADD_FAILURE() << "':' without a number read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c.nc:1:1: ':' needs a program number"), std::string::npos)
        << e.what();
  }
}

// G65's argument specification II: A B C once, I J K up to ten times (#4 .. #33), a new set
// where a letter is not after the one before in I J K order, mixed with specification I (the
// later word holds a variable two give). Variables by hand from Fanuc's table.
TEST(GcodeFanuc, MacroArgumentSpecificationTwo) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const std::string call =
      "G65 P2000 A1. I2. J3. K4. I5. K6. J7. I8. D9. I10. J11. K12. I13. I14. I15. I16. I17.";
  const std::string sub = R"(
M30
O2000
G1 X#1 Y#4 F100.
G1 X#5 Y#6
G1 X#7 Y#9
G1 X#11 Y#13
G1 X#10 Y#16
G1 X#17 Y#18
G1 X#19 Y#22
G1 X#25 Y#28
G1 X#31 Y[#8 + #12 + #14 + #15 + #20 + #21 + #23 + #24 + #26 + #27 + #29 + #30 + #32 + #33 + 1.]
M99
%
)";
  const std::string head = "%\nO1000\nG21 G90 G17 G94\nG0 X0. Y0. Z5.\n";
  const GcodeProgram p = read_gcode(head + call + sub, "spec2.nc", ro);
  // I2 J3 K4: set 1 (#4 #5 #6); I5 K6: set 2 (#7, #9); J7, not after K: set 3's J (#11); I8:
  // set 4 (#13); D9 is #7 (specification I), the later word; I10 J11 K12: set 5 (#16 #17
  // #18); I13 .. I17: sets 6 .. 10 (#19 #22 #25 #28 #31). #10 is vacant (X left out); the
  // rest of #4 .. #33 are vacant (0 in the sum).
  const std::vector<Vec3> want = {{1, 2, 5},   {3, 4, 5},   {9, 6, 5},   {7, 8, 5}, {7, 10, 5},
                                  {11, 12, 5}, {13, 14, 5}, {15, 16, 5}, {17, 1, 5}};
  expect_ends(p, want);
  // An eleventh set is too many; an argument before G65 is not one.
  for (const auto& [text, what] :
       {std::pair{call + " I18.", "at most ten sets of I J K"},
        std::pair{"X1. " + call, "X before G65: its arguments come after it"}}) {
    try {
      (void)read_gcode(head + text + sub, "bad.nc", ro);
      ADD_FAILURE() << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
  }
}

// IF [..] THEN #i = ...: the setting, and an alarm #3000 = n, only where the condition holds (a
// macro guarding its arguments, as Haas's and Fanuc's serial-number macros do).
TEST(GcodeFanuc, IfThenSetsOnlyWhereTheConditionHolds) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const GcodeProgram p = read_gcode(
      "G21 G90 G94\nG0 X0. Y0. Z5.\n#100 = 1.\nIF [1 EQ 2] THEN #100 = 9.\n"
      "IF [1 EQ 2] THEN #3000 = 9 (NOT RAISED)\nG1 X#100 F100.\nIF [1 EQ 1] THEN #101 = 3.\n"
      "G1 Y#101\nM30\n",
      "if.nc", ro);
  expect_ends(p, {{1, 0, 5}, {1, 3, 5}});
  try {
    (void)read_gcode("G0 X0. Y0. Z5.\nIF [1 EQ 1] THEN #3000 = 7 (RAISED)\nM30\n", "a.nc", ro);
    ADD_FAILURE() << "the alarm was not raised";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("a.nc:2:18: the program raised alarm #3000 = 7 (RAISED)"),
              std::string::npos)
        << e.what();
  }
}

// Fanuc's polar coordinate command G16 .. G15: X the distance from the program's zero, Y the
// angle (degrees; in G91 added to the current point's), the one left out the current point's.
// LinuxCNC has no G15/G16 (it refuses them; its polar words are @ and ^). Ends by hand.
TEST(GcodeFanuc, PolarCoordinatesG16) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const std::string prog =
      "G21 G90 G17 G94\nG0 X0. Y0. Z5.\nG16\nG1 X10. Y90. F100.\nY180.\nG91 Y-90.\nG90 X20.\n"
      "G15\nG1 X5. Y5.\nM30\n";
  const GcodeProgram p = read_gcode(prog, "polar.nc", ro);
  expect_ends(p, {{0, 10, 5}, {-10, 0, 5}, {0, 10, 5}, {0, 20, 5}, {5, 5, 5}});
  for (const char* code : {"G15", "G16"}) {
    try {
      (void)read_gcode(fmt::format("G0 X0 Y0 Z5\n{}\nM2\n", code), "l.ngc");
      ADD_FAILURE() << code << " read by the linuxcnc dialect";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(fmt::format("unsupported G-code {}", code)),
                std::string::npos)
          << e.what();
    }
  }
  EXPECT_THROW((void)read_gcode("G0 X0. Y0. Z5.\nG16 G91 G1 X10. Y10. F100.\nM30\n", "r.nc", ro),
               InputError);  // an incremental radius: the current point as the centre
}

// Fanuc's G10 data setting and extra systems: L2 P1 .. P6 (G91: added), L2 P0 the external
// offset (every system moves), L20 P the G54.1 P systems; L10 .. L13 the H and D registers
// G43 and G41 read. Positions by hand (the output frame is G54 with its origin at 0).
TEST(GcodeFanuc, DataSettingAndExtraSystems) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const std::string prog =
      "G21 G90 G17 G94\nG10 L2 P2 X100. Y0. Z0.\nG10 L20 P3 X200. Y10. Z0.\nG0 X0. Y0. Z5.\n"
      "G55 X0. Y0.\nG54.1 P3 X1. Y1.\nG10 L2 P2 G91 X5.\nG90 G55 X0. Y0.\nG10 L2 P0 X1000.\n"
      "G0 X0. Y0.\n"
      // H3: 20 - 0.5; G53 Z0 puts the spindle's gauge line at machine Z 0, the tip 19.5 below.
      "G54 G10 L10 P3 R20.\nG10 L11 P3 R-0.5\nG43 H3 Z50.\nG53 Z0.\nG49 G0 Z5.\n"
      // D5: a radius of 3 (geometry 3.2, wear -0.2); left of +X is +Y.
      "G10 L12 P5 R3.2\nG10 L13 P5 R-0.2\nG0 X-10. Y0.\nG41 D5 G1 X0. Y0. F100.\nX20.\n"
      "G40 X30.\nM30\n";
  const GcodeProgram p = read_gcode(prog, "data.nc", ro);
  const std::vector<Vec3> e = ends_of(p);
  ASSERT_GE(e.size(), 9U);
  EXPECT_LE((e[0] - Vec3(100, 0, 5)).norm(), 1e-12);   // G55 X0 Y0
  EXPECT_LE((e[1] - Vec3(201, 11, 5)).norm(), 1e-12);  // G54.1 P3 X1 Y1
  EXPECT_LE((e[2] - Vec3(105, 0, 5)).norm(), 1e-12);   // G55 moved by 5 in G91
  EXPECT_LE((e[3] - Vec3(1105, 0, 5)).norm(), 1e-12);  // and by the external 1000
  // Back in G54 (with the external offset): X0 Y0 is at 1000; the G53 Z0 move of the tip.
  bool found_z = false, found_comp = false;
  for (const Vec3& v : e) {
    found_z = found_z || std::abs(v.z() - (-19.5 - 0.0)) <= 1e-12;
    found_comp = found_comp || (std::abs(v.x() - 1020) <= 1e-12 && std::abs(v.y() - 3) <= 1e-12);
  }
  EXPECT_TRUE(found_z) << "G53 Z0 with H3 of 19.5 mm";
  EXPECT_TRUE(found_comp) << "X20 compensated 3 mm to the left";
  EXPECT_EQ(
      std::count_if(p.info.warnings.begin(), p.info.warnings.end(),
                    [](const std::string& w) { return w.find("assumed") != std::string::npos; }),
      0);
  // An offset the program writes itself is its own: #7001 (G54.1 P1's X) = 3.
  const GcodeProgram own =
      read_gcode("G21 G90 G94\nG0 X0. Y0. Z5.\n#7001 = 3.\nG54.1 P1 X0. Y0.\nM30\n", "own.nc", ro);
  expect_ends(own, {{3, 0, 5}});
  EXPECT_TRUE(own.info.warnings.empty());
  // #4001 .. #4130 are the control's: read only.
  EXPECT_THROW((void)read_gcode("#4001 = 5.\nM30\n", "ro.nc", ro), InputError);
  // G53 moves at rapid whatever the mode (the G1 before it).
  std::vector<GcodeMove::Kind> kinds;
  GcodeReadOptions traced = ro;
  traced.trace = [&](const GcodeMove& m) { kinds.push_back(m.kind); };
  (void)read_gcode("G21 G90 G94\nG0 X0. Y0. Z5.\nG1 X1. F100.\nG53 Z0.\nM30\n", "g53.nc", traced);
  ASSERT_EQ(kinds.size(), 3U);  // the approach, the G1, the G53
  EXPECT_EQ(kinds[1], GcodeMove::Kind::feed);
  EXPECT_EQ(kinds[2], GcodeMove::Kind::rapid);
  // What Fanuc's G10 does not have, and Haas's codes, are refused by name.
  EXPECT_THROW((void)read_gcode("G10 L3 P1 R1.\nM30\n", "l3.nc", ro), InputError);
  EXPECT_THROW((void)read_gcode("G0 X0. Y0. Z5.\nG154 P2 X1.\nM30\n", "g154.nc", ro), InputError);
}

// Haas: G154 P1 .. P99 and G110 .. G129 (its first 20), G10 L20 into them, G10 L2 P0 the G52
// shift, G10 L12 a diameter; G187 and G103 (smoothing, look-ahead) leave the path as it is.
TEST(GcodeHaas, ExtraSystemsG52AndMachineSettings) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::haas;
  const std::string prog =
      "G21 G90 G17 G94\nG10 L20 P2 X50. Y0. Z0.\nG0 X0. Y0. Z5.\nG111 X0. Y0.\nG154 P2 X1.\n"
      "G10 L2 P0 X3.\nG1 X0. F100.\nG187 P1 E0.01\nG103 P4\nG54 X0. Y0.\n"
      "G10 L12 P5 R6.\nG0 X-10. Y0.\nG41 D5 G1 X0. Y0. F100.\nX20.\nG40 X30.\nM30\n";
  const GcodeProgram p = read_gcode(prog, "haas.nc", ro);
  const std::vector<Vec3> e = ends_of(p);
  ASSERT_GE(e.size(), 5U);
  EXPECT_LE((e[0] - Vec3(50, 0, 5)).norm(), 1e-12);  // G111 = G154 P2
  EXPECT_LE((e[1] - Vec3(51, 0, 5)).norm(), 1e-12);
  EXPECT_LE((e[2] - Vec3(53, 0, 5)).norm(), 1e-12);  // G52 X3
  EXPECT_LE((e[3] - Vec3(3, 0, 5)).norm(), 1e-12);   // G54 with G52 X3
  bool found_comp = false;
  for (const Vec3& v : e) {
    found_comp = found_comp || (std::abs(v.x() - 23) <= 1e-12 && std::abs(v.y() - 3) <= 1e-12);
  }
  EXPECT_TRUE(found_comp) << "a 6 mm diameter: 3 mm to the left";
  // Haas's programs have five digits: M98 P10001 calls O10001 (Fanuc's P would be 1 repeat of
  // O0001).
  const GcodeProgram five = read_gcode(
      "%\nO00001\nG21 G90 G94\nG0 X0. Y0. Z5.\nM98 P10001\nM30\n%\nO10001\nG0 X7. Y7.\nM99\n",
      "five.nc", ro);
  expect_ends(five, {{7, 7, 5}});
  // G154 P1 .. P99's offsets at #14001 + 20 (P - 1), P1 .. P20's also at #7001 + 20 (P - 1).
  const GcodeProgram vars = read_gcode(
      "G21 G90 G17 G94\n#14421 = 10.\n#14422 = 4.\n#14001 = 2.\n#100 = #7001\n"
      "G0 X0. Y0. Z5.\nG154 P22 X0. Y0.\nG154 P1 X#100 Y0.\nM30\n",
      "vars.nc", ro);
  expect_ends(vars, {{10, 4, 5}, {4, 0, 5}});  // P22 at (10, 4); P1 at X2, X#100 = 2 more
  EXPECT_THROW((void)read_gcode("#15981 = 1.\nM30\n", "p100.nc", ro), InputError);  // no P100
  // Fanuc's dialect has no G187; LinuxCNC's neither.
  GcodeReadOptions fanuc;
  fanuc.dialect = Dialect::fanuc;
  EXPECT_THROW((void)read_gcode("G187 P1\nM30\n", "f.nc", fanuc), InputError);
}

// Mach3: LinuxCNC's language with Fanuc-style subprograms (O<n>, M98 P L, M99), G15/G16
// polar coordinates, G59 P7 .. fixtures and G31 (straight probe, LinuxCNC's G38.2).
TEST(GcodeMach3, SubprogramsPolarFixturesAndProbe) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::mach3;
  const std::string prog =
      "G21 G90 G17 G94\nG0 X0 Y0 Z5\nM98 P100 L2\nG16\nG1 X10 Y90 F100\nG15\nG59 P7 X0 Y0\n"
      "G31 X5 F50\nG59 P1 X0 Y0\nM30\nO100\nG91 G1 X1 F100\nG90\nM99\n";
  const GcodeProgram p = read_gcode(prog, "mach3.tap", ro);
  // G59 P1 is G54: back to X0 Y0.
  expect_ends(p, {{1, 0, 5}, {2, 0, 5}, {0, 10, 5}, {0, 0, 5}, {5, 0, 5}, {0, 0, 5}});
  const auto warned = [&](const std::string& what) {
    return std::any_of(p.info.warnings.begin(), p.info.warnings.end(),
                       [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(warned("G59 P7 is used but its offset is not given"));
  EXPECT_TRUE(warned("read as a feed move to its end point"));
  EXPECT_THROW((void)read_gcode("G28.1 X0\nM30\n", "r.tap", ro), InputError);
}

// Programs by others for Haas and Mach3 (tests/ngc/dialects, README.md names each one's
// source and licence), read with their control's dialect.
TEST(GcodeDialects, HaasAndMach3ProgramsByOthers) {
  const auto dir = test::source_dir() / "tests/ngc/dialects";
  GcodeReadOptions haas;
  haas.dialect = Dialect::haas;
  // A Haas serial-number macro (G65 arguments, IF without THEN and THEN M97, M97 local
  // subprograms, G103, G51 scaling and G68 rotation, G50 G69 in one block, #4109 the modal
  // F), called by the file beside it with Z-0.005 (inch): its engraving runs at that depth
  // and rises to R0.1 above the top between characters.
  const GcodeProgram sn = read_gcode_file(dir / "sn_call.nc", haas);
  double deepest = 0;
  for (const Segment& seg : sn.path.segments()) deepest = std::min(deepest, seg.end().z());
  EXPECT_NEAR(deepest, -0.005 * 25.4, 1e-9);  // exact numbers, one scaling by P (1 here)
  // A Haas part program: facing, contours and drilling, read whole.
  const GcodeProgram step =
      read_gcode_file(dir / "haas__cadekiely__stepblock-steps-o78241.nc", haas);
  EXPECT_GT(step.path.feed_length_mm(), 0.0);
  // Another, whose G82 leaves out R and P (Haas: the initial level, no dwell) and which
  // engraves text with G47: refused by name where it starts.
  try {
    (void)read_gcode_file(dir / "haas__cadekiely__4x3_block-o78244.nc", haas);
    ADD_FAILURE() << "G47 read";
  } catch (const InputError& e) {
    EXPECT_NE(
        std::string(e.what()).find("o78244.nc:140:6: G47 (Haas's text engraving) is not read"),
        std::string::npos)
        << e.what();
  }
  // pcb2gcode's Mach3 output with its probing: M40/M41 (the Mach3 profile's macros) said and
  // ignored, G31 read as LinuxCNC's G38.2, M98 P8 L6 and #[expressions] as Mach3 runs them.
  GcodeReadOptions mach3;
  mach3.dialect = Dialect::mach3;
  const GcodeProgram front =
      read_gcode_file(dir / "mach3__pcb2gcode__example_board_al_mach3_front.ngc", mach3);
  const auto said = [&](const std::string& what) {
    return std::any_of(front.info.warnings.begin(), front.info.warnings.end(),
                       [&](const std::string& w) { return w.find(what) != std::string::npos; });
  };
  EXPECT_TRUE(said("M40 (a macro of the Mach3 profile) was ignored"));
  EXPECT_TRUE(said("read as a feed move to its end point"));
  EXPECT_GT(front.path.feed_length_mm(), 0.0);
}

// G96 D S: the spindle speed of a feed-per-revolution move is S m/min over the circumference
// at its start's X (LinuxCNC's motion), at most D; G97 S back to rpm. Feeds by hand.
TEST(GcodeSpindle, ConstantSurfaceSpeedG96) {
  std::vector<double> feeds;
  GcodeReadOptions ro;
  ro.trace = [&](const GcodeMove& m) {
    if (m.kind != GcodeMove::Kind::rapid) feeds.push_back(m.feed_mm_per_min);
  };
  const GcodeProgram p = read_gcode(
      "G21 G90 G17 G95\nG0 X10 Y0 Z0\nS500 M3\nG96 D2000 S100\nG1 X20 F0.1\nG1 X1\nG1 X2\n"
      "G97 S1000\nG1 X30\nM2\n",
      "css.ngc", ro);
  ASSERT_EQ(feeds.size(), 4U);
  EXPECT_NEAR(feeds[0], 0.1 * 100 * 1000 / (2 * kPi * 10), 1e-9);  // 1591.5 rpm at X10
  EXPECT_NEAR(feeds[1], 0.1 * 100 * 1000 / (2 * kPi * 20), 1e-9);  // 795.8 rpm at X20
  EXPECT_NEAR(feeds[2], 0.1 * 2000, 1e-9);  // 15,915 rpm at X1: at most D2000
  EXPECT_NEAR(feeds[3], 0.1 * 1000, 1e-9);  // G97: S1000
  // Without S, G96 is an error, as in LinuxCNC.
  try {
    (void)read_gcode("G96 D2000\nM2\n", "s.ngc");
    ADD_FAILURE() << "G96 without S";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("S word missing with G96"), std::string::npos) << e.what();
  }
  (void)p;
}

// G88 stops for the operator to retract by hand: the retraction is modelled as a rapid to the
// clear plane and named (LinuxCNC's canon has no move there; docs/gcode.md).
TEST(GcodeCycles, G88RetractsAsTheOperatorWouldAndSaysSo) {
  const GcodeProgram p = read_gcode(
      "G21 G17 G90 G94\nG0 X0 Y0 Z10\nS500 M3 F200\nG98 G88 X5 Y5 Z-4 R2 P1\nG80\nM2\n", "g88.ngc");
  const std::vector<Vec3> want{{5, 5, 10}, {5, 5, 2}, {5, 5, -4}, {5, 5, 10}};
  ASSERT_EQ(p.path.segments().size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    EXPECT_EQ(p.path.segments()[i].end(), want[i]) << i;  // words copied: exact
  }
  EXPECT_EQ(p.path.segments()[2].motion(), Motion::feed);
  EXPECT_EQ(p.path.segments()[3].motion(), Motion::rapid);
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(p.info.warnings[0].find("g88.ngc:4: G88 stops the program"), std::string::npos)
      << p.info.warnings[0];
}

// Fanuc's fine boring G76 and back boring G87 (Q shifts off the wall, along +X by the
// parameter's default) and tapping G84 (out to R at the feed), as Fanuc's manual describes
// them; LinuxCNC does not read these.
TEST(GcodeFanuc, BoringAndTappingCyclesMoveAsTheManualDescribes) {
  GcodeReadOptions o;
  o.dialect = Dialect::fanuc;
  const GcodeProgram p = read_gcode(
      "G21 G17 G90 G94\nG0 X0. Y0. Z10.\nS500 M3 F200.\nG98 G76 X5. Y5. Z-4. R2. Q0.5 P100\n"
      "G80\nG99 G84 X10. Y0. Z-6. R1.\nG80\nG0 Z10.\nG98 G87 X20. Y0. Z-3. R-10. Q1.\nG80\n"
      "M30\n",
      "bore.nc", o);
  const std::vector<std::pair<Vec3, Motion>> want{
      // G76: to the hole, down to R, bore, shift, out, shift back.
      {{5, 5, 10}, Motion::rapid},
      {{5, 5, 2}, Motion::rapid},
      {{5, 5, -4}, Motion::feed},
      {{5.5, 5, -4}, Motion::rapid},
      {{5.5, 5, 10}, Motion::rapid},
      {{5, 5, 10}, Motion::rapid},
      // G84 in G99: in and out to R at the feed.
      {{10, 0, 10}, Motion::rapid},
      {{10, 0, 1}, Motion::rapid},
      {{10, 0, -6}, Motion::feed},
      {{10, 0, 1}, Motion::feed},
      {{10, 0, 10}, Motion::rapid},  // G0 Z10
      // G87: shifted down through the hole to R (the bore's bottom), back on the axis, bore up
      // to Z at the feed, shifted, out to the initial level, back on the axis.
      {{20, 0, 10}, Motion::rapid},
      {{21, 0, 10}, Motion::rapid},
      {{21, 0, -10}, Motion::rapid},
      {{20, 0, -10}, Motion::rapid},
      {{20, 0, -3}, Motion::feed},
      {{21, 0, -3}, Motion::rapid},
      {{21, 0, 10}, Motion::rapid},
      {{20, 0, 10}, Motion::rapid}};
  const auto& seg = p.path.segments();
  ASSERT_EQ(seg.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i) {
    // 1e-12 mm: sums of the words (5 + 0.5) in double.
    EXPECT_LE((seg[i].end() - want[i].first).norm(), 1e-12)
        << i << ": " << seg[i].end().transpose();
    EXPECT_EQ(seg[i].motion(), want[i].second) << i;
  }
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(
      p.info.warnings[0].find("bore.nc:4: G76: the shift Q off the bore's wall goes along +X"),
      std::string::npos)
      << p.info.warnings[0];
}

TEST(GcodeFanuc, NumbersWithoutDecimalPointAreNamedInAWarning) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const GcodeProgram p = read_gcode("G21 G90 G0 X0 Y0 Z5\nG1 X100 F200\n", "nodot.nc", ro);
  EXPECT_EQ(p.path.segments().back().end().x(), 100.0);
  ASSERT_EQ(p.info.warnings.size(), 1u);
  EXPECT_NE(p.info.warnings[0].find("nodot.nc:1: X0 has no decimal point: taken as 0 mm"),
            std::string::npos)
      << p.info.warnings[0];
}

TEST(GcodeFanuc, MalformedMacrosNameTheLine) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  ro.max_blocks = 10'000;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"G0 X0. Y0. Z0.\nEND 1\n", "f.nc:2:1: END 1 without its WHILE .. DO 1"},
      {"G0 X0. Y0. Z0.\nWHILE [1 LT 0] DO 2\nG1 X1.\n", "f.nc:2:1: WHILE .. DO 2 has no END 2"},
      {"G0 X0. Y0. Z0.\nGOTO 70\n", "f.nc:2:1: GOTO 70: no block N70 in f.nc"},
      {"G0 X0. Y0. Z0.\nM98 P9\n", "f.nc:2:5: program O0009 is not in the program"},
      {"G0 X0. Y0. Z0.\n#3000 = 12 (TOOL BROKEN)\n",
       "f.nc:2:1: the program raised alarm #3000 = 12 (TOOL BROKEN)"},
      {"G0 X0. Y0. Z0.\n#0 = 1\n", "f.nc:2:1: #0 is always vacant: it cannot be set"},
      {"G0 X0. Y0. Z0.\nIF [1] X1.\n", "f.nc:2:8: IF [condition] is followed by GOTO n or THEN"},
      {"G0 X0. Y0. Z0.\nN10 G1 X1. F100.\nGOTO 10\n", "stopped after 10000 blocks"},
  };
  for (const auto& [code, want] : cases) {
    try {
      (void)read_gcode(code, "f.nc", ro);
      ADD_FAILURE() << "no error for:\n" << code;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(want), std::string::npos)
          << "want: " << want << "\ngot:  " << e.what();
    }
  }
  // M98 in the Grbl dialect says where it belongs (LinuxCNC 2.9 reads it).
  try {
    GcodeReadOptions grbl;
    grbl.dialect = Dialect::grbl;
    (void)read_gcode("G0 X0 Y0 Z0\nM98 P100\n", "l.ngc", grbl);
    ADD_FAILURE() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("l.ngc:2:1: M98 is the subprogram call of Fanuc, "
                                         "LinuxCNC, Haas and Mach3, not of the grbl dialect"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// Fanuc's G68 rotation and G51 scaling (hand-computed: LinuxCNC has neither): a quarter turn
// about the origin takes X10 Y0 to (0, 10) and X10 Y5 to (-5, 10); a factor 2 takes X5 Y1 to
// (10, 2); a mirror of X (I-1.) turns the clockwise half circle from (0, 0) to (10, 0) into a
// counter-clockwise one to (-10, 0) through (-5, 5); G69 and G50 leave the tool where it is.
// LinuxCNC's dialect refuses them.
TEST(GcodeFanuc, RotationAndScalingMoveTheProgram) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const GcodeProgram p = read_gcode(
      "%\nO1000\nG21 G90 G17\nG0 X0. Y0. Z1.\nG1 Z-1. F600.\nG68 X0. Y0. R90.\nG1 X10. Y0.\n"
      "G1 X10. Y5.\nG69\nG1 X0. Y0.\nG51 X0. Y0. P2.\nG1 X5. Y1.\nG50\nG1 X0. Y0.\n"
      "G51 X0. Y0. I-1. J1. K1.\nG2 X10. Y0. I5. J0.\nG50\nG1 X0. Y0.\nM30\n%\n",
      "turn.nc", ro);
  const std::vector<Vec3> want{{0, 0, -1},  {0, 10, -1}, {-5, 10, -1}, {0, 0, -1},
                               {10, 2, -1}, {0, 0, -1},  {-10, 0, -1}, {0, 0, -1}};
  ASSERT_NO_FATAL_FAILURE(expect_ends(p, want));
  const auto& s = p.path.segments();
  EXPECT_LE((s[6].point_at(0.5 * s[6].length_mm()) - Vec3(-5, 5, -1)).norm(), 1e-12);
  EXPECT_NEAR(s[6].length_mm(), 5 * kPi, 1e-12);
  GcodeReadOptions lc;
  try {
    (void)read_gcode("G0 X0 Y0 Z1\nG68 X0 Y0 R90\nM2\n", "turn.ngc", lc);
    ADD_FAILURE() << "LinuxCNC's dialect read G68";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("turn.ngc:2:1: unsupported G-code G68"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace trochomill

namespace trochomill {
namespace {

// Haas's M97 P<block> L<times>: a subprogram at block N100 of the program itself, run twice
// (incremental moves: (5, 0), (5, 5), then (10, 5), (10, 10)), back after M99 to the block
// after the call; a block number the program lacks is named. LinuxCNC's dialect refuses M97.
TEST(GcodeFanuc, HaasLocalSubprogramCalls) {
  GcodeReadOptions ro;
  ro.dialect = Dialect::fanuc;
  const GcodeProgram p = read_gcode(
      "%\nO1000\nG21 G90 G17\nG0 X0. Y0. Z1.\nG1 Z-1. F600.\nM97 P100 L2\nG1 X0. Y0.\nM30\n"
      "N100 G91 G1 X5.\nY5.\nG90\nM99\n%\n",
      "haas.nc", ro);
  const std::vector<Vec3> want{{0, 0, -1},  {5, 0, -1},   {5, 5, -1},
                               {10, 5, -1}, {10, 10, -1}, {0, 0, -1}};
  expect_ends(p, want);
  try {
    (void)read_gcode("G0 X0. Y0. Z1.\nM97 P200\nM30\n", "haas.nc", ro);
    ADD_FAILURE() << "a missing block was called";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("M97 P 200: no block N200 in haas.nc"), std::string::npos)
        << e.what();
  }
  EXPECT_THROW((void)read_gcode("G0 X0 Y0 Z1\nM97 P100\nM2\n", "lc.ngc"), InputError);
}

// A G5 cubic with a control point 1e4 mm off: its nearly straight stretches fit arcs of radius
// up to 2e8 mm, whose starts recomputed from the centre are 1e-8 mm off the tool (refused as
// "an arc that starts where the tool is not" before). Its length by Simpson's rule on 2e5
// intervals of the Bezier's speed (converged to 1e-10 mm): 12567.708495 mm; the arcs lie within
// the spline tolerance (0.001 mm) of the curve, their length within 0.01 mm of it.
TEST(Gcode, AFarControlPointSplineIsRead) {
  const auto p =
      read_gcode("G0 X0 Y0 Z2\nG1 Z-1 F600\nG5 X10 Y0 I2 J3 P-10000 Q10000\nM2\n", "g5.ngc");
  EXPECT_NEAR(p.path.length_mm() - 3, 12567.708495, 0.01);
  EXPECT_LT((p.path.segments().back().end() - Vec3(10, 0, -1)).norm(), 1e-9);
}

// A tool number past an int was undefined behaviour when M6 recorded the change (a fuzzer's
// finding); T and M61's Q are now bounded like the tool table's T, with the column named.
TEST(Gcode, ToolNumbersAreBounded) {
  for (const char* text : {"T1000000000000 M6\nM2\n", "T99999999999 M6\nM2\n", "M61 Q-1\nM2\n",
                           "M61 Q99999999999\nM2\n", "M61 Q1.5\nM2\n"}) {
    try {
      (void)read_gcode(text, "t.ngc");
      ADD_FAILURE() << "accepted " << text;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("0 .. 1e6"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("t.ngc:1:"), std::string::npos) << e.what();
    }
  }
  // M61's Q is a tool number, not a length: not scaled by G20, not bounded as one.
  EXPECT_NO_THROW((void)read_gcode("G20\nM61 Q50000\nG0 X0 Y0 Z1\nM2\n", "q.ngc"));
  const auto ok = read_gcode("T1000000 M6\nG0 X0 Y0 Z1\nM2\n", "t.ngc");
  ASSERT_EQ(ok.info.tool_changes.size(), 1u);
  EXPECT_EQ(ok.info.tool_changes[0].first, 1000000);
}

}  // namespace
}  // namespace trochomill
