#!/usr/bin/python3
"""NC programs written by others (tests/ngc/corpus; SOURCES.tsv names each one's repository,
commit, licence and the CAM or person that wrote it) read by trochomill and by LinuxCNC's
interpreter, compared move by move with tests/ngc/peer_test.py on a machine whose offsets are
zero (programs written for other machines) and the corpus's tool table.

Some programs LinuxCNC refuses as they are: without M2, M30 or a closing % at the end
(NEEDS_END: compared with M2 appended to a copy; trochomill reads them with a warning), with a
closing % and no opening one (NEEDS_PERCENT: compared with % prepended), or for a reason of
their own (LINUXCNC_REFUSES, with LinuxCNC's message). Every other program must read with
LinuxCNC's moves, but those of KNOWN (each with its reason); the share of the programs
LinuxCNC runs that read so must be at least 95 %.

    /usr/bin/python3 tests/ngc/corpus_test.py TROCHOMILL

Exit 77 (a skip) without LinuxCNC."""
import os
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
CORPUS = os.path.join(HERE, "corpus")
NEEDS_END = """bcnc__sample camotics__heart camotics__heart_cutout camotics__slant_test cncjs__jsdc
ugs__ruler ugs__ugs ugs__window""".split()
NEEDS_PERCENT = """camotics__compass camotics__compass_bottom camotics__compass_text camotics__compass_top
camotics__locket_inside camotics__locket_outside""".split()
LINUXCNC_REFUSES = {
    "cncjs__Circle_Diamond_Square_Calibration": "Radius to end of arc differs",
    "cncjs__helical-thread-milling": "Length of cutter compensation entry move",
    "linuxcnc__G6_Curva_Stella_1": "Unknown g code used",  # G6.2: LinuxCNC after 2.9
    "pcb2gcode__example_board_al_mach3_back": "Unknown m code used: M40",
    "pcb2gcode__multivibrator_pre_post_milling_gcode_back": "Unknown word starting with r",
}
# LinuxCNC's Python module runs these with F0 (its preview); its interpreter proper (rs274,
# and the machine) refuses a feed move without a feed, as trochomill does.
REFUSED_BY_BOTH = {
    "camotics__mt_kazbegi_2013": "feed move with no feed rate",
    "camotics__sworn_brothers_llc": "feed move with no feed rate",
}
KNOWN = {
    # rs274 (the module crashes on its tool change) lets the probe G38.2 stop at a trip point
    # of its own; trochomill, as LinuxCNC's preview, takes a probe move to its end.
    "pcb2gcode__example_board_al_linuxcnc_back": "G38.2: where the probe stops",
}


def main():
    troch = sys.argv[1]
    names = sorted(f[:-4] for f in os.listdir(CORPUS) if f.endswith(".ngc"))
    # Under the sanitizers (TROCHOMILL_CORPUS_STRIDE from tests/CMakeLists.txt) every n-th
    # program, for memory and undefined behaviour; the Release suite reads them all and
    # holds the share.
    stride = int(os.environ.get("TROCHOMILL_CORPUS_STRIDE", "1"))
    names = names[::stride]
    listed = set(f[:-4] for f in (l.split("\t")[0] for l in open(os.path.join(CORPUS, "SOURCES.tsv")))
                 if f.endswith(".ngc"))
    unlisted = [n for n in names if n not in listed]
    tmp = tempfile.TemporaryDirectory()
    paths = []
    for n in names:
        src = os.path.join(CORPUS, n + ".ngc")
        if n in NEEDS_END or n in NEEDS_PERCENT:
            text = open(src, errors="replace").read()
            text = text + "\nM2\n" if n in NEEDS_END else "%\n" + text
            src = os.path.join(tmp.name, n + ".ngc")
            open(src, "w").write(text)
        paths.append(src)
    run = subprocess.run(["/usr/bin/python3", os.path.join(HERE, "peer_test.py"), troch,
                          "--zero-machine", "--tools", os.path.join(CORPUS, "tools.tbl")] + paths,
                         capture_output=True, text=True)
    if run.returncode == 77:
        print(run.stderr.strip())
        return 77
    result, cur = {}, None
    for line in run.stdout.splitlines():
        if line.startswith("ok   "):
            result[line[5:-4]] = []
        elif line.startswith("FAIL "):
            cur = line[5:-4]
            result[cur] = []
        elif line.startswith("  ") and cur:
            result[cur].append(line.strip())
    failures = []
    for n in unlisted:
        failures.append("%s: not in SOURCES.tsv (its source and licence)" % n)
    same = refused = 0
    for n in names:
        r = result.get(n)
        if r is None:
            failures.append("%s: no result" % n)
        elif n in LINUXCNC_REFUSES:
            refused += 1
            if not any(x.startswith("LinuxCNC:") and LINUXCNC_REFUSES[n] in x for x in r):
                failures.append("%s: LinuxCNC no longer refuses it with '%s': %s"
                                % (n, LINUXCNC_REFUSES[n], "; ".join(r) or "ok"))
        elif n in REFUSED_BY_BOTH:
            refused += 1
            if not any(x.startswith("trochomill:") and REFUSED_BY_BOTH[n] in x for x in r):
                failures.append("%s: trochomill does not refuse it with '%s': %s"
                                % (n, REFUSED_BY_BOTH[n], "; ".join(r) or "ok"))
        elif not r:
            same += 1
            if n in KNOWN:
                print("now read as LinuxCNC reads it (remove it from KNOWN): " + n)
        elif n not in KNOWN:
            failures.append("%s: %s" % (n, "; ".join(r)))
    runs = len(names) - refused
    share = same / runs if runs else 0.0
    print("%d programs by others: LinuxCNC runs %d (%d of them once completed with M2 or %%), "
          "%d read with its moves (%.1f %%), %d differ for a known reason; %d refused by "
          "LinuxCNC" % (len(names), runs, len(NEEDS_END) + len(NEEDS_PERCENT), same,
                        100 * share, runs - same, refused))
    if share < 0.95 and stride == 1:
        failures.append("%.1f %% read as LinuxCNC reads them, below 95 %%" % (100 * share))
    for f in failures:
        print("FAIL " + f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
