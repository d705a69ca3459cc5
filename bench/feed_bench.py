#!/usr/bin/python3
"""optimize-feed: run time and time saved.

    /usr/bin/python3 bench/feed_bench.py build/bin/trochomill [BLOCKS]

1. The Wagih 2023 trochoidal slot program (20 cycles, `plan` of examples/wagih2023/
   trochoidal.toml in LinuxCNC's language) and the Pivkin 2025 example's program.
2. A third-party style adaptive-clearing program (written here as CAM systems write one: G1
   chords of 0.2 mm along constant-engagement loops that step sideways across a pocket,
   linking moves in air, a ramp entry) of BLOCKS blocks (default 100,000), 2.5D at one level.

For each: the wall time of optimize-feed (best of 3 for the small ones, 1 for the large), and
the programme's time before and after with the machine's acceleration (from its --json).
"""
import json
import math
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def adaptive_program(blocks):
    """Loops of radius 4 mm about a centre that steps 0.8 mm along +Y across a 60 mm pocket,
    each loop a circle of G1 chords of ~0.2 mm, rows 8 mm apart (linking in air at Z2)."""
    lines = ["(adaptive clearing, third-party style: G1 chords, constant step)",
             "G21 G90 G17 G94", "T1 M6", "S8000 M3", "G0 Z5", "G0 X-26 Y-5", "G0 Z1",
             "G1 Z-3 F300"]
    r, step, chord = 4.0, 0.8, 0.2
    per_loop = int(2 * math.pi * r / chord)
    x, y = -26.0, -5.0
    row = 0
    lines.append("G1 X%.4f Y%.4f F1200" % (x, y))
    while len(lines) < blocks:
        cy = y + r
        for k in range(1, per_loop + 1):
            a = -math.pi / 2 + 2 * math.pi * k / per_loop
            px = x + r * math.cos(a)
            py = cy + r * math.sin(a) + step * k / per_loop
            lines.append("G1 X%.4f Y%.4f" % (px, py))
        y += step
        if y > 60:  # next row: lift, move over, plunge in air below the stock
            row += 1
            x = -26.0 + 6.5 * (row % 9)
            y = -5.0
            lines += ["G0 Z2", "G0 X%.4f Y%.4f" % (x, y), "G1 Z-3 F300", "G1 Y-5 F1200"]
    lines += ["G0 Z5", "M5", "M30"]
    return "\n".join(lines) + "\n"


ADAPTIVE_JOB = """[tool]
diameter = 12.0
teeth = 3
helix_angle = 40.0
[slot]
width = 64.0
length = 64.0
depth = 3.0
[cutting]
feed_rate = 1200.0
spindle_speed = 8000.0
[machine]
dialect = "linuxcnc"
max_acceleration = 2000.0
max_feed = 4000.0
min_feed = 200.0
[path]
type = "linear"
step = 1.0
"""


def run(troch, prog, job, repeat):
    best = None
    summary = None
    for _ in range(repeat):
        with tempfile.TemporaryDirectory() as tmp:
            out, js = os.path.join(tmp, "out.ngc"), os.path.join(tmp, "s.json")
            t0 = time.perf_counter()
            subprocess.run([troch, "optimize-feed", prog, "--job", job, "-o", out, "--json", js],
                           check=True, capture_output=True)
            dt = time.perf_counter() - t0
            summary = json.load(open(js))
        best = dt if best is None else min(best, dt)
    return best, summary


def main():
    troch = os.path.abspath(sys.argv[1])
    blocks = int(sys.argv[2]) if len(sys.argv) > 2 else 100000
    with tempfile.TemporaryDirectory() as tmp:
        rows = []
        for name, job in (("Wagih 2023 trochoidal, 20 cycles", "examples/wagih2023/trochoidal.toml"),
                          ("Pivkin 2025 trochoidal", "examples/pivkin2025/trochoidal.toml")):
            job = os.path.join(ROOT, job)
            prog = os.path.join(tmp, "p.ngc")
            subprocess.run([troch, "plan", job, "--set", 'machine.dialect="linuxcnc"', "-o", prog],
                           check=True, capture_output=True)
            jl = os.path.join(tmp, "j.toml")
            open(jl, "w").write(open(job).read().replace('dialect = "sinumerik"',
                                                         'dialect = "linuxcnc"'))
            n = sum(1 for _ in open(prog))
            rows.append((name, n) + run(troch, prog, jl, 3))
        prog = os.path.join(tmp, "adaptive.ngc")
        open(prog, "w").write(adaptive_program(blocks))
        job = os.path.join(tmp, "adaptive.toml")
        open(job, "w").write(ADAPTIVE_JOB)
        n = sum(1 for _ in open(prog))
        rows.append(("adaptive clearing (generated)", n) + run(troch, prog, job, 1))
    print("| program | blocks | optimize-feed wall time (s) | time before (s) | after (s) | saved |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, n, dt, s in rows:
        print("| %s | %d | %.2f | %.1f | %.1f | %.1f %% |" % (
            name, n, dt, s["time_before_with_acceleration_s"], s["time_after_with_acceleration_s"],
            s["time_saved_percent"]))


main()
