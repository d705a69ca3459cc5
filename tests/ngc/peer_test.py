#!/usr/bin/python3
"""trochomill's interpreter against LinuxCNC's on a corpus of programs (tests/ngc/programs):
every canonical move's kind and end point within 1e-6 mm, arc centres and turning sense equal,
feeds equal, the total path length within 1e-9 relative.

    /usr/bin/python3 tests/ngc/peer_test.py TROCHOMILL [PROGRAM...]

LinuxCNC runs through its Python module `gcode` (tests/ngc/linuxcnc_canon.py) with the machine
of tests/ngc/machine.var and tests/ngc/tools.tbl; trochomill gets the same machine as options.
Exit 77 (a skip) when LinuxCNC is not installed.
"""
import math
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# The machine of machine.var (inches there; mm here) and tools.tbl.
G54 = (101.6, 50.8, -25.4)
OPTIONS = ["--offset", "G54=101.6,50.8,-25.4", "--offset", "G55=254,127,-12.7",
           "--offset", "G56=-50.8,76.2,0", "--offset", "G59.3=25.4,25.4,0",
           "--g28", "0,0,50.8", "--g30", "254,25.4,38.1",
           "--tool-table", os.path.join(HERE, "tools.tbl"), "-I", os.path.join(HERE, "lib")]
# End points: both print 9 decimals and compute in double precision from the same words, so
# 1e-6 mm holds unless a rule differs.
TOL_MM = 1e-6
TOL_FEED = 1e-6  # mm/min, relative; feeds are products of the same words


def parse(line):
    """A move line of either tool: (kind, end, centre, axis, turns, feed, line, started)."""
    started = not line.startswith("; ")
    if not started:
        line = line[2:]
    words = line.split()
    kind = words[0]
    end = [float(words[1][1:]), float(words[2][1:]), float(words[3][1:])]
    centre = axis = turns = feed = None
    src = None
    for w in words[4:]:
        if w[0] == "C":
            centre = [None if c == "-" else float(c) for c in w[1:].split(",")]
        elif w[0] == "A":
            axis = [int(float(a)) for a in w[1:].split(",")]
        elif w[0] == "R":
            turns = int(w[1:])
        elif w[0] == "T":
            sweep = float(w[1:])
            turns = int(math.copysign(math.ceil(abs(sweep) / 360.0 - 1e-9), sweep))
        elif w[0] == "F":
            feed = float(w[1:])
        elif w[0] == "L":
            src = int(w[1:])
        elif ":" in w:
            src = int(w.rsplit(":", 1)[1])
    return kind, end, centre, axis, turns, feed, src, started


def length(moves, first):
    """The path's length: the moves from `first` on, from the end of the one before."""
    total = 0.0
    if first > len(moves):  # no moves (a program without motion) or none after the first
        return total
    prev = moves[first - 1][1] if first > 0 else [0.0, 0.0, 0.0]
    for kind, end, centre, axis, turns, feed, src, started in moves[first:]:
        if kind in ("G2", "G3"):
            n = axis.index(1)
            i1, i2 = [(0, 1), (1, 2), (2, 0)][[2, 0, 1].index(n)]
            c1, c2 = centre[i1], centre[i2]
            r = math.hypot(prev[i1] - c1, prev[i2] - c2)
            a0 = math.atan2(prev[i2] - c2, prev[i1] - c1)
            a1 = math.atan2(end[i2] - c2, end[i1] - c1)
            ccw = kind == "G3"
            sweep = (a1 - a0) % (2 * math.pi) if ccw else (a0 - a1) % (2 * math.pi)
            if sweep < 1e-12:
                sweep = 2 * math.pi
            sweep += 2 * math.pi * (abs(turns) - 1)
            total += math.hypot(r * sweep, end[n] - prev[n])
        else:
            total += math.dist(prev, end)
        prev = end
    return total


def xy_arc_points(kind, prev, end, centre, sagitta=1e-4):
    """The points after `prev` of an XY arc move (G2/G3) from prev to end about centre, as
    chords of sagitta <= `sagitta` mm (a whole circle when the ends coincide)."""
    cx, cy = centre[0], centre[1]
    r = math.hypot(prev[0] - cx, prev[1] - cy)
    a0 = math.atan2(prev[1] - cy, prev[0] - cx)
    a1 = math.atan2(end[1] - cy, end[0] - cx)
    sweep = (a1 - a0) % (2 * math.pi) if kind == "G3" else -((a0 - a1) % (2 * math.pi))
    if abs(sweep) < 1e-12:
        sweep = math.copysign(2 * math.pi, 1 if kind == "G3" else -1)
    step = 2 * math.acos(max(-1.0, 1 - sagitta / r)) if r > sagitta else math.pi
    n = max(1, math.ceil(abs(sweep) / step))
    return [(cx + r * math.cos(a0 + sweep * k / n), cy + r * math.sin(a0 + sweep * k / n))
            for k in range(1, n + 1)]


def main():
    troch = sys.argv[1]
    programs = sys.argv[2:] or sorted(
        os.path.join(HERE, "programs", f) for f in os.listdir(os.path.join(HERE, "programs"))
        if f.endswith(".ngc"))
    failures = 0
    compared = 0
    for prog in programs:
        name = os.path.basename(prog)
        # Programs that use the tool table or G95 go to `rs274 -g` (this Debian build's Python
        # module crashes on tool data and does not pass the spindle speed), which prints 4
        # decimals of the program's unit: ends within half its last digit (in mm, or in inches
        # after G20), lengths within that per move.
        text = open(prog).read().upper()
        standalone = "G43" in text or "M6" in text or "G95" in text or "G41 " in text \
            or "G42 " in text
        digit = 5e-5 * (25.4 if "G20" in text else 1.0)
        tol = digit + 1e-9 if standalone else TOL_MM
        peer = subprocess.run(
            ["/usr/bin/python3", os.path.join(HERE, "linuxcnc_canon.py"), prog, "--var",
             os.path.join(HERE, "machine.var"), "--tools", os.path.join(HERE, "tools.tbl")]
            + (["--rs274"] if standalone else []),
            capture_output=True, text=True, cwd=os.path.join(HERE, "lib"))
        if peer.returncode == 77:
            print(peer.stderr.strip())
            return 77
        ours = subprocess.run([troch, "check-gcode", prog, "--trace"] + OPTIONS,
                              capture_output=True, text=True)
        problems = []
        if peer.returncode != 0:
            problems.append("LinuxCNC: " + (peer.stdout + peer.stderr).strip())
        if ours.returncode != 0:
            problems.append("trochomill: " + ours.stderr.strip())
        if not problems:
            a = [parse(l) for l in peer.stdout.splitlines() if l.strip()]
            b = [parse(l) for l in ours.stdout.splitlines() if l.strip()]
            # LinuxCNC's moves in machine coordinates; trochomill's in G54.
            a = [(k, [e[i] - G54[i] for i in range(3)],
                  None if c is None else [None if c[i] is None else c[i] - G54[i]
                                          for i in range(3)], ax, t, f, s, st)
                 for k, e, c, ax, t, f, s, st in a]
            if len(a) != len(b):
                problems.append("%d moves in LinuxCNC, %d in trochomill" % (len(a), len(b)))
            for i, (m, n) in enumerate(zip(a, b)):
                where = "move %d (LinuxCNC line %s, trochomill line %s)" % (i + 1, m[6], n[6])
                if m[0] != n[0]:
                    problems.append("%s: %s against %s" % (where, m[0], n[0]))
                    break
                # Before the path starts the machine's position is unknown (LinuxCNC starts
                # at machine zero, trochomill at the work origin): only the kinds compare.
                d = max(abs(m[1][k] - n[1][k]) for k in range(3)) if n[7] else 0.0
                if d > tol:
                    problems.append("%s: end %s against %s" % (where, m[1], n[1]))
                    break
                if m[0] in ("G2", "G3"):
                    if m[3] != n[3] or m[4] != n[4]:
                        problems.append("%s: axis/turns %s %s against %s %s"
                                        % (where, m[3], m[4], n[3], n[4]))
                        break
                    dc = max(abs(m[2][k] - n[2][k]) for k in range(3) if m[2][k] is not None)
                    # LinuxCNC keeps a centre whose radii to start and end differ (within its
                    # limits: a spiral); trochomill moves it onto the chord's bisector, by at
                    # most that difference.
                    start = a[i - 1][1] if i > 0 else None
                    spiral = 0.0
                    if start is not None:
                        ks = [k for k in range(3) if m[2][k] is not None]
                        r0 = math.sqrt(sum((start[k] - m[2][k]) ** 2 for k in ks))
                        r1 = math.sqrt(sum((m[1][k] - m[2][k]) ** 2 for k in ks))
                        spiral = abs(r0 - r1)
                    if dc > tol + spiral:
                        problems.append("%s: centre %s against %s" % (where, m[2], n[2]))
                        break
                if m[0] != "G0" and abs(m[5] - n[5]) > max(TOL_FEED * abs(m[5]), tol):
                    problems.append("%s: feed %.9g against %.9g" % (where, m[5], n[5]))
                    break
            if not problems:
                # The path's length from its second move: its first one starts at the height
                # the approach left the tool at, which is unknown before the program.
                first = next((i for i, m in enumerate(b) if m[7]), len(b)) + 1
                la, lb = length(a, first), length(b, first)
                if abs(la - lb) > (2 * digit * len(a) if standalone else 1e-9 * max(la, 1.0)):
                    problems.append("length %.12g mm against %.12g mm" % (la, lb))
            compared += len(b)
        if problems:
            failures += 1
            print("FAIL %s\n  %s" % (name, "\n  ".join(problems)))
        else:
            print("ok   %s" % name)
    print("%d programs, %d moves compared, %d failed" % (len(programs), compared, failures))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
