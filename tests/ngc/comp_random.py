#!/usr/bin/python3
"""Cutter radius compensation against LinuxCNC's on random contours: COUNT programs from SEED,
each a G41.1/G42.1 contour of 2-7 random moves (lines, R arcs of either sense and size, Z
moves that wait in the queue, rapids) with a random diameter. Each must be refused by both
interpreters or give the same moves (peer_test.py's comparison).

    /usr/bin/python3 tests/ngc/comp_random.py TROCHOMILL SEED COUNT

Exit 77 (a skip) when LinuxCNC is not installed, 1 on a difference (the program is kept and
named).
"""
import os
import random
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))


def program(rng):
    lines = ["G21 G17 G90 G94", "G0 Z5", "G0 X0 Y0", "F500", "G1 Z-1",
             "%s D%g" % (rng.choice(["G41.1", "G42.1"]), rng.choice([2, 4, 6, 10, 20]))]
    x = y = 0.0
    for _ in range(rng.randint(2, 7)):
        scale = rng.choice([5, 40])  # short moves make deep corners
        nx, ny = round(x + rng.uniform(-scale, scale), 3), round(y + rng.uniform(-scale, scale), 3)
        t = rng.random()
        if t < 0.55:
            lines.append("G1 X%g Y%g" % (nx, ny))
        elif t < 0.8:
            chord = ((nx - x) ** 2 + (ny - y) ** 2) ** 0.5
            r = round(rng.uniform(chord / 2 + 0.5, chord * 2 + 1), 3) * rng.choice([1, -1])
            lines.append("%s X%g Y%g R%g" % (rng.choice(["G2", "G3"]), nx, ny, r))
        elif t < 0.9:
            lines.append("G1 Z%g" % round(rng.uniform(-3, 0), 2))
            continue
        else:
            lines.append("G0 X%g Y%g" % (nx, ny))
        x, y = nx, ny
    lines += ["G40", "G0 X0 Y0", "M2"]
    return "\n".join(lines) + "\n"


def main():
    troch, seed, count = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    rng = random.Random(seed)
    tmp = tempfile.mkdtemp(prefix="trochomill-comp-")
    same = refused = 0
    for i in range(count):
        path = os.path.join(tmp, "comp%d.ngc" % i)
        with open(path, "w") as f:
            f.write(program(rng))
        peer = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "linuxcnc_canon.py"), path],
                              capture_output=True, text=True)
        if peer.returncode == 77:
            print(peer.stderr.strip())
            return 77
        ours = subprocess.run([troch, "check-gcode", path], capture_output=True, text=True)
        peer_refused = peer.returncode != 0 or peer.stdout.startswith("error")
        if peer_refused or ours.returncode != 0:
            if peer_refused and ours.returncode == 2:
                refused += 1
                os.remove(path)
                continue
            print("DIFFERENT %s\n  LinuxCNC: %s\n  trochomill: %s" % (
                path, peer.stdout.strip().splitlines()[-1] if peer_refused else "runs it",
                ours.stderr.strip() if ours.returncode else "runs it"))
            return 1
        cmp = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "peer_test.py"), troch, path],
                             capture_output=True, text=True)
        if cmp.returncode != 0:
            print("DIFFERENT %s\n%s" % (path, cmp.stdout))
            return 1
        same += 1
        os.remove(path)
    print("%d contours: %d with the same moves, %d refused by both" % (count, same, refused))
    os.rmdir(tmp)
    return 0


sys.exit(main())
