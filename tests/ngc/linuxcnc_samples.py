#!/usr/bin/python3
"""LinuxCNC's own sample programs (Debian linuxcnc-uspace, /usr/share/linuxcnc/ncfiles, written
by LinuxCNC's authors) read by trochomill and by LinuxCNC's interpreter, compared move by move
with tests/ngc/peer_test.py. Every program in MATCH must give LinuxCNC's moves; the tally of
the others (LinuxCNC refuses them too, or they use what trochomill does not read yet: lathe
cycles, probing, splines, threading) is printed. A program that newly matches is said, to
be added to MATCH.

    /usr/bin/python3 tests/ngc/linuxcnc_samples.py TROCHOMILL

Exit 77 (a skip) without LinuxCNC or its samples."""
import glob
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SAMPLES = "/usr/share/linuxcnc/ncfiles"
# Read with LinuxCNC's moves (2026-12: 38 of the 44 that LinuxCNC runs with this machine).
MATCH = """3D_Chips 3dtest arcspiral cds comp-g1 comp311 comp311_2 factorial flowsnake g20sub g881
g881min g882 gmoccapy_2_tools_with_cutter_radius_compensation gridprobe hole-circle m250 b-index daisy systems threading
m61demo m6demo m6remap m70m72-demo m73-demo m75 m76 offsets polar retval roparams smartprobe
spiral testm6fail toplevel tort touchoff""".split()

programs = sorted(glob.glob(os.path.join(SAMPLES, "*.ngc")))
if not programs:
    print("LinuxCNC's sample programs (%s) are not installed" % SAMPLES, file=sys.stderr)
    sys.exit(77)
run = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "peer_test.py"), sys.argv[1]]
                     + programs, capture_output=True, text=True)
if run.returncode == 77:
    print(run.stderr.strip())
    sys.exit(77)
result, cur = {}, None
for line in run.stdout.splitlines():
    if line.startswith("ok   "):
        result[line[5:]] = []
        cur = None
    elif line.startswith("FAIL "):
        cur = line[5:]
        result[cur] = ["FAIL"]
    elif line.startswith("  ") and cur:
        result[cur].append(line.strip())
missing = [p for p in MATCH if p + ".ngc" not in result]
broken = [p for p in MATCH if result.get(p + ".ngc")]
new = [n for n, r in result.items() if not r and n[:-4] not in MATCH]
refused = [n for n, r in result.items() if any(x.startswith("LinuxCNC:") for x in r)]
differ = [n for n, r in result.items() if r and n not in refused]
print("%d samples: %d read as LinuxCNC reads them, %d refused by LinuxCNC as well, %d differ"
      % (len(result), len(result) - len(refused) - len(differ), len(refused), len(differ)))
for n in differ:
    print("  differs: %s: %s" % (n, result[n][1] if len(result[n]) > 1 else ""))
for n in new:
    print("  now read as LinuxCNC reads it (add it to MATCH): " + n)
for p in missing:
    print("FAIL %s: not among the samples" % p)
for p in broken:
    print("FAIL %s: %s" % (p, "; ".join(result[p][1:])))
sys.exit(1 if missing or broken else 0)
