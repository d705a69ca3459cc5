#!/usr/bin/env python3
"""Slots along a drawing's contour, checked by other authors' code: each example of
examples/curves planned for LinuxCNC, read by LinuxCNC's own interpreter (rs274, through
tests/ngc/linuxcnc_canon.py), its motion length against trochomill's, and the plan area the
tool cuts at the floor (the tool-centre path buffered by the tool radius with shapely, GEOS)
against the slot's in closed form: a ring pi((Rc + W/2)^2 - (Rc - W/2)^2), a tube of length L
and width W with round ends L W + pi (W/2)^2 (the tube formula: every normal of the
centreline within W/2 sweeps once where its radius of curvature exceeds W/2).
Usage: peer.py TROCHOMILL WORK_DIR. Exit 77 (skip) without LinuxCNC."""
import math
import os
import subprocess
import sys

from shapely.geometry import LineString

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "tests", "ngc"))
from peer_test import parse, length, xy_arc_points  # noqa: E402  (the corpus test's reading)

cli, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def floor_points(moves, z_floor):
    """The tool centre's points at the floor: arcs as chords of sagitta <= 1e-4 mm."""
    pts, prev = [], [0.0, 0.0, 0.0]
    for kind, end, centre, axis, turns, feed, src, started, _extra in moves:
        at_floor = abs(prev[2] - z_floor) < 1e-6 and abs(end[2] - z_floor) < 1e-6
        if at_floor and kind in ("G2", "G3"):
            pts += xy_arc_points(kind, prev, end, centre)
        elif at_floor:
            if not pts:
                pts.append((prev[0], prev[1]))
            pts.append((end[0], end[1]))
        prev = end
    return pts


CASES = {
    # job, tool radius mm, depth mm, closed-form area mm^2
    "ring": (4.0, 3.0, math.pi * ((30 + 6) ** 2 - (30 - 6) ** 2)),
    "bend": (4.0, 3.0, (40 + math.pi * 20 / 2 + 30) * 12 + math.pi * 6 ** 2),
    # The SVG's centreline: its length as trochomill reads it (the Bezier's biarcs, within
    # 0.001 mm; check-drawing), the tube formula as for the bend.
    "s-curve": (4.0, 3.0, 117.3574 * 12 + math.pi * 6 ** 2),
}
for name, (radius, depth, area) in CASES.items():
    job = os.path.join(ROOT, "examples", "curves", name + ".toml")
    prog = os.path.join(work, name + ".ngc")
    plan = subprocess.run([cli, "plan", job, "--set", "machine.dialect=linuxcnc", "-o", prog],
                          capture_output=True, text=True)
    check(plan.returncode == 0, "%s: planned (%s)" % (name, (plan.stdout + plan.stderr).strip()))
    if plan.returncode != 0:
        continue
    ours = float(plan.stdout.split("path ")[1].split(" mm")[0])
    peer = subprocess.run(["/usr/bin/python3", os.path.join(ROOT, "tests", "ngc", "linuxcnc_canon.py"),
                           prog, "--tools", os.path.join(ROOT, "tests", "ngc", "tools.tbl"),
                           "--rs274"], capture_output=True, text=True)
    if peer.returncode == 77:
        print(peer.stderr.strip())
        sys.exit(77)
    check(peer.returncode == 0 and "error" not in peer.stdout,
          "%s: LinuxCNC's rs274 reads the program (%s)" % (name, peer.stderr.strip()[:200]))
    moves = [parse(l) for l in peer.stdout.splitlines() if l.strip()]
    # Before the first move off the machine's X0 Y0 (LinuxCNC starts there, trochomill's path
    # above its first point) the two do not compare: both lengths from that move's end.
    first = next(i for i, m in enumerate(moves) if m[7] and (m[1][0], m[1][1]) != (0.0, 0.0))
    theirs = length(moves, first + 1)
    pts = floor_points(moves, -depth)
    cut = LineString(pts).buffer(radius, resolution=256).area
    # 0.5 %: the biarcs narrow the orbit by the arc tolerance (0.001 mm of 6 mm walls) and the
    # buffer's polygon and the chords are within 1e-4 mm: far below it.
    check(abs(cut / area - 1) < 0.005,
          "%s: cut area at the floor %.3f mm^2 against %.3f mm^2 (%+.4f %%)"
          % (name, cut, area, 100 * (cut / area - 1)))
    # The program's coordinates have 4 decimals (each end within 5e-5 mm of the path's, the
    # errors of joined moves mostly cancel) and `plan` prints the length to 0.001 mm: 0.01 mm
    # (+1e-6 of the length) holds them (measured 0.0005 and 0.0026 mm) and catches a missing
    # loop (12 mm) or a wrong arc.
    check(abs(theirs - ours) < 1e-6 * ours + 0.01,
          "%s: LinuxCNC's motion length %.4f mm, trochomill's %.4f mm" % (name, theirs, ours))

if failures:
    print("%d failed" % len(failures))
    sys.exit(1)
