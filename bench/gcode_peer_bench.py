#!/usr/bin/python3
"""Interpreter throughput, trochomill against LinuxCNC's rs274, side by side on the same files.

    /usr/bin/python3 bench/gcode_peer_bench.py build/bin/trochomill [MB]

Programs (written to a temporary folder): plain G1 moves (MB megabytes, default 100), a while
loop, a subroutine called from a repeat loop (2 and 2.5 million blocks) and a contour run with
cutter compensation in a repeat loop (0.9 million blocks). Each tool runs each
program 3 times; the median wall time and the peak resident memory (from /usr/bin/time) are
printed. rs274 -g prints every canonical call; trochomill is timed both printing every move
(check-gcode --trace, the like-for-like figure) and reading only (check-gcode).
"""
import math
import os
import shutil
import statistics
import subprocess
import sys
import tempfile


def write_programs(d, mb):
    plain = os.path.join(d, "plain.ngc")
    with open(plain, "w") as f:
        f.write("G21 G90 G17 G94\nG0 X0 Y0 Z1\nG1 Z-1 F1000\n")
        size, i = 0, 0
        while size < mb * 1_000_000:
            line = "G1 X%.4f Y%.4f\n" % (50 * math.cos(i * 0.001) + i * 1e-4,
                                          50 * math.sin(i * 0.001))
            f.write(line)
            size += len(line)
            i += 1
        f.write("M2\n")
    loop = os.path.join(d, "loop.ngc")
    with open(loop, "w") as f:
        f.write("G21 G90 G17 G94\nG0 X0 Y0 Z1\nG1 Z-1 F1000\n#1 = 0\n"
                "o100 while [#1 LT 500000]\n  G1 X[#1 MOD 10] Y[#1 * 0.001]\n"
                "  #1 = [#1 + 1]\no100 endwhile\nM2\n")
    subs = os.path.join(d, "subs.ngc")
    with open(subs, "w") as f:
        f.write("G21 G90 G17 G94\no<step> sub\n  G1 X[#1 MOD 10] Y[#1 * 0.001]\n"
                "o<step> endsub\nG0 X0 Y0 Z1\nG1 Z-1 F1000\n#1 = 0\no100 repeat [500000]\n"
                "  o<step> call [#1]\n  #1 = [#1 + 1]\no100 endrepeat\nM2\n")
    comp = os.path.join(d, "comp.ngc")
    with open(comp, "w") as f:
        # A compensated contour (lines, an arc, convex and concave corners) entered and left
        # 100 000 times: 0.9 M blocks through cutter compensation.
        f.write("G21 G90 G17 G94\nG0 X-10 Y-10 Z1\nG1 Z-1 F1000\no100 repeat [100000]\n"
                "  G41.1 D6 G1 X0 Y0\n  G1 X40\n  G3 X50 Y10 R10\n  G1 Y30\n  G1 X25 Y20\n"
                "  G1 X0 Y30\n  G1 Y0\n  G40 G1 X-10 Y-10\no100 endrepeat\nM2\n")
    return [("plain %d MB" % mb, plain), ("while loop, 2.0 M blocks", loop),
            ("sub calls, 2.5 M blocks", subs), ("cutter compensation, 0.9 M blocks", comp)]


def run(cmd, cwd):
    times, mems = [], []
    for _ in range(3):
        r = subprocess.run(["/usr/bin/time", "-f", "%e %M"] + cmd, cwd=cwd,
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                           stdin=subprocess.DEVNULL, text=True)
        t, m = r.stderr.strip().splitlines()[-1].split()
        times.append(float(t))
        mems.append(int(m) / 1024)
    return statistics.median(times), max(mems)


def main():
    troch = os.path.abspath(sys.argv[1])
    mb = int(sys.argv[2]) if len(sys.argv) > 2 else 100
    rs274 = shutil.which("rs274")
    d = tempfile.mkdtemp()
    try:
        print("| program | trochomill | trochomill --trace | rs274 -g | ratio (rs274 / --trace) |")
        print("|---|---|---|---|---|")
        for name, prog in write_programs(d, mb):
            a = run([troch, "check-gcode", prog], d)
            b = run([troch, "check-gcode", prog, "--trace"], d)
            c = run([rs274, "-g", prog], d) if rs274 else None
            cs = "%.2f s, %.0f MB" % c if c else "not installed"
            ratio = "%.1f" % (c[0] / b[0]) if c else "-"
            print("| %s | %.2f s, %.0f MB | %.2f s, %.0f MB | %s | %s |"
                  % (name, a[0], a[1], b[0], b[1], cs, ratio))
    finally:
        shutil.rmtree(d)


main()
