#!/usr/bin/python3
"""LinuxCNC's own interpreter (Debian linuxcnc-uspace's Python module `gcode`, the interpreter
AXIS previews with) run on an NC program: prints every canonical move in machine coordinates
(mm, full double precision), in the format of `trochomill check-gcode --trace`, so the two can
be compared move by move.

    /usr/bin/python3 tests/ngc/linuxcnc_canon.py PROGRAM [--var FILE] [--tools FILE]

--var: a LinuxCNC parameter file (work offsets, G28/G30 positions, mm: the module starts its
interpreter in mm); --tools: a tool table, lines "T<n> Z<length mm> D<diameter mm>". Positions and feeds reach
the canon in inches and go out in mm.
Exit 77 when the module is missing (a skip for CTest).
"""
import math
import os
import subprocess
import sys
import tempfile

try:
    import gcode  # noqa: E402  (Debian: /usr/lib/python3/dist-packages)
except ImportError:
    print("LinuxCNC's Python module 'gcode' is not installed (Debian linuxcnc-uspace)",
          file=sys.stderr)
    sys.exit(77)

IN = 25.4  # the module reports inches
TMP = tempfile.TemporaryDirectory()  # the parameter file LinuxCNC reads and writes; removed at exit
# LinuxCNC 2.9's interpreter keeps its tool data in $HOME/.tool.mmap, truncated and rewritten
# by every run: runs at once (the tests run in parallel) would share it. Each run its own.
os.environ["HOME"] = TMP.name


class Canon:
    def __init__(self, parameter_file, tools):
        self.parameter_file = parameter_file
        self.tools = tools
        self.lineno = 0
        self.plane = 1
        self.feed = 0.0
        self.g5x = [0.0, 0.0, 0.0]
        self.g92 = [0.0, 0.0, 0.0]
        # The axes besides X Y Z (A B C degrees, U V W mm): their offsets and current values.
        self.g5x_extra = [0.0] * 6
        self.g92_extra = [0.0] * 6
        self.extra = [0.0] * 6
        self.rotation = 0.0
        self.state = None
        self.per_rev = False  # G95, from the interpreter's comment (its state lags a line)
        self.spindle = 0.0
        self.moves = []

    # What the interpreter asks.
    def get_tool(self, pocket):
        length = self.tools.get(pocket, (0.0, 0.0))[0]  # mm: the interpreter's user units here
        return (pocket, 0.0, 0.0, length, 0, 0, 0, 0, 0, 0, 0.0, 0, 0, 0)

    def get_external_angular_units(self):
        return 1.0

    def get_external_length_units(self):
        return 1.0

    def get_axis_mask(self):
        return 0x1FF  # X Y Z A B C U V W

    def get_block_delete(self):
        return False

    def check_abort(self):
        return False

    # What it says.
    def next_line(self, st):
        self.state = st
        self.lineno = st.sequence_number

    def set_g5x_offset(self, index, x, y, z, *rest):
        self.g5x = [x * IN, y * IN, z * IN]
        if len(rest) >= 6:
            self.g5x_extra = extra_mm(rest)

    def set_g92_offset(self, x, y, z, *rest):
        self.g92 = [x * IN, y * IN, z * IN]
        if len(rest) >= 6:
            self.g92_extra = extra_mm(rest)

    def note_extra(self, rest):
        # A B C U V W of a move (program coordinates: rotary in degrees, U V W in inches) in
        # machine coordinates.
        if len(rest) >= 6:
            e = extra_mm(rest)
            self.extra = [e[k] + self.g92_extra[k] + self.g5x_extra[k] for k in range(6)]

    def set_xy_rotation(self, theta):
        self.rotation = theta

    def set_plane(self, plane):
        self.plane = plane

    def set_feed_rate(self, rate):
        self.feed = rate * IN

    def to_machine(self, x, y, z):
        x, y, z = x * IN + self.g92[0], y * IN + self.g92[1], z * IN + self.g92[2]
        t = math.radians(self.rotation)
        x, y = x * math.cos(t) - y * math.sin(t), x * math.sin(t) + y * math.cos(t)
        return x + self.g5x[0], y + self.g5x[1], z + self.g5x[2]

    def feed_now(self):
        # G95 (units per revolution): the canon rate times the spindle speed.
        return self.feed * self.spindle if self.per_rev else self.feed

    def comment(self, text):
        if text.startswith("interpreter: feed mode set to"):
            self.per_rev = "revolution" in text

    def set_spindle_rate(self, *args):
        self.spindle = args[-1] if len(args) > 1 else args[0]

    def straight_traverse(self, x, y, z, *rest):
        self.note_extra(rest)
        self.moves.append(("G0",) + self.to_machine(x, y, z) + (None, self.lineno, list(self.extra)))

    def straight_feed(self, x, y, z, *rest):
        self.note_extra(rest)
        self.moves.append(("G1",) + self.to_machine(x, y, z)
                          + (self.feed_now(), self.lineno, list(self.extra)))

    def straight_probe(self, x, y, z, *rest):
        # A probing move (G38.x) as a feed move to its end, as trochomill reads it.
        self.straight_feed(x, y, z, *rest)

    def rigid_tap(self, x, y, z, *rest):
        # G33.1: in to the point and back out, as LinuxCNC's preview draws it.
        back = self.moves[-1][1:4] if self.moves else None
        self.straight_feed(x, y, z)
        if back is not None:
            self.moves.append(("G1",) + tuple(back) + (self.feed_now(), self.lineno,
                                                      list(self.extra)))

    def arc_feed(self, first_end, second_end, first_axis, second_axis, rotation, axis_end, *rest):
        self.note_extra(rest)
        # CANON_PLANE: 1 XY (first X, second Y, axis Z), 2 YZ (Y, Z, X), 3 XZ (Z, X, Y).
        if self.plane == 1:
            end = (first_end, second_end, axis_end)
            centre = (first_axis, second_axis, None)
            axis = (0, 0, 1)
        elif self.plane == 2:
            end = (axis_end, first_end, second_end)
            centre = (None, first_axis, second_axis)
            axis = (1, 0, 0)
        else:
            end = (second_end, axis_end, first_end)
            centre = (second_axis, None, first_axis)
            axis = (0, 1, 0)
        self.moves.append(("G3" if rotation > 0 else "G2",) + self.to_machine(*end)
                          + (self.feed_now(), self.lineno, list(self.extra),
                             machine_centre(self, centre), axis, rotation))

    def __getattr__(self, name):
        # Every other canonical call (spindle, coolant, comments, dwell, tool change...).
        if name.startswith("__"):
            raise AttributeError(name)
        return lambda *args: None


def extra_mm(values):
    """A B C (degrees, as they are) and U V W (inches to mm) of a canonical call."""
    return [values[k] * (IN if k >= 3 else 1.0) for k in range(6)]


def rs274_extra(values, mm):
    """A B C U V W (degrees, mm) of an rs274 line's values after X Y Z: this build prints A B C
    only (its machine has no U V W), in the program's units."""
    v = list(values[:6]) + [0.0] * (6 - len(values[:6]))
    return [w * (mm if k >= 3 else 1.0) for k, w in enumerate(v)]


def run_rs274(program, var, tools):
    """The standalone interpreter `rs274 -g` (4 decimals): for programs that use the tool
    table, which this Debian build's Python module crashes on. Its external units are inches:
    the var file and the tool lengths and diameters go to it in inches; it prints in the
    program's units (USE_LENGTH_UNITS: mm, or inches after G20)."""
    import re
    import shutil
    exe = shutil.which("rs274")
    if exe is None:
        print("rs274 (Debian linuxcnc-uspace) is not installed", file=sys.stderr)
        sys.exit(77)
    tmp = TMP.name
    vfile = os.path.join(tmp, "p.var")
    with open(vfile, "w") as f:
        if var:
            for line in open(var):
                n, v = line.split()
                f.write("%s\t%.12f\n" % (n, float(v) / IN))
    tfile = os.path.join(tmp, "t.tbl")
    with open(tfile, "w") as f:
        for t, (z, d) in sorted(tools.items()):
            f.write("T%d P%d Z%.12f D%.12f\n" % (t, t, z / IN, d / IN))
    run = subprocess.run([exe, "-t", tfile, "-v", vfile, "-g", program], capture_output=True,
                         text=True, stdin=subprocess.DEVNULL)
    out = run.stdout
    # rs274 stops at an error and says why on stderr (then its output is a partial program).
    said = [l for l in run.stderr.splitlines() if l.strip() and l.strip() != "executing"]
    if said:
        print("error: " + said[0])
        sys.exit(1)
    canon = Canon(vfile, tools)
    plane = "XY"
    mm = 1.0  # mm per printed unit: rs274 prints in the program's units (G20: inches)
    call = re.compile(r"^\s*\d+ N\S*\s+([\w.]+)\((.*)\)\s*$")  # SPINDLE.0.WAIT_ORIENT_COMPLETE
    for line in out.splitlines():
        m = call.match(line)
        if not m:
            if line.strip() and line.strip() != "executing":
                print("error: " + line)
                sys.exit(1)
            continue
        name, args = m.group(1), m.group(2)
        nums = [float(a) for a in re.findall(r"-?\d+\.\d+|-?\d+", args.split("CANON_")[0])] \
            if "CANON_" not in args else []
        # Values reach the Canon methods in inches (they scale by IN).
        if name == "USE_LENGTH_UNITS":
            mm = IN if "INCHES" in args else 1.0
        elif name == "SET_G5X_OFFSET":
            canon.g5x = [v * mm for v in nums[1:4]]
            canon.g5x_extra = rs274_extra(nums[4:], mm)
        elif name == "SET_G92_OFFSET":
            canon.g92 = [v * mm for v in nums[0:3]]
            canon.g92_extra = rs274_extra(nums[3:], mm)
        elif name == "SET_XY_ROTATION":
            canon.rotation = nums[0]
        elif name == "SELECT_PLANE":
            plane = args.replace("CANON_PLANE_", "")
            canon.plane = {"XY": 1, "YZ": 2, "XZ": 3}[plane]
        elif name == "SET_FEED_RATE":
            canon.feed = nums[0] * mm
        elif name == "SET_FEED_MODE":
            canon.per_rev = int(nums[1]) == 1
        elif name == "SET_SPINDLE_SPEED":
            canon.spindle = nums[-1]
        elif name in ("STRAIGHT_TRAVERSE", "STRAIGHT_FEED", "STRAIGHT_PROBE"):
            x, y, z = (v * mm / IN for v in nums[0:3])
            # A B C U V W in the canon's units (inches for U V W, as the module gives them).
            rest = [v / IN if k >= 3 else v for k, v in enumerate(rs274_extra(nums[3:], mm))]
            canon.lineno = 0
            if name == "STRAIGHT_TRAVERSE":
                canon.straight_traverse(x, y, z, *rest)
            else:
                canon.straight_feed(x, y, z, *rest)
        elif name == "RIGID_TAP":
            x, y, z = (v * mm / IN for v in nums[0:3])
            canon.lineno = 0
            canon.rigid_tap(x, y, z)
        elif name == "ARC_FEED":
            v = nums
            k = mm / IN
            rest = [w / IN if j >= 3 else w for j, w in enumerate(rs274_extra(v[6:], mm))]
            canon.arc_feed(v[0] * k, v[1] * k, v[2] * k, v[3] * k, int(v[4]), v[5] * k, *rest)
    return canon


def main():
    args = sys.argv[1:]
    program = args[0]
    var = None
    tools = {}
    if "--var" in args:
        var = args[args.index("--var") + 1]
    if "--tools" in args:
        with open(args[args.index("--tools") + 1]) as f:
            for line in f:
                words = line.split()
                if not words:
                    continue
                t = int(words[0][1:])
                z = d = 0.0
                for w in words[1:]:
                    if w[0] in "Zz":
                        z = float(w[1:])
                    elif w[0] in "Dd":
                        d = float(w[1:])
                tools[t] = (z, d)
    if "--rs274" in args:
        canon = run_rs274(program, var, tools)
        print_moves(canon)
        return
    tmp = TMP.name
    param = os.path.join(tmp, "p.var")
    with open(param, "w") as f:
        if var:
            with open(var) as v:
                f.write(v.read())
    canon = Canon(param, tools)
    # "G21" first: the module's canon starts without units, and converts to inches only once
    # a program has set mm (a feed on the G21 line itself would otherwise go through unscaled).
    result, seq = gcode.parse(program, canon, "G21", "")
    if result > gcode.MIN_ERROR:
        print("error: line %d: %s" % (seq, gcode.strerror(result)))
        sys.exit(1)
    print_moves(canon)


def print_moves(canon):
    for m in canon.moves:
        kind, x, y, z, feed, line, extra = m[:7]
        s = "%s X%.9f Y%.9f Z%.9f" % (kind, x, y, z)
        if kind in ("G2", "G3"):
            centre, axis, rotation = m[7:]
            s += " C%s,%s,%s A%d,%d,%d R%d" % (
                tuple("%.9f" % c if c is not None else "-" for c in centre) + axis + (rotation,))
        s += " ABC:%.9f,%.9f,%.9f UVW:%.9f,%.9f,%.9f" % tuple(extra)
        if feed is not None:
            s += " F%.9f" % feed
        s += " L%d" % line
        print(s)


def machine_centre(canon, centre):
    # The centre's two plane coordinates through the offsets active at the arc (XY rotation
    # only turns XY).
    c = [v if v is not None else 0.0 for v in centre]
    x, y, z = canon.to_machine(*c)
    return tuple(None if centre[i] is None else (x, y, z)[i] for i in range(3))


main()
