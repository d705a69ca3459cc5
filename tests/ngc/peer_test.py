#!/usr/bin/python3
"""trochomill's interpreter against LinuxCNC's on a corpus of programs (tests/ngc/programs):
every canonical move's kind and end point within 1e-6 mm, arc centres and turning sense equal,
feeds equal, the total path length within 1e-9 relative.

    /usr/bin/python3 tests/ngc/peer_test.py TROCHOMILL [--zero-machine] [--tools FILE] [PROGRAM...]

--zero-machine: a machine whose offsets and G28/G30 positions are all zero (programs written
for another machine: both interpreters then start at the work origin, which is machine zero);
--tools: another tool table (lines "T<n> Z<length mm> D<diameter mm>").

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
    """A move line of either tool: (kind, end, centre, axis, turns, feed, line, started, extra):
    extra is A B C (degrees) and U V W (mm) at the end, None where the line has none."""
    started = not line.startswith("; ")
    if not started:
        line = line[2:]
    words = line.split()
    kind = words[0]
    end = [float(words[1][1:]), float(words[2][1:]), float(words[3][1:])]
    centre = axis = turns = feed = None
    src = extra = None
    for w in words[4:]:
        if w.startswith("ABC:") or w.startswith("UVW:"):
            extra = (extra or []) + [float(v) for v in w[4:].split(",")]
        elif w[0] == "C":
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
    return kind, end, centre, axis, turns, feed, src, started, extra


def length(moves, first):
    """The path's length: the moves from `first` on, from the end of the one before."""
    total = 0.0
    if first > len(moves):  # no moves (a program without motion) or none after the first
        return total
    prev = moves[first - 1][1] if first > 0 else [0.0, 0.0, 0.0]
    for kind, end, centre, axis, turns, feed, src, started, extra in moves[first:]:
        if kind == "SPL":  # a spline: compared on its own (compare_spline)
            prev = end
            continue
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


SPLINE_TOL = 1e-3 + 1e-6  # mm: trochomill's spline_tolerance_mm, and the 9 printed decimals


def special_line_numbers(prog):
    """The program's lines, in one pass, (a) with a spline code (G5, G5.1, G5.3: where the
    curve is made) and (b) with G33, G33.1 or G76: their moves run at the pitch times the
    spindle speed, which LinuxCNC's canon does not pass to the preview (their feeds are not
    compared)."""
    import re
    spline = re.compile(r"G\s*0*5\s*(\.\s*[013])?(?![\d.])", re.I)
    synced = re.compile(r"G\s*(33|76)(?![\d])", re.I)
    splines, synchronized = set(), set()
    for n, text in enumerate(open(prog, errors="replace"), 1):
        text = re.sub(r"\([^)]*\)|;.*", "", text)
        if spline.search(text):
            splines.add(n)
        if synced.search(text):
            synchronized.add(n)
    return splines, synchronized


def collapse_splines(moves, lines):
    """Each run of moves from one spline line as one move ("SPL"); the runs' moves by key."""
    out, runs = [], {}
    i = 0
    while i < len(moves):
        m = moves[i]
        if m[6] in lines and m[0] != "G0":
            j = i
            while j + 1 < len(moves) and moves[j + 1][6] == m[6] and moves[j + 1][0] != "G0":
                j += 1
            prev = out[-1][1] if out else moves[i][1]
            key = (m[6], len(runs))
            runs[key] = (prev, moves[i:j + 1])
            last = moves[j]
            out.append(("SPL", last[1], None, None, None, last[5], last[6], last[7], last[8]))
            i = j + 1
        else:
            out.append(m)
            i += 1
    return out, runs


def path_points(start, run, step=2e-3):
    """Points along a run of moves (lines and XY arcs) at most `step` mm apart."""
    pts = [start]
    prev = start
    for kind, end, centre, axis, turns, feed, src, started, extra in run:
        if kind in ("G2", "G3"):
            r = math.hypot(prev[0] - centre[0], prev[1] - centre[1])
            for x, y in xy_arc_points(kind, prev, end, centre, sagitta=min(1e-6, r / 10)):
                pts.append([x, y, end[2]])
        else:
            n = max(1, math.ceil(math.dist(prev, end) / step))
            pts += [[prev[k] + (end[k] - prev[k]) * t / n for k in range(3)]
                    for t in range(1, n + 1)]
        prev = end
    return pts


def seg_distance(p, a, b):
    d = [b[k] - a[k] for k in range(3)]
    L2 = sum(v * v for v in d)
    t = 0.0 if L2 == 0 else max(0.0, min(1.0, sum((p[k] - a[k]) * d[k] for k in range(3)) / L2))
    return math.dist(p, [a[k] + t * d[k] for k in range(3)])


def compare_spline(ra, rb):
    """LinuxCNC's chords against trochomill's arcs of one spline: the same start and end, every
    LinuxCNC point within SPLINE_TOL of trochomill's curve, and the chords no longer than the
    arcs (a chord is shorter than the curve it spans) but not 1 % shorter."""
    (sa, ma), (sb, mb) = ra, rb
    if max(abs(ma[-1][1][k] - mb[-1][1][k]) for k in range(3)) > 1e-6:
        return "end %s against %s" % (ma[-1][1], mb[-1][1])
    dense = path_points(sb, mb)
    worst = 0.0
    for m in ma:
        p = m[1]
        worst = max(worst, min(seg_distance(p, dense[k], dense[k + 1])
                               for k in range(len(dense) - 1)))
    if worst > SPLINE_TOL:
        return "a point of LinuxCNC's %.6f mm from trochomill's curve" % worst
    la = sum(math.dist(p, q) for p, q in zip([sa] + [m[1] for m in ma], [m[1] for m in ma]))
    lb = sum(math.dist(p, q) for p, q in zip(dense, dense[1:]))
    if not (0.99 * lb - 1e-6 <= la <= lb + 1e-6):
        return "chords %.6f mm against the curve's %.6f mm" % (la, lb)
    return None


def main():
    global G54, OPTIONS
    args = sys.argv[1:]
    troch = args.pop(0)
    var, tools = os.path.join(HERE, "machine.var"), os.path.join(HERE, "tools.tbl")
    if "--tools" in args:
        k = args.index("--tools")
        tools = os.path.abspath(args[k + 1])
        del args[k:k + 2]
        OPTIONS = [tools if o.endswith("tools.tbl") else o for o in OPTIONS]
    if "--zero-machine" in args:
        args.remove("--zero-machine")
        var = os.path.join(HERE, "zero.var")
        G54 = (0.0, 0.0, 0.0)
        OPTIONS = ["--g28", "0,0,0", "--g30", "0,0,0", "--tool-table", tools,
                   "-I", os.path.join(HERE, "lib")]
    programs = args or sorted(
        os.path.join(HERE, "programs", f) for f in os.listdir(os.path.join(HERE, "programs"))
        if f.endswith(".ngc"))
    failures = 0
    compared = 0
    for prog in programs:
        prog = os.path.abspath(prog)  # LinuxCNC runs in lib/ (the subroutine files)
        name = os.path.basename(prog)
        # Programs that use the tool table or G95 go to `rs274 -g` (this Debian build's Python
        # module crashes on tool data and does not pass the spindle speed), which prints 4
        # decimals of the program's unit: ends within half its last digit (in mm, or in inches
        # after G20), lengths within that per move; where the program sets G92 or G52 offsets,
        # the machine position is the sum of three printed numbers (the end, the G5x and the
        # G92 offset), each rounded: three half-digits.
        text = open(prog).read().upper()
        standalone = "G43" in text or "M6" in text or "G95" in text or "G41 " in text \
            or "G42 " in text
        digit = 5e-5 * (25.4 if "G20" in text else 1.0)
        if "G92" in text or "G52" in text:
            digit *= 3
        tol = digit + 1e-9 if standalone else TOL_MM
        peer = subprocess.run(
            ["/usr/bin/python3", os.path.join(HERE, "linuxcnc_canon.py"), prog, "--var",
             var, "--tools", tools]
            + (["--rs274"] if standalone else []),
            capture_output=True, text=True, cwd=os.path.join(HERE, "lib"))
        if peer.returncode == 77:
            print(peer.stderr.strip())
            return 77
        if peer.returncode < 0 and not standalone:
            # The module crashed (it does on tool data the check above did not see: a bare T
            # word, M06): the standalone interpreter instead.
            standalone = True
            tol = digit + 1e-9
            peer = subprocess.run(
                ["/usr/bin/python3", os.path.join(HERE, "linuxcnc_canon.py"), prog, "--var",
                 var, "--tools", tools, "--rs274"], capture_output=True, text=True, cwd=os.path.join(HERE, "lib"))
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
                                          for i in range(3)], ax, t, f, s, st, x)
                 for k, e, c, ax, t, f, s, st, x in a]
            # Splines (G5, G5.1, G5.2 .. G5.3): LinuxCNC's preview draws chords between points
            # of the exact curve, trochomill follows it with arcs: each run of a spline's moves
            # becomes one move compared by its end, its points' distance to the arcs and its
            # length.
            spline_lines, synchronized = special_line_numbers(prog)
            if spline_lines:
                a, runs_a = collapse_splines(a, spline_lines)
                b, runs_b = collapse_splines(b, spline_lines)
                for key in sorted(set(runs_a) & set(runs_b)):
                    why = compare_spline(runs_a[key], runs_b[key])
                    if why:
                        problems.append("spline of line %s: %s" % (key[0], why))
                if set(runs_a) != set(runs_b):
                    problems.append("splines at lines %s in LinuxCNC, %s in trochomill"
                                    % (sorted(k[0] for k in runs_a), sorted(k[0] for k in runs_b)))
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
                # A B C U V W: trochomill prints them once the program has used them; before,
                # LinuxCNC's must be 0 (the machine of machine.var has no offsets for them).
                xa, xb = m[8] or [0.0] * 6, n[8] or [0.0] * 6
                if max(abs(xa[k] - xb[k]) for k in range(6)) > tol:
                    problems.append("%s: A B C U V W %s against %s" % (where, xa, xb))
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
                synced = n[6] in synchronized or (standalone and m[6] == 0 and synchronized)
                if m[0] != "G0" and not synced and abs(m[5] - n[5]) > max(TOL_FEED * abs(m[5]),
                                                                        tol):
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
