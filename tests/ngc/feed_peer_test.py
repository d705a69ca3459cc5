#!/usr/bin/python3
"""optimize-feed on every corpus program (tests/ngc/programs) with the machine of
peer_test.py (tests/ngc/feed_job.toml):

1. the rewrite succeeds, or is refused with exit 2 and a message naming what (a program that
   reads its own feed, #<_feed>);
2. the rewritten program's motion is the input's: trochomill's own trace of both
   (check-gcode --trace), move by move, every new move of the same kind as the input move it
   lies in (arcs: the same centre, axis and sense), its end on that move within 1e-6 mm, the
   input move's end reached exactly (1e-6 mm); only feeds differ, and a feed is either the
   input's or within the job's [machine] min_feed .. max_feed;
3. every line of the input is in the output, unchanged, except blocks whose F word or
   motion words changed (the output's extra lines are the pieces of split moves);
4. LinuxCNC's own interpreter reads every rewritten program as trochomill does (peer_test.py
   on the outputs: move by move, ends within 1e-6 mm, feeds equal) where LinuxCNC is
   installed (else that part is skipped and said).

    /usr/bin/python3 tests/ngc/feed_peer_test.py TROCHOMILL
"""
import difflib
import json
import math
import re
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
OPTIONS = ["--offset", "G54=101.6,50.8,-25.4", "--offset", "G55=254,127,-12.7",
           "--offset", "G56=-50.8,76.2,0", "--offset", "G59.3=25.4,25.4,0",
           "--g28", "0,0,50.8", "--g30", "254,25.4,38.1",
           "--tool-table", os.path.join(HERE, "tools.tbl"), "-I", os.path.join(HERE, "lib")]
JOB = os.path.join(HERE, "feed_job.toml")
MIN_FEED, MAX_FEED = 60.0, 2400.0  # feed_job.toml's [machine]
# Split points are written to 1e-6 mm (9 places in G91), so the new ends lie on the input's
# moves to that; 2e-6 leaves room for the trace's own 9 printed places.
TOL = 2e-6
REFUSED = {"predefined_params.ngc": "#<_feed>"}


def trace(troch, prog):
    out = subprocess.run([troch, "check-gcode", prog, "--trace"] + OPTIONS,
                         capture_output=True, text=True)
    if out.returncode != 0:
        raise RuntimeError("check-gcode %s: %s" % (prog, out.stderr.strip()))
    moves = []
    for line in out.stdout.splitlines():
        w = line.replace("; ", "").split()
        m = {"kind": w[0], "end": [float(v[1:]) for v in w[1:4]], "feed": None}
        for x in w[4:]:
            if x.startswith("ABC:") or x.startswith("UVW:"):
                m["extra"] = m.get("extra", []) + [float(c) for c in x[4:].split(",")]
            elif x[0] == "C":
                m["centre"] = [float(c) for c in x[1:].split(",")]
            elif x[0] == "A":
                m["axis"] = [float(c) for c in x[1:].split(",")]
            elif x[0] == "F":
                m["feed"] = float(x[1:])
        moves.append(m)
    return moves


def on_move(p, start, m):
    """Distance of point p from input move m that starts at `start`."""
    if m["kind"] in ("G2", "G3"):
        c, a = m["centre"], m["axis"]
        n = a.index(max(a, key=abs))
        d = [p[k] - c[k] for k in range(3)]
        r_p = math.hypot(*[d[k] for k in range(3) if k != n])
        ds = [start[k] - c[k] for k in range(3)]
        r_s = math.hypot(*[ds[k] for k in range(3) if k != n])
        return abs(r_p - r_s)  # on the cylinder of the arc (the helix's height is checked
        # by the pieces ending where the input ends)
    # A line: distance from the segment.
    v = [m["end"][k] - start[k] for k in range(3)]
    w = [p[k] - start[k] for k in range(3)]
    vv = sum(x * x for x in v)
    t = 0.0 if vv == 0 else max(0.0, min(1.0, sum(v[k] * w[k] for k in range(3)) / vv))
    return math.dist(p, [start[k] + t * v[k] for k in range(3)])


def same_motion(a, b):
    """Problems of output trace b against input trace a (empty: b refines a)."""
    problems = []
    j = 0
    prev_a = prev_b = [0.0, 0.0, 0.0]
    for i, m in enumerate(a):
        while True:
            if j >= len(b):
                return ["the output ends before input move %d" % (i + 1)]
            n = b[j]
            j += 1
            if n["kind"] != m["kind"]:
                return ["input move %d (%s) became %s" % (i + 1, m["kind"], n["kind"])]
            if m["kind"] in ("G2", "G3"):
                # The trace gives the centre at the start's height along the axis: compare
                # it in the plane.
                ax = m["axis"].index(max(m["axis"], key=abs))
                if max(abs(n["centre"][k] - m["centre"][k]) for k in range(3) if k != ax) > TOL \
                        or n["axis"] != m["axis"]:
                    return ["input move %d: an arc piece about another centre" % (i + 1)]
            d = on_move(n["end"], prev_a, m)
            if d > TOL:
                return ["input move %d: a piece ends %.3g mm off it" % (i + 1, d)]
            if m["kind"] != "G0" and m["feed"] is not None:
                f = n["feed"]
                kept = abs(f - m["feed"]) <= 1e-6 * m["feed"]
                if not kept and not (MIN_FEED * (1 - 1e-9) <= f <= MAX_FEED * (1 + 1e-9)):
                    problems.append("input move %d: feed %g outside %g .. %g"
                                    % (i + 1, f, MIN_FEED, MAX_FEED))
            if math.dist(n["end"], m["end"]) <= TOL:
                # A B C U V W reach the input's values where the input move ends.
                if m.get("extra") != n.get("extra") and max(
                        abs(u - v) for u, v in zip(m.get("extra", [0.0] * 6),
                                                   n.get("extra", [0.0] * 6))) > TOL:
                    return ["input move %d: A B C U V W %s became %s"
                            % (i + 1, m.get("extra"), n.get("extra"))]
                break
        prev_a = m["end"]
        prev_b = n["end"]
    if j != len(b):
        problems.append("%d output moves beyond the input's end" % (len(b) - j))
    del prev_b
    return problems


WORD = re.compile(r"[XYZIJKRPF@^][-+]?(#<[^>]*>|#+\d+|[\d.]+)")  # @ ^: LinuxCNC's polar words


def residue(line):
    """A block without its motion and feed words (what the rewrite may change), spaces out,
    upper case; comments kept as they are."""
    code, comment = line, ""
    for mark in ("(", ";"):
        if mark in code:
            code, comment = code[:code.index(mark)], code[code.index(mark):] + comment
    code = code.replace(" ", "").replace("\t", "").upper()
    # Bracketed values, innermost first, then the plain words.
    while True:
        new = re.sub(r"\[[^\[\]]*\]", "0", code)
        if new == code:
            break
        code = new
    return WORD.sub("", code), comment


def lines_kept(src, out):
    """Every input line is in the output, in order: unchanged, or with only motion and feed
    words changed (its other words and comments kept); the output's extra lines are pieces of
    split moves (G1/G2/G3 with motion and feed words only). None when so, else what is wrong."""
    a = open(src, newline="").read().splitlines()
    b = open(out, newline="").read().splitlines()
    sm = difflib.SequenceMatcher(a=a, b=b, autojunk=False)
    for op, i1, i2, j1, j2 in sm.get_opcodes():
        if op == "equal":
            continue
        i = i1
        for line in b[j1:j2]:
            if i < i2 and residue(line) == residue(a[i]):
                i += 1
            elif residue(line) not in (("G1", ""), ("G2", ""), ("G3", "")):
                return "output line '%s' is neither an input block nor a piece of one" % line
        if i != i2:
            return "input lines %d-%d are gone: %s" % (i + 1, i2, a[i:i2])
    return None


def main():
    troch = os.path.abspath(sys.argv[1])
    programs = sorted(os.path.join(HERE, "programs", f)
                      for f in os.listdir(os.path.join(HERE, "programs")) if f.endswith(".ngc"))
    # Under the sanitizers (TROCHOMILL_CORPUS_STRIDE=12 from tests/CMakeLists.txt) every
    # twelfth program: the Release suite checks the motion of all, the sanitizers look for
    # memory and undefined behaviour in a twelfth of them (Ngc.MovesEqualLinuxCncsOnTheCorpus reads
    # the whole corpus under the sanitizers).
    stride = int(os.environ.get("TROCHOMILL_CORPUS_STRIDE", "1"))
    # With a stride, a program whose moves the rewrite splits is always among them (the sample
    # alone may split almost nothing as the corpus grows, and part 2 would test little):
    # inch_units.ngc, 27 lines of pieces in 2.7 s (Release); comp_outside_rectangle.ngc and
    # plane_g18_g19_arcs.ngc split as many but take 6.7 s each, 30 s under the sanitizers.
    always = ("inch_units.ngc",)
    sample = programs[::stride]
    programs = sample + [p for p in programs
                         if os.path.basename(p) in always and p not in sample]
    failures = 0
    outputs = []
    split_total = 0
    with tempfile.TemporaryDirectory() as tmp:
        for prog in programs:
            name = os.path.basename(prog)
            out = os.path.join(tmp, name)
            # Three rounds of scheduling: what is tested is the rewrite (motion, lines, LinuxCNC),
            # not the chip the rounds converge to (tests/feed_test.cpp); the whole test 117 s
            # to 50 s in a Release build.
            run = subprocess.run([troch, "optimize-feed", prog, "--job", JOB, "--rounds", "3",
                                  "-I", os.path.join(HERE, "lib"), "-o", out,
                                  "--json", out + ".json"],
                                 capture_output=True, text=True)
            problems = []
            if name in REFUSED:
                if run.returncode != 2 or REFUSED[name] not in run.stderr:
                    problems.append("expected exit 2 naming %s, got %d: %s"
                                    % (REFUSED[name], run.returncode, run.stderr.strip()))
                elif os.path.exists(out):
                    problems.append("an output was written for a refused program")
            elif run.returncode != 0:
                problems.append("exit %d: %s" % (run.returncode, run.stderr.strip()))
            else:
                problems += same_motion(trace(troch, prog), trace(troch, out))
                kept = lines_kept(prog, out)
                if kept:
                    problems.append(kept)
                outputs.append(out)
                split_total += json.load(open(out + ".json"))["lines_added"]
            if problems:
                failures += 1
                print("FAIL %s\n  %s" % (name, "\n  ".join(problems)))
            else:
                print("ok   %s" % name)
        print("%d programs, %d lines of pieces added, %d failed" % (len(programs), split_total,
                                                                     failures))
        # The rewrite must split moves somewhere, or part 2 tests nothing.
        if split_total < 100 // stride:
            print("FAIL only %d lines of pieces over the corpus" % split_total)
            failures += 1
        peer = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "peer_test.py"), troch]
                              + outputs, capture_output=True, text=True)
        print(peer.stdout.strip().splitlines()[-1] if peer.stdout.strip() else peer.stderr)
        if peer.returncode == 77:
            print("LinuxCNC is not installed: the rewritten programs were not read by it")
        elif peer.returncode != 0:
            print(peer.stdout)
            failures += 1
    return 1 if failures else 0


sys.exit(main())
