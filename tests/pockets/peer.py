#!/usr/bin/env python3
"""Pockets, checked by other authors' code: each test pocket of tests/data/dxf/pockets.dxf
(ezdxf's drawing) planned for LinuxCNC and read by LinuxCNC's own interpreter (rs274, through
tests/ngc/linuxcnc_canon.py): its motion length against trochomill's; the plan area the tool
cuts at the floor (the tool-centre path there buffered by the tool radius with shapely, GEOS)
against the pocket's net area less the inside corners' cusps in closed form,
(1 - pi/4) (R + 0.002)^2 each (the finishing pass runs 0.002 mm off the walls); no tool centre
at a cutting level closer to a wall or island than R + stock to leave (R for the finishing
pass); and the engagement kernel's proof that `plan` prints: the clearing's largest
engagement outside the entries at most the target + 2 %. Then rest machining: the rectangle
by a 20 mm tool and by a 6 mm tool after it, the pair's cut area and the second's. Then the
entries: a pocket open beside its stock box, a pre-drilled hole.
Usage: peer.py TROCHOMILL WORK_DIR. Exit 77 (skip) without LinuxCNC."""
import math
import os
import re
import subprocess
import sys

from shapely.geometry import LineString, Point, Polygon
from shapely.ops import unary_union

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "ngc"))
from peer_test import parse, length, xy_arc_points  # noqa: E402

cli, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []
DXF = os.path.join(ROOT, "tests", "data", "dxf", "pockets.dxf")
R = 5.0
CUSP = (1 - math.pi / 4) * (R + 0.002) ** 2


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def rs274(program):
    """LinuxCNC's rs274 reading the program (tests/ngc/linuxcnc_canon.py): its moves as lines."""
    return subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "tests", "ngc", "linuxcnc_canon.py"),
                           program, "--tools", os.path.join(ROOT, "tests", "ngc", "tools.tbl"),
                           "--rs274"], capture_output=True, text=True)


def path_points(moves, keep):
    """The tool centre's feed points where keep(z0, z1): arcs as chords of sagitta <= 1e-4 mm,
    as runs (a list of point lists, one per run of such moves)."""
    runs, cur, prev = [], [], [0.0, 0.0, 0.0]
    for kind, end, centre, axis, turns, feed, src, started, _extra in moves:
        if kind in ("G1", "G2", "G3") and keep(prev[2], end[2]):
            if not cur:
                cur.append((prev[0], prev[1]))
            if kind in ("G2", "G3"):
                cur += xy_arc_points(kind, prev, end, centre)
            else:
                cur.append((end[0], end[1]))
        elif cur:
            runs.append(cur)
            cur = []
        prev = end
    if cur:
        runs.append(cur)
    return runs


CASES = {
    # name: (boundary layer, islands layer, the walls as shapely polygons, convex corners)
    "rect": ("RECT", None, Polygon([(0, 0), (60, 0), (60, 40), (0, 40)]), 4),
    "l": ("L", None, Polygon([(100, 0), (150, 0), (150, 20), (120, 20), (120, 50), (100, 50)]), 5),
    "islands": ("ISLB", "ISL",
                Polygon([(200, 0), (270, 0), (270, 50), (200, 50)]).difference(
                    Polygon([(215, 12), (227, 12), (227, 20), (215, 20)])).difference(
                    Point(250, 25).buffer(6.0, resolution=4096)), 4),
    "neck": ("NECK", None, Polygon([(300, 0), (330, 0), (330, 8), (345, 8), (345, 0), (375, 0),
                                    (375, 30), (345, 30), (345, 22), (330, 22), (330, 30),
                                    (300, 30)]), 8),
    "circle": ("CIRC", None, Point(450, 20).buffer(20.0, resolution=4096), 0),
    # Channels, cleared by trochoidal loops along the medial axis: a straight one, a ring about
    # an island (no corners), a room with one too narrow for the clearing passes.
    "channel": ("CHAN", None, Polygon([(500, 0), (560, 0), (560, 14), (500, 14)]), 4),
    "ring": ("RING", "RINGI", Point(620, 30).buffer(24.0, resolution=4096).difference(
        Point(620, 30).buffer(10.0, resolution=4096)), 0),
    "thin": ("THIN", None, Polygon([(700, 0), (740, 0), (740, 14.4), (780, 14.4), (780, 25.6),
                                    (740, 25.6), (740, 40), (700, 40)]), 6),
}
# The channels by the straight slot's families ([path] type): the cycles carried along a
# straight axis, a ring's and a narrow one's.
CASES["channel-linear-elliptical"] = CASES["channel"] + (
    '[path]\ntype = "linear-elliptical"\naspect_ratio = 0.8\nlinear_distance = 0.3\n',)
CASES["ring-elliptical"] = CASES["ring"] + ('[path]\ntype = "elliptical"\naspect_ratio = 0.7\n',)
CASES["thin-trochoidal"] = CASES["thin"] + ('[path]\ntype = "trochoidal"\n',)
TARGET, STOCK, DEPTH = 50.0, 0.2, 4.0
for name, case in CASES.items():
    boundary, islands, walls, corners = case[:4]
    job = os.path.join(work, name + ".toml")
    with open(job, "w") as f:
        f.write('[geometry]\nfile = "%s"\n[pocket]\nboundary = "%s"\n' % (DXF, boundary))
        if islands:
            f.write('islands = "%s"\n' % islands)
        f.write("depth = %g\nmax_step_down = 2.0\nstock_to_leave = %g\nmax_engagement = %g\n"
                "[tool]\ndiameter = %g\nteeth = 3\n[cutting]\nfeed_rate = 1200.0\n"
                "spindle_speed = 8000.0\n%s" % (DEPTH, STOCK, TARGET, 2 * R, "".join(case[4:])))
    prog = os.path.join(work, name + ".ngc")
    plan = subprocess.run([cli, "plan", job, "-o", prog], capture_output=True, text=True)
    check(plan.returncode == 0, "%s: planned (%s)" % (name, plan.stderr.strip()[:300]))
    if plan.returncode != 0:
        continue
    ours = float(plan.stdout.split(": pocket, path ")[1].split(" mm")[0])
    eng = float(re.search(r"clearing \(entries excepted\) engagement max ([0-9.]+)", plan.stdout)[1])
    # 2 %: the acceptance of the target (the planner holds 1.2 degrees below it at its points;
    # the kernel samples every tooth in between).
    check(eng <= TARGET * 1.02, "%s: the kernel's largest clearing engagement %.3f degrees "
          "(target %g)" % (name, eng, TARGET))
    peer = rs274(prog)
    if peer.returncode == 77:
        print(peer.stderr.strip())
        sys.exit(77)
    check(peer.returncode == 0 and "error" not in peer.stdout,
          "%s: LinuxCNC's rs274 reads the program (%s)" % (name, peer.stderr.strip()[:200]))
    moves = [parse(l) for l in peer.stdout.splitlines() if l.strip()]
    first = next(i for i, m in enumerate(moves) if m[7] and (m[1][0], m[1][1]) != (0.0, 0.0))
    theirs = length(moves, first + 1)
    # 4 decimals in the program (5e-5 mm an end) over thousands of moves: 1e-5 of the length;
    # and an arc of radius r below 1 mm (a narrow channel's loops) turns by up to 5e-5 sqrt 2 / r
    # more or less at each end as LinuxCNC reads it: its length by up to 1.5e-4 mm.
    small, prev = 0, (0.0, 0.0, 0.0)
    for m in moves:
        if m[0] in ("G2", "G3") and math.hypot(prev[0] - m[2][0], prev[1] - m[2][1]) < 1.0:
            small += 1
        prev = m[1]
    check(abs(theirs - ours) < 1e-5 * ours + 0.01 + 1.5e-4 * small,
          "%s: LinuxCNC's motion length %.4f mm, trochomill's %.4f mm" % (name, theirs, ours))
    floor = path_points(moves, lambda z0, z1: abs(z0 + DEPTH) < 1e-6 and abs(z1 + DEPTH) < 1e-6)
    cut = unary_union([LineString(r).buffer(R, resolution=64) if len(r) > 1
                       else Point(r[0]).buffer(R, resolution=64) for r in floor])
    expected = walls.area - corners * CUSP
    # 1 %: the acceptance; the buffer's polygons (64 segments a quarter) are within
    # 1e-3 mm of the circles and the program's coordinates within 5e-5 mm.
    check(abs(cut.area / expected - 1) < 0.01,
          "%s: cut area at the floor %.2f mm^2 against %.2f mm^2 (%+.3f %%)"
          % (name, cut.area, expected, 100 * (cut.area / expected - 1)))
    # No centre closer to the walls than R + stock to leave while clearing (the program
    # planned again without the finishing pass: the clearing is the same), than R in the
    # whole program. 1e-4 mm: the program's 4 decimals and the chords of the arcs.
    edge = walls.boundary

    def closest(moves):
        runs = path_points(moves, lambda z0, z1: z0 < 0 and z1 < 0 and abs(z0 - z1) < 1e-9)
        return min(edge.distance(Point(p)) for r in runs for p in r)

    rough = os.path.join(work, name + "-rough.ngc")
    plan = subprocess.run([cli, "plan", job, "--set", "pocket.finish_pass=false", "-o", rough],
                          capture_output=True, text=True)
    peer = rs274(rough)
    rough_moves = [parse(l) for l in peer.stdout.splitlines() if l.strip()]
    check(plan.returncode == 0 and peer.returncode == 0 and rough_moves,
          "%s: the clearing alone planned and read" % name)
    if rough_moves:
        d = closest(rough_moves)
        check(d >= R + STOCK - 1e-4, "%s: the clearing's closest centre %.5f mm from a wall "
              "(R + stock = %g)" % (name, d, R + STOCK))
    d = closest(moves)
    check(d >= R - 1e-4, "%s: the program's closest centre %.5f mm from a wall (R = %g)"
          % (name, d, R))

def rect_program(name, extra, d, sets=()):
    """The rectangle 4 mm deep at the target with a tool of diameter d and `extra` [pocket]
    keys, planned (with --set `sets`), the kernel's proof checked and read by LinuxCNC: its
    moves and the tool's cut at the floor (shapely), or None where planning failed."""
    job = os.path.join(work, name + ".toml")
    with open(job, "w") as f:
        f.write('[geometry]\nfile = "%s"\n[pocket]\nboundary = "RECT"\n%s' % (DXF, extra))
        f.write("depth = %g\nmax_step_down = 2.0\nmax_engagement = %g\n[tool]\ndiameter = %g\n"
                "teeth = 3\n[cutting]\nfeed_rate = 1200.0\nspindle_speed = 8000.0\n"
                % (DEPTH, TARGET, d))
    prog = os.path.join(work, name + ".ngc")
    args = [cli, "plan", job, "-o", prog]
    for a in sets:
        args += ["--set", a]
    plan = subprocess.run(args, capture_output=True, text=True)
    check(plan.returncode == 0, "%s: planned (%s)" % (name, plan.stderr.strip()[:300]))
    if plan.returncode != 0:
        return None
    eng = float(re.search(r"clearing \(entries excepted\) engagement max ([0-9.]+)", plan.stdout)[1])
    check(eng <= TARGET * 1.02, "%s: the kernel's largest clearing engagement %.3f degrees "
          "(target %g)" % (name, eng, TARGET))
    peer = rs274(prog)
    check(peer.returncode == 0 and "error" not in peer.stdout,
          "%s: LinuxCNC's rs274 reads the program (%s)" % (name, peer.stderr.strip()[:200]))
    moves = [parse(l) for l in peer.stdout.splitlines() if l.strip()]
    floor = path_points(moves, lambda z0, z1: abs(z0 + DEPTH) < 1e-6 and abs(z1 + DEPTH) < 1e-6)
    cut = unary_union([LineString(r).buffer(d / 2, resolution=64) if len(r) > 1
                       else Point(r[0]).buffer(d / 2, resolution=64) for r in floor])
    return moves, cut


# Rest machining: the rectangle by a 20 mm tool, then by a 6 mm tool after it ([pocket]
# rest_of, the first program's header giving its tool). LinuxCNC reads both; at the floor the
# pair cuts the rectangle less the 6 mm tool's cusps, and the second cuts, outside what the
# first cut, the corners' difference of cusps.
walls = CASES["rect"][2]
cuts = {}
for name, d, extra in (("rest-first", 20.0, ""), ("rest-second", 6.0, 'rest_of = "rest-first.ngc"\n')):
    got = rect_program(name, extra, d)
    if got is None:
        break
    cuts[name] = got[1]
if len(cuts) == 2:
    first, second = cuts["rest-first"], cuts["rest-second"]
    c = 1 - math.pi / 4
    pair = first.union(second).area
    expected = walls.area - 4 * c * 3.002 ** 2
    # 1 %, the (the first program alone: 3.3 % short).
    check(abs(pair / expected - 1) < 0.01, "rest: the pair cuts %.2f mm^2 at the floor against "
          "%.2f mm^2 (%+.3f %%)" % (pair, expected, 100 * (pair / expected - 1)))
    left = second.difference(first).area
    corners = 4 * c * (10.002 ** 2 - 3.002 ** 2)
    # 2 %: the corners' 78 mm^2 against shapely's polygons (1e-3 mm along 40 mm of arcs).
    check(abs(left / corners - 1) < 0.02, "rest: the second cuts %.2f mm^2 the first left, "
          "against the cusps' difference %.2f mm^2" % (left, corners))

# Entries: the rectangle with its [stock] box from x = 20 on (its left third air: the tool
# comes down there, its disc clear of the box), and with a pre-drilled hole at (45, 20) (fed
# straight down it). LinuxCNC reads both; the first move below the top is where it should be;
# at the floor the tool cuts the rectangle's part in the box less two corners' cusps (open),
# the rectangle less four (hole).
box = Polygon([(20, -5), (80, -5), (80, 45), (20, 45)])
for name, extra, sets in (("open", "", ["stock.min=[20, -5, -3]", "stock.max=[80, 45, 0]"]),
                          ("hole", "entry_holes = [[45, 20]]\n", [])):
    got = rect_program(name, extra, 2 * R, sets)
    if got is None:
        continue
    moves, cut = got
    down = next(m for m in moves if m[1][2] < 0)
    if name == "open":
        # 1e-4 mm: the program's 4 decimals.
        d = box.distance(Point(down[1][0], down[1][1]))
        # (A rapid: there is nothing there to cut.)
        check(d >= R - 1e-4, "open: the first move below the top, %s to "
              "(%.4f, %.4f), %.4f mm from the stock box (R = %g)"
              % (down[0], down[1][0], down[1][1], d, R))
    else:
        check(down[0] == "G1" and abs(down[1][0] - 45) < 1e-4 and abs(down[1][1] - 20) < 1e-4,
              "hole: the first move below the top, %s to (%.4f, %.4f), down the hole at (45, 20)"
              % (down[0], down[1][0], down[1][1]))
    if name == "open":
        cut, expected = cut.intersection(box), walls.intersection(box).area - 2 * CUSP
    else:
        expected = walls.area - 4 * CUSP
    # 1 %: the acceptance (as the pockets above).
    check(abs(cut.area / expected - 1) < 0.01,
          "%s: cut area at the floor %.2f mm^2 against %.2f mm^2 (%+.3f %%)"
          % (name, cut.area, expected, 100 * (cut.area / expected - 1)))

if failures:
    print("%d failed" % len(failures))
    sys.exit(1)
