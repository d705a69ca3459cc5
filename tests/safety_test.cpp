// Programs safe to run on a machine: the set-up blocks of every dialect (work offset, tool
// length offset), the approach (Z alone to the clearance plane, then X Y), no rapid that moves
// X or Y below the clearance plane, the slot placed anywhere in the workpiece by an exact
// rigid motion; and LinuxCNC's own interpreter (rs274, a real peer) reading every family,
// entry and placement with the same verdict.
#include <fmt/format.h>
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "test_util.hpp"
#include "trochomill/error.hpp"
#include "trochomill/gcode.hpp"

namespace trochomill {
namespace {

std::vector<Override> family_overrides(const std::string& type, const std::string& entry) {
  std::vector<Override> ov = {parse_override("slot.length=6"),
                              parse_override("path.entry=" + entry)};
  if (type == "elliptical" || type == "linear-elliptical") {
    ov.push_back(parse_override("path.aspect_ratio=0.8"));
  }
  if (type == "linear-elliptical") ov.push_back(parse_override("path.linear_distance=1"));
  return ov;
}

std::string write(const Job& job, Dialect d) {
  GcodeWriteOptions o;
  o.dialect = d;
  return write_gcode(job, plan_path(job).path, o);
}

// The lines of a program up to its first motion block after the set-up.
std::vector<std::string> lines_of(const std::string& code) {
  std::vector<std::string> out;
  std::istringstream in(code);
  for (std::string l; std::getline(in, l);) out.push_back(l);
  return out;
}

TEST(Safety, SetUpAndApproachFollowTheDialect) {
  const Job job = test::wagih_job("trochoidal", {parse_override("tool.tool_number=7")});
  struct Case {
    Dialect dialect;
    std::vector<std::string> in_order;  // lines that must appear, in this order
  };
  const std::vector<Case> cases = {
      {Dialect::linuxcnc,
       {"G21 G17 G90 G94 G40 G49 G80", "G54", "T7 M6", "S2000 M3", "G0 G43 H7 Z5", "G0 X5 Y"}},
      {Dialect::fanuc,
       {"O1000", "G21 G17 G90 G94 G40 G49 G80", "G54", "T7 M6", "G0 G43 H7 Z5.", "G0 X5. Y"}},
      {Dialect::sinumerik, {"G71 G17 G90 G94 G40", "G54", "T7 D1", "M6", "G0 Z5", "G0 X5 Y"}},
      {Dialect::grbl, {"G21 G17 G90 G94", "G54", "S2000 M3", "G0 Z5", "G0 X5 Y"}},
      {Dialect::haas,
       {"O1000", "G21 G17 G90 G94 G40 G49 G80", "G54", "T7 M6", "G0 G43 H7 Z5.", "G0 X5. Y"}},
      {Dialect::mach3,
       {"G21 G17 G90 G94 G40 G49 G80", "G54", "T7 M6", "S2000 M3", "G0 G43 H7 Z5", "G0 X5 Y"}},
  };
  for (const Case& c : cases) {
    const std::vector<std::string> lines = lines_of(write(job, c.dialect));
    std::size_t at = 0;
    for (const std::string& want : c.in_order) {
      while (at < lines.size() && lines[at].rfind(want, 0) != 0) ++at;
      ASSERT_LT(at, lines.size()) << to_string(c.dialect) << ": no '" << want << "' in order";
    }
    // The XY approach block carries no Z: the Z move came first, alone.
    EXPECT_EQ(lines[at].find('Z'), std::string::npos) << lines[at];
  }
  // Every Fanuc number carries its decimal point (a Fanuc set to least-increment input reads
  // "Z5" as 5 um): read back as Fanuc, no number is without one.
  GcodeReadOptions fanuc;
  fanuc.dialect = Dialect::fanuc;
  const GcodeProgram back = read_gcode(write(job, Dialect::fanuc), "f.nc", fanuc);
  EXPECT_TRUE(back.info.warnings.empty()) << back.info.warnings.front();
  // The length offset register and the work offset are the job's.
  const Job other = test::wagih_job("trochoidal", {parse_override("machine.length_offset=27"),
                                                   parse_override("machine.work_offset=G57"),
                                                   parse_override("tool.tool_number=3")});
  const std::string lc = write(other, Dialect::linuxcnc);
  EXPECT_NE(lc.find("\nG57\n"), std::string::npos);
  EXPECT_NE(lc.find("\nT3 M6\n"), std::string::npos);
  EXPECT_NE(lc.find("\nG0 G43 H27 Z5\n"), std::string::npos);
}

TEST(Safety, JobRulesForTheSetUp) {
  // Sinumerik's settable offsets stop at G57; H0 would apply no length offset.
  try {
    (void)test::wagih_job("trochoidal", {parse_override("machine.dialect=sinumerik"),
                                         parse_override("machine.work_offset=G59")});
    FAIL() << "G59 accepted for sinumerik";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("G54 .. G57"), std::string::npos) << e.what();
  }
  try {
    (void)test::wagih_job("trochoidal", {parse_override("tool.tool_number=0")});
    FAIL() << "H0 accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("G43 H0"), std::string::npos) << e.what();
  }
  // Grbl has no tool table: T0 is fine there.
  EXPECT_NO_THROW((void)test::wagih_job("trochoidal", {parse_override("machine.dialect=grbl"),
                                                       parse_override("tool.tool_number=0")}));
}

// Every rapid of every written program: X or Y change only at or above the clearance plane.
void expect_safe_rapids(const GcodeProgram& prog, double clear_z, const std::string& label) {
  for (const Segment& s : prog.path.segments()) {
    if (s.motion() != Motion::rapid) continue;
    const Vec3 a = s.start(), b = s.end();
    if (std::hypot(b.x() - a.x(), b.y() - a.y()) > 1e-9) {
      // 1e-4 mm: the program's resolution.
      EXPECT_GE(std::min(a.z(), b.z()), clear_z - 1e-4) << label;
    }
  }
}

TEST(Safety, NoRapidMovesXYBelowTheClearancePlane) {
  for (const std::string type :
       {"trochoidal", "circular", "elliptical", "linear-elliptical", "linear"}) {
    for (const std::string entry : {"outside", "helix", "ramp", "plunge"}) {
      if (type == "linear" && entry == "helix") continue;
      const Job job = test::wagih_job(type, family_overrides(type, entry));
      for (const Dialect d : {Dialect::linuxcnc, Dialect::fanuc, Dialect::sinumerik, Dialect::grbl,
                              Dialect::haas, Dialect::mach3}) {
        const std::string label = fmt::format("{} {} {}", type, entry, to_string(d));
        const GcodeProgram prog = read_gcode(write(job, d), "safe.ngc");
        expect_safe_rapids(prog, job.machine.safe_z_mm, label);
        // The path starts above the stock and ends at the clearance plane.
        EXPECT_GE(prog.path.segments().front().start().z(), job.machine.safe_z_mm - 1e-4) << label;
        EXPECT_GE(prog.path.segments().back().end().z(), job.machine.safe_z_mm - 1e-4) << label;
      }
    }
  }
}

TEST(Safety, PlacementTurnsAndMovesEveryMoveExactly) {
  for (const std::string type : {"elliptical", "linear", "trochoidal"}) {
    const std::vector<Override> base = family_overrides(type, type == "linear" ? "ramp" : "helix");
    const Job job = test::wagih_job(type, base);
    const GcodeProgram plain = read_gcode(write(job, Dialect::linuxcnc), "plain.ngc");
    for (const double angle : {0.0, 90.0, 180.0, -90.0, 270.0, 37.5, -123.25}) {
      std::vector<Override> ov = base;
      ov.push_back(parse_override("slot.origin_x=125.5"));
      ov.push_back(parse_override("slot.origin_y=-40.25"));
      ov.push_back(parse_override(fmt::format("slot.angle={}", angle)));
      const Job placed_job = test::wagih_job(type, ov);
      const Placement pl = slot_placement(placed_job);
      const GcodeProgram placed = read_gcode(write(placed_job, Dialect::linuxcnc), "placed.ngc");
      const std::string label = fmt::format("{} at {} degrees", type, angle);
      ASSERT_EQ(placed.path.segments().size(), plain.path.segments().size()) << label;
      // At multiples of 90 degrees with an origin on the 1e-4 mm grid the turn commutes with
      // the output's rounding: every written coordinate is exactly the plain one moved (1e-9:
      // the reader's own arithmetic on arc centres). Otherwise both are rounded to 1e-4 mm
      // independently: at most 0.5e-4 sqrt(2) each in XY.
      const bool right_angle = std::fmod(angle, 90.0) == 0;
      const double tol = right_angle ? 1e-9 : 2 * 0.5e-4 * std::sqrt(2.0) + 1e-9;
      double worst = 0;
      for (std::size_t i = 0; i < placed.path.segments().size(); ++i) {
        const Segment& p = placed.path.segments()[i];
        const Segment& q = plain.path.segments()[i];
        ASSERT_EQ(p.kind(), q.kind()) << label << " segment " << i;
        ASSERT_EQ(p.motion(), q.motion()) << label << " segment " << i;
        worst = std::max(worst, (p.end() - pl.to_work(q.end())).norm());
        // The arcs' centres and sweeps follow from rounded I, J and end points; the reader's
        // reconstruction amplifies that rounding on short arcs, so they are compared where
        // the rounding commutes with the turn (exact).
        if (right_angle && p.kind() == Segment::Kind::curve) {
          worst = std::max(worst, (p.center() - pl.to_work(q.center())).norm());
          EXPECT_NEAR(p.u1() - p.u0(), q.u1() - q.u0(), 1e-9) << label;  // G2 stays G2
        }
      }
      EXPECT_LE(worst, tol) << label;
      // Read back into the slot frame, the program is the plain one (what analyze --gcode does).
      const ToolPath back = to_slot_frame(placed.path, pl);
      double back_worst = 0;
      for (std::size_t i = 0; i < back.segments().size(); ++i) {
        back_worst = std::max(back_worst,
                              (back.segments()[i].end() - plain.path.segments()[i].end()).norm());
      }
      EXPECT_LE(back_worst, tol) << label;
      if (right_angle) {
        EXPECT_NEAR(back.length_mm(), plain.path.length_mm(), 1e-9 * plain.path.length_mm());
      }
      expect_safe_rapids(placed, job.machine.safe_z_mm, label);
    }
  }
}

TEST(Safety, PlacementFramesAreInverse) {
  const Placement pl{12.5, -3.25, 33.0};
  const Vec3 p(1.5, -7.25, -2);
  EXPECT_LE((pl.to_slot(pl.to_work(p)) - p).norm(), 1e-12);  // round-off of two turns
  // 90 degrees: the slot's +Y runs along the workpiece's -X, exactly.
  const Placement q{0, 0, 90};
  EXPECT_EQ(q.to_work(Vec3(0, 10, 0)), Vec3(-10, 0, 0));
  EXPECT_EQ(q.to_work(Vec3(3, 0, -1)), Vec3(0, 3, -1));
  const ToolPath path = plan_path(test::wagih_job("trochoidal")).path;
  const ToolPath moved = to_work_frame(path, pl);
  EXPECT_EQ(moved.cycles().size(), path.cycles().size());
  for (std::size_t k = 0; k < path.cycles().size(); ++k) {
    EXPECT_EQ(moved.cycles()[k].first_segment, path.cycles()[k].first_segment);
  }
  EXPECT_NEAR(moved.length_mm(), path.length_mm(), 1e-9 * path.length_mm());
}

// ---- LinuxCNC's interpreter ------------------------------------------------------------

std::string find_in_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  std::istringstream dirs(path != nullptr ? path : "/usr/bin:/bin");
  for (std::string dir; std::getline(dirs, dir, ':');) {
    const std::filesystem::path p = std::filesystem::path(dir) / name;
    if (access(p.c_str(), X_OK) == 0) return p.string();
  }
  return "";
}

struct CanonMove {
  std::string kind;  // STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED
  Vec3 end;
};
struct CanonRun {
  std::vector<CanonMove> moves;
  std::vector<std::string> calls_before_motion;  // canonical calls before the first move
  std::string errors;                            // anything rs274 printed that is not a call
};

std::vector<double> numbers_in(const std::string& args) {
  std::vector<double> v;
  std::istringstream in(args);
  for (std::string tok; std::getline(in, tok, ',');) v.push_back(std::strtod(tok.c_str(), nullptr));
  return v;
}

CanonRun run_rs274(const std::string& rs274, const std::filesystem::path& dir,
                   const std::string& code) {
  const auto prog = dir / "p.ngc", out = dir / "canon.txt";
  std::ofstream(prog) << code;
  // HOME: LinuxCNC 2.9's interpreter keeps its tool data in $HOME/.tool.mmap, truncated and
  // rewritten by every run; other tests run rs274 at the same time (ctest -j).
  const std::string cmd =
      fmt::format("HOME='{}' '{}' -t '{}' -g '{}' > '{}' 2>&1 < /dev/null", dir.string(), rs274,
                  (dir / "tool.tbl").string(), prog.string(), out.string());
  (void)std::system(cmd.c_str());
  CanonRun run;
  std::ifstream in(out);
  bool moved = false;
  for (std::string line; std::getline(in, line);) {
    // A canonical call: "   12 N..... NAME(args)" (std::regex is avoided: GCC 12 warns
    // falsely inside it under the sanitizers).
    const auto n = line.find(" N.");
    const auto open = line.find('(', n == std::string::npos ? 0 : n);
    const auto close = line.rfind(')');
    const bool is_call = n != std::string::npos && open != std::string::npos &&
                         close != std::string::npos && close > open &&
                         line.find_first_not_of(" 0123456789") == n + 1;
    if (is_call) {
      const auto name_at = line.find(' ', n + 1) + 1;
      const std::string name = line.substr(name_at, open - name_at);
      const std::vector<double> a = numbers_in(line.substr(open + 1, close - open - 1));
      if (name == "STRAIGHT_TRAVERSE" || name == "STRAIGHT_FEED") {
        run.moves.push_back({name, Vec3(a.at(0), a.at(1), a.at(2))});
        moved = true;
      } else if (name == "ARC_FEED") {
        // ARC_FEED(first_end, second_end, first_axis, second_axis, rotation, axis_end, ...)
        run.moves.push_back({name, Vec3(a.at(0), a.at(1), a.at(5))});
        moved = true;
      } else if (!moved) {
        run.calls_before_motion.push_back(line);
      }
    } else if (line != "executing" && !line.empty()) {
      run.errors += line + "\n";
    }
  }
  return run;
}

TEST(Rs274, LinuxCncReadsEveryProgramAndFindsNoUnsafeRapid) {
  const std::string rs274 = find_in_path("rs274");
  if (rs274.empty()) {
    GTEST_SKIP() << "rs274 (Debian's linuxcnc-uspace) is not installed: scripts/install-deps "
                    "--test installs it";
  }
  const auto dir = std::filesystem::temp_directory_path() /
                   fmt::format("trochomill-rs274-{}", static_cast<long>(getpid()));
  std::filesystem::create_directories(dir);
  // Tool 7 with a 50 mm length offset, so applying it is visible in the canonical calls.
  std::ofstream(dir / "tool.tbl") << "T7 P7 Z50 D10 ;\n";
  int runs = 0, combination = 0;
  for (const std::string type :
       {"trochoidal", "circular", "elliptical", "linear-elliptical", "linear"}) {
    for (const std::string entry : {"outside", "helix", "ramp", "plunge"}) {
      if (type == "linear" && entry == "helix") continue;
      int placement = 0;
      ++combination;
      for (const auto& [ox, oy, angle, offset] :
           std::vector<std::tuple<double, double, double, std::string>>{
               {0, 0, 0, "G54"}, {150.5, -20.25, 37.5, "G55"}, {-30, 60, 90, "G54"}}) {
#if defined(TROCHOMILL_SANITIZED)
        // 90 s under the sanitizers: there each family and entry at one of the placements in
        // turn (every placement still written); the Release suite runs all three.
        if (placement++ % 3 != combination % 3) continue;
#else
        (void)placement;
#endif
        std::vector<Override> ov = family_overrides(type, entry);
        ov.push_back(parse_override("tool.tool_number=7"));
        ov.push_back(parse_override(fmt::format("slot.origin_x={}", ox)));
        ov.push_back(parse_override(fmt::format("slot.origin_y={}", oy)));
        ov.push_back(parse_override(fmt::format("slot.angle={}", angle)));
        ov.push_back(parse_override("machine.work_offset=" + offset));
        const Job job = test::wagih_job(type, ov);
        const std::string label =
            fmt::format("{} {} at ({}, {}) {} deg {}", type, entry, ox, oy, angle, offset);
        const CanonRun run = run_rs274(rs274, dir, write(job, Dialect::linuxcnc));
        ASSERT_GE(run.moves.size(), 2u) << label;
        ++runs;
        ASSERT_TRUE(run.errors.empty()) << label << ": rs274 said\n" << run.errors;
        ASSERT_GT(run.moves.size(), 10u) << label;
        // The length offset of tool 7 is in effect before the first move, and the work offset
        // is the job's (G55 is coordinate system 2).
        bool tlo = false, g5x = offset == "G54";
        for (const std::string& c : run.calls_before_motion) {
          if (c.find("USE_TOOL_LENGTH_OFFSET") != std::string::npos) {
            tlo = c.find("USE_TOOL_LENGTH_OFFSET(0.0000 0.0000 0.0000") == std::string::npos;
          }
          if (c.find("SET_G5X_OFFSET(2,") != std::string::npos) g5x = true;
        }
        EXPECT_TRUE(tlo) << label << ": no tool length offset before the first move";
        EXPECT_TRUE(g5x) << label << ": the work offset was not selected";
        // The first move is Z alone (rs274 starts at X0 Y0), to the clearance plane.
        const double clear = job.machine.safe_z_mm;
        EXPECT_EQ(run.moves[0].kind, "STRAIGHT_TRAVERSE") << label;
        EXPECT_EQ(run.moves[0].end.x(), 0.0) << label;
        EXPECT_EQ(run.moves[0].end.y(), 0.0) << label;
        EXPECT_NEAR(run.moves[0].end.z(), clear, 1e-4) << label;
        // No rapid changes X or Y below the clearance plane; below it rapids go straight down
        // or up. 1e-4 mm: the program's resolution.
        Vec3 at = run.moves[0].end;
        for (const CanonMove& m : run.moves) {
          if (m.kind == "STRAIGHT_TRAVERSE" &&
              std::hypot(m.end.x() - at.x(), m.end.y() - at.y()) > 1e-6) {
            EXPECT_GE(std::min(at.z(), m.end.z()), clear - 1e-4)
                << label << ": rapid from " << at.transpose() << " to " << m.end.transpose();
          }
          at = m.end;
        }
        // LinuxCNC and trochomill's reader agree move by move on the same program (the reader
        // skips zero-length moves and takes the approach as its start point).
        const std::string code = write(job, Dialect::linuxcnc);
        const GcodeProgram ours = read_gcode(code, "p.ngc");
        std::size_t j = 0;
        Vec3 prev = run.moves[1].end;
        double disagree = 0;
        for (std::size_t i = 2; i < run.moves.size(); ++i) {
          if ((run.moves[i].end - prev).norm() < 1e-9) continue;
          prev = run.moves[i].end;
          ASSERT_LT(j, ours.path.segments().size()) << label;
          disagree = std::max(disagree, (ours.path.segments()[j].end() - prev).norm());
          ++j;
        }
        EXPECT_EQ(j, ours.path.segments().size()) << label;
        EXPECT_LE(disagree, 1e-9) << label;  // both parse the same 4-decimal numbers
        // And where LinuxCNC puts the tool is where the planned path, placed, puts it: every
        // end point lies on the path (the nearest of all samples) within the fit tolerance,
        // the rounding, and half the 0.002 mm sample spacing (a corner between samples).
        const ToolPath work = to_work_frame(plan_path(job).path, slot_placement(job));
        const PathSamples s = sample_by_length(work, 0.002);
        double worst = 0;
        std::size_t worst_i = 0;
        for (std::size_t i = 1; i < run.moves.size(); ++i) {
          std::size_t hint = 0;
          const double d = test::distance_to_polyline(s, run.moves[i].end, hint, s.size());
          if (d > worst) {
            worst = d;
            worst_i = i;
          }
        }
        EXPECT_LE(worst, 0.001 + 0.5e-4 * std::sqrt(3.0) + 0.001)
            << label << ": move " << worst_i << " to " << run.moves[worst_i].end.transpose();
      }
    }
  }
#if defined(TROCHOMILL_SANITIZED)
  EXPECT_EQ(runs, 19);
#else
  EXPECT_EQ(runs, 57);
#endif
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace trochomill
