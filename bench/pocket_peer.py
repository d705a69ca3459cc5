#!/usr/bin/env python3
"""Pocket clearing, side by side: trochomill's pocket planner against FreeCAD 0.20's Adaptive
clearing (libarea's Adaptive2d), on the same pocket, both programs measured by trochomill's
engagement kernel (`trochomill analyze --gcode`).

Usage: pocket_peer.py TROCHOMILL_BIN WORK_DIR [--job JOB.toml]

  TROCHOMILL_BIN  the trochomill executable (e.g. build/bin/trochomill)
  WORK_DIR        folder for the programs, the analyses and libarea's log (created if missing)
  --job           the pocket job (default: examples/pockets/plate.toml of the source tree, found
                  beside this script's folder or above the executable's build/bin)

The FreeCAD side is run headless: Adaptive2d is fed the job's boundary and islands as polygons
(read from the job's DXF with ezdxf, arcs as chords within 0.01 mm), with FreeCAD's defaults for
what the job does not say, and its output is turned into LinuxCNC G-code the way FreeCAD 0.20's
PathAdaptive.GenerateGCode does (straight-chord helix entry, cutting as G1, keep-tool-down links
as G0 at depth, other links lifted to the clearance height).

Exit code 77 (skipped) when FreeCAD's `area` module or ezdxf is missing.
"""
import argparse
import bisect
import csv
import json
import math
import os
import subprocess
import sys
import time
import tomllib

FREECAD_LIB = "/usr/lib/freecad-python3/lib"  # Debian's freecad-python3 package
SKIP = 77
ENGAGED_DEG = 0.5  # a sample cuts when its engagement exceeds this
ON_CIRCLE_MM = 0.05  # entry detection: a move's end on the helix circle within this

# ------------------------------------------------------------------------------------------------
# Inputs


def load_area():
    """FreeCAD's libarea binding, or None."""
    sys.path.append(FREECAD_LIB)
    try:
        import area  # noqa: PLC0415 (FreeCAD's module, found only on its path)
    except ImportError:
        return None
    return area


def find_job(script_dir, bin_path):
    """The default job: examples/pockets/plate.toml of the source tree."""
    rel = os.path.join("examples", "pockets", "plate.toml")
    for root in (os.path.join(script_dir, ".."),
                 os.path.join(os.path.dirname(os.path.abspath(bin_path)), "..", "..")):
        cand = os.path.normpath(os.path.join(root, rel))
        if os.path.isfile(cand):
            return cand
    sys.exit(f"pocket_peer: no {rel} beside this script or the executable: give --job")


def layer_polygons(ezdxf, doc, layer, chord_tol=0.01, join_tol=1e-4):
    """The closed contours of a DXF layer as polygons [(x, y), ...] (no repeated last point).
    Lines, arcs, circles and polylines are flattened (max chord deviation `chord_tol` mm) and
    open pieces are chained end to end, as FreeCAD joins a face's edges into wires."""
    from ezdxf import path as dxfpath  # noqa: PLC0415

    closed, pieces = [], []
    for e in doc.modelspace().query(f'*[layer=="{layer}"]'):
        pts = [(v.x, v.y) for v in dxfpath.make_path(e).flattening(chord_tol)]
        if len(pts) < 2:
            continue
        if math.dist(pts[0], pts[-1]) < join_tol:
            closed.append(pts[:-1])
        else:
            pieces.append(pts)
    while pieces:  # chain open pieces into loops
        chain = pieces.pop(0)
        while math.dist(chain[0], chain[-1]) >= join_tol:
            for i, p in enumerate(pieces):
                if math.dist(chain[-1], p[0]) < join_tol:
                    chain += p[1:]
                elif math.dist(chain[-1], p[-1]) < join_tol:
                    chain += p[-2::-1]
                else:
                    continue
                pieces.pop(i)
                break
            else:
                sys.exit(f"pocket_peer: layer {layer} has an open contour at {chain[-1]}")
        closed.append(chain[:-1])
    return closed


# ------------------------------------------------------------------------------------------------
# FreeCAD side: Adaptive2d, then G-code as PathAdaptive.GenerateGCode (FreeCAD 0.20) writes it


def run_adaptive(area, job, boundary, islands, log_path):
    """Adaptive2d.Execute on the job's pocket; returns (results as dicts, wall seconds)."""
    tool_d = job["tool"]["diameter"]
    a2d = area.Adaptive2d()
    a2d.toolDiameter = float(tool_d)
    # FreeCAD's StepOver is an integer percent of the diameter: the one whose straight-cut
    # engagement acos(1 - 2 s) is the job's target (53 deg -> 20 %, i.e. 53.1 deg).
    target = math.radians(job["pocket"]["max_engagement"])
    a2d.stepOverFactor = round(100 * (1 - math.cos(target)) / 2) / 100
    a2d.stockToLeave = float(job["pocket"].get("stock_to_leave", 0.0))
    # FreeCAD's HelixDiameterLimit: its default 0 (libarea's own), or --helix-diameter.
    a2d.helixRampDiameter = float(job.get("_helix_diameter", 0.0))
    a2d.keepToolDownDistRatio = 3.0  # FreeCAD's default KeepToolDownRatio
    a2d.tolerance = 0.1  # FreeCAD's default Tolerance (accuracy vs speed)
    a2d.forceInsideOut = False  # FreeCAD's default
    a2d.finishingProfile = True  # FreeCAD's default
    a2d.opType = area.AdaptiveOperationType.ClearingInside

    # Stock: FreeCAD passes the stock's bounding box; the plate around the pocket is taken as
    # 10 mm wider on each side, so the pocket is closed and entered by a helix.
    xs = [p[0] for p in boundary]
    ys = [p[1] for p in boundary]
    m = 10.0
    stock = [(min(xs) - m, min(ys) - m), (max(xs) + m, min(ys) - m),
             (max(xs) + m, max(ys) + m), (min(xs) - m, max(ys) + m)]

    # libarea prints progress on the C stdout: send it to a log, keep the table clean.
    sys.stdout.flush()
    saved = os.dup(1)
    with open(log_path, "w") as log:
        os.dup2(log.fileno(), 1)
        try:
            t0 = time.perf_counter()
            out = a2d.Execute([stock], [boundary] + islands, lambda paths: False)
            wall = time.perf_counter() - t0
        finally:
            os.dup2(saved, 1)
            os.close(saved)
    results = [{"HelixCenterPoint": r.HelixCenterPoint, "StartPoint": r.StartPoint,
                "AdaptivePaths": [(int(t), list(pts)) for t, pts in r.AdaptivePaths],
                "ReturnMotionType": int(r.ReturnMotionType)} for r in out]
    return results, wall


def finishing_start(paths, cutting):
    """Index of the first path of libarea's finishing profile: the profile passes are closed
    cutting loops appended after the clearing; they begin after the last link before the first
    loop. len(paths) when there is none."""
    for i, (mtype, pts) in enumerate(paths):
        if mtype == cutting and len(pts) > 10 and math.dist(pts[0], pts[-1]) < 1e-6:
            j = i
            while j > 0 and paths[j - 1][0] == cutting:
                j -= 1
            return j
    return len(paths)


class Gcode:
    """A LinuxCNC program as FreeCAD's linuxcnc post writes it: 3 decimals, every given word
    written (no modal suppression); remembers which lines belong to which phase."""

    def __init__(self):
        self.lines = []
        self.finishing = set()  # 1-based line numbers of the finishing profile
        self.in_finishing = False

    def add(self, text):
        self.lines.append(text)
        if self.in_finishing:
            self.finishing.add(len(self.lines))

    def move(self, code, **words):
        self.add(code + "".join(f" {k}{v:.3f}" for k, v in words.items()))

    def text(self):
        return "\n".join(self.lines) + "\n"


def freecad_gcode(area, job, results):
    """The program of FreeCAD 0.20's PathAdaptive.GenerateGCode (UseHelixArcs off, no cone, no
    finish depth), for the job's depths, heights and feeds."""
    MT = area.AdaptiveMotionType
    safe = float(job["machine"].get("safe_z", 5.0))
    clearance = safe  # ClearanceHeight = SafeHeight = the job's safe_z
    start_depth, final_depth = 0.0, -float(job["pocket"]["depth"])
    step_down = float(job["pocket"]["max_step_down"])
    horiz = float(job["cutting"]["feed_rate"])
    # The vertical feed: the job's entry feed ([path] entry_feed, 0 = half the feed), as trochomill.
    vert = float(job.get("path", {}).get("entry_feed", 0.0)) or horiz / 2
    lift = 0.0  # FreeCAD's default LiftDistance: keep-tool-down links at cutting depth

    # Depth levels as PathUtils.depth_params: every step_down, the last one at the final depth.
    depths, z = [], start_depth
    while z - step_down > final_depth + 1e-9:
        z -= step_down
        depths.append(round(z, 6))
    depths.append(final_depth)

    # The helix: FreeCAD's HelixAngle set so a turn descends the job's entry pitch.
    helix_r = max(math.dist(r["HelixCenterPoint"], r["StartPoint"]) for r in results)
    pitch = float(job.get("path", {}).get("entry_pitch", 1.0))
    helix_angle = min(89.0, max(1.0, math.degrees(math.atan2(pitch, 2 * math.pi * helix_r))))
    depth_per_circle = 2 * math.pi * helix_r * math.tan(math.radians(helix_angle))

    g = Gcode()
    g.add("(FreeCAD 0.20 Adaptive clearing: libarea Adaptive2d, GenerateGCode as PathAdaptive.py)")
    g.add(f"(helix angle {helix_angle:.3f} deg: {pitch:g} mm a turn; links kept down at depth)")
    g.add("G21 G90 G17")
    g.add("G40 G49 G80")
    g.add("T1 M6")
    g.add("G43 H1")
    g.add(f"S{float(job['cutting']['spindle_speed']):.0f} M3")
    g.move("G0", Z=clearance)

    lz = pass_start = start_depth
    for pass_end in depths:
        for region in results:
            cx, cy = region["HelixCenterPoint"]
            sx, sy = region["StartPoint"]
            start_angle = math.atan2(sy - cy, sx - cx)
            pass_depth = pass_start - pass_end
            r_helix = math.dist((cx, cy), (sx, sy))
            if r_helix > 0.01:  # helix ramp of straight chords, pi/16 apart
                r = r_helix - 0.01
                maxfi = pass_depth / depth_per_circle * 2 * math.pi
                fi = 0.0
                offset = -maxfi + start_angle - math.pi / 16
                hx, hy = cx + r * math.cos(offset), cy + r * math.sin(offset)
                g.add(f"(Helix to depth: {pass_end:f})")
                g.move("G0", Z=clearance)
                g.move("G0", X=hx, Y=hy, Z=clearance)
                g.move("G0", X=hx, Y=hy, Z=safe)
                g.move("G1", X=hx, Y=hy, Z=pass_start, F=vert)
                while fi < maxfi:
                    z = pass_start - fi / maxfi * (pass_start - pass_end)
                    g.move("G1", X=cx + r * math.cos(fi + offset), Y=cy + r * math.sin(fi + offset),
                           Z=z, F=vert)
                    fi += math.pi / 16
                maxfi += 2 * math.pi  # one more circle at depth to clear the centre
                while fi < maxfi:
                    g.move("G1", X=cx + r * math.cos(fi + offset), Y=cy + r * math.sin(fi + offset),
                           Z=pass_end, F=horiz)
                    fi += math.pi / 16
            else:  # no helix: plunge at the start point
                g.move("G0", Z=clearance)
                g.move("G0", X=sx, Y=sy, Z=clearance)
                g.move("G1", X=sx, Y=sy, Z=pass_end, F=vert)
            lz = pass_end
            g.add(f"(Adaptive - depth: {pass_end:f})")

            paths = region["AdaptivePaths"]
            fin = finishing_start(paths, int(MT.Cutting))
            for k, (mtype, pts) in enumerate(paths):
                g.in_finishing = k >= fin
                for x, y in pts:
                    if mtype == int(MT.Cutting):
                        z = pass_end
                        if z != lz:
                            g.move("G1", Z=z, F=vert)
                        g.move("G1", X=x, Y=y, F=horiz)
                    elif mtype == int(MT.LinkClear):  # keep the tool down
                        z = pass_end + lift
                        if z != lz:
                            g.move("G0", Z=z)
                        g.move("G0", X=x, Y=y)
                    elif mtype == int(MT.LinkNotClear):  # lift to the clearance height
                        z = clearance
                        if z != lz:
                            g.move("G0", Z=z)
                        g.move("G0", X=x, Y=y)
                    # LinkClearAtPrevPass: FreeCAD 0.20 writes nothing (its code is commented out)
                    lz = z
            g.in_finishing = False
            if lz != clearance:
                g.move("G0", Z=clearance)
                lz = clearance
        pass_start = pass_end
    g.add("M5")
    g.add("M2")
    return g, helix_angle, depths


# ------------------------------------------------------------------------------------------------
# Measurement: trochomill's kernel on a program, samples mapped to program lines


def run(cmd, **kw):
    """Runs a command; exits with its output when it fails."""
    p = subprocess.run(cmd, capture_output=True, text=True, **kw)
    if p.returncode != 0:
        sys.exit(f"pocket_peer: {' '.join(cmd)} failed ({p.returncode}):\n{p.stdout}{p.stderr}")
    return p


def trace_moves(binary, program):
    """The moves of `check-gcode --trace`: (line, kind, start xyz, end xyz, centre or None,
    sweep deg, feed mm/min), the approach before the path starts left out (as analyze does)."""
    moves, prev = [], None
    for ln in run([binary, "check-gcode", program, "--trace"]).stdout.splitlines():
        skipped = ln.startswith("; ")
        f = ln[2:].split() if skipped else ln.split()
        if not f or f[0] not in ("G0", "G1", "G2", "G3"):
            continue
        w = {t[0]: t[1:] for t in f[1:]}
        end = (float(w["X"]), float(w["Y"]), float(w["Z"]))
        if not skipped and prev is not None:
            centre = tuple(map(float, w["C"].split(","))) if "C" in w else None
            if w.get("G", "17") != "17":
                sys.exit(f"pocket_peer: {program}: only G17 arcs are measured")
            moves.append({"line": int(f[-1].rsplit(":", 1)[1]), "kind": f[0], "start": prev,
                          "end": end, "centre": centre, "sweep": float(w.get("T", 0.0)),
                          "feed": float(w["F"])})
        prev = end
    return moves


def move_seconds(m):
    """Duration of a move at its programmed feed (rapids at the rapid rate)."""
    (x0, y0, z0), z1 = m["start"], m["end"][2]
    if m["centre"] is not None:
        r = math.hypot(x0 - m["centre"][0], y0 - m["centre"][1])
        length = math.hypot(r * math.radians(abs(m["sweep"])), z1 - z0)
    else:
        length = math.dist(m["start"], m["end"])
    return 60.0 * length / m["feed"]


def fit_circle(pts):
    """Least-squares circle (Kasa) through xy points: (cx, cy, r, max residual) or None."""
    if len(pts) < 3:
        return None
    # x^2 + y^2 + D x + E y + F = 0: normal equations of the linear least squares.
    A = [[0.0] * 3 for _ in range(3)]
    b = [0.0] * 3
    for x, y in pts:
        row, rhs = (x, y, 1.0), -(x * x + y * y)
        for i in range(3):
            b[i] += row[i] * rhs
            for j in range(3):
                A[i][j] += row[i] * row[j]
    for c in range(3):  # Gaussian elimination with partial pivoting
        p = max(range(c, 3), key=lambda i: abs(A[i][c]))
        if abs(A[p][c]) < 1e-12:
            return None
        A[c], A[p], b[c], b[p] = A[p], A[c], b[p], b[c]
        for i in range(c + 1, 3):
            k = A[i][c] / A[c][c]
            b[i] -= k * b[c]
            for j in range(c, 3):
                A[i][j] -= k * A[c][j]
    s = [0.0] * 3
    for i in (2, 1, 0):
        s[i] = (b[i] - sum(A[i][j] * s[j] for j in range(i + 1, 3))) / A[i][i]
    cx, cy = -s[0] / 2, -s[1] / 2
    r2 = cx * cx + cy * cy - s[2]
    if r2 <= 0:
        return None
    r = math.sqrt(r2)
    return cx, cy, r, max(abs(math.hypot(x - cx, y - cy) - r) for x, y in pts)


def entry_moves(moves):
    """The entry moves, found the same way in both programs, as {move index: kind}: "helix" for
    a run of feed moves changing Z along a circle and the turn at depth that follows it (the
    following feed moves on the helix circle, up to one full turn), "plunge" for any other feed
    move changing Z."""
    entry, i, n = {}, 0, len(moves)

    def descends(m):
        return m["kind"] != "G0" and abs(m["end"][2] - m["start"][2]) >= 1e-6

    while i < n:
        if not descends(moves[i]):
            i += 1
            continue
        run_start = i
        while i < n and descends(moves[i]):
            i += 1
        pts = [moves[run_start]["start"][:2]] + [moves[k]["end"][:2] for k in range(run_start, i)]
        circle = fit_circle(pts)
        if circle is None or circle[2] < ON_CIRCLE_MM or circle[3] > ON_CIRCLE_MM:
            entry.update((k, "plunge") for k in range(run_start, i))
            continue
        entry.update((k, "helix") for k in range(run_start, i))
        cx, cy, r, _ = circle
        turned = 0.0
        while i < n and moves[i]["kind"] != "G0":
            m = moves[i]
            (x0, y0, _), (x1, y1, _) = m["start"], m["end"]
            if abs(math.hypot(x1 - cx, y1 - cy) - r) > ON_CIRCLE_MM:
                break
            if m["centre"] is not None:
                if math.hypot(m["centre"][0] - cx, m["centre"][1] - cy) > ON_CIRCLE_MM:
                    break
                d = math.radians(abs(m["sweep"]))
            else:
                d = abs(math.atan2((x0 - cx) * (y1 - cy) - (y0 - cy) * (x1 - cx),
                                   (x0 - cx) * (x1 - cx) + (y0 - cy) * (y1 - cy)))
            if turned + d > 2 * math.pi + 1e-3:
                break
            turned += d
            entry[i] = "helix"
            i += 1
    return entry


def measure(binary, job_path, target, program, finishing_lines, stem):
    """Runs analyze on a program and condenses its samples: largest engagement and the share of
    cutting samples above the target, entries excepted, for the whole program and for the
    clearing (finishing lines excepted too)."""
    json_path, csv_path = stem + ".json", stem + ".csv"
    run([binary, "analyze", job_path, "--gcode", program, "--json", json_path, "--csv", csv_path])
    with open(json_path) as f:
        metrics = json.load(f)
    moves = trace_moves(binary, program)
    ends, t = [], 0.0
    for m in moves:
        t += move_seconds(m)
        ends.append(t)
    if abs(t - metrics["machining_time_s"]) > 1e-3 * max(1.0, t):
        print(f"warning: {program}: moves add up to {t:.3f} s, analyze says "
              f"{metrics['machining_time_s']:.3f} s: the line mapping may be off", file=sys.stderr)
    entry = entry_moves(moves)
    acc = {k: {"n": 0, "above": 0, "above5": 0, "max": 0.0, "at": None}
           for k in ("all", "clearing")}
    other = {k: {"moves": set(), "max": 0.0, "at": None}
             for k in ("helix", "plunge", "rapid", "retract")}
    with open(csv_path, newline="") as f:
        for row in csv.DictReader(f):
            eng = float(row["engagement_deg"])
            if eng <= ENGAGED_DEG:
                continue
            k = min(bisect.bisect_left(ends, float(row["t_s"])), len(moves) - 1)
            m = moves[k]
            where = (float(row["x_mm"]), float(row["y_mm"]), float(row["z_mm"]), m["line"])
            if k in entry or m["kind"] == "G0":
                # Not cutting along the floor: entries, and rapids touching material (a rapid
                # straight up off a wall is a "retract"; any other is a rapid into material).
                if k in entry:
                    kind = entry[k]
                elif m["start"][:2] == m["end"][:2] and m["end"][2] > m["start"][2]:
                    kind = "retract"
                else:
                    kind = "rapid"
                o = other[kind]
                o["moves"].add(k)
                if eng > o["max"]:
                    o["max"], o["at"] = eng, where
                continue
            phases = ("all",) if m["line"] in finishing_lines else ("all", "clearing")
            for p in phases:
                a = acc[p]
                a["n"] += 1
                a["above"] += eng > target
                a["above5"] += eng > target + 5
                if eng > a["max"]:
                    a["max"], a["at"] = eng, where
    return {"metrics": metrics, "acc": acc, "other": other, "entries": len(entry)}


def program_blocks(path):
    """The blocks of a program that are not comment lines, as (1-based line, text)."""
    with open(path) as f:
        return [(i, ln) for i, ln in enumerate(f.read().splitlines(), 1)
                if ln.strip() and not ln.lstrip().startswith("(")]


def program_size(path):
    with open(path, "rb") as f:
        data = f.read()
    return len(data), data.count(b"\n")


# ------------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("trochomill_bin")
    ap.add_argument("work_dir")
    ap.add_argument("--job", help="pocket job (default: examples/pockets/plate.toml)")
    ap.add_argument("--helix-diameter", type=float, default=0.0,
                    help="FreeCAD's HelixDiameterLimit (mm; default 0, libarea's own): a narrow "
                         "pocket may need one that fits")
    args = ap.parse_args()

    area = load_area()
    if area is None:
        print(f"SKIP: FreeCAD's area module is missing (Debian: apt-get install freecad-python3; "
              f"looked in {FREECAD_LIB})")
        return SKIP
    try:
        import ezdxf  # noqa: PLC0415
    except ImportError:
        print("SKIP: ezdxf is missing (Debian: apt-get install python3-ezdxf)")
        return SKIP

    binary = os.path.abspath(args.trochomill_bin)
    job_path = os.path.abspath(args.job or find_job(os.path.dirname(os.path.abspath(__file__)), binary))
    work = os.path.abspath(args.work_dir)
    os.makedirs(work, exist_ok=True)
    with open(job_path, "rb") as f:
        job = tomllib.load(f)
    job["_helix_diameter"] = args.helix_diameter

    # The pocket's geometry from the job's drawing.
    doc = ezdxf.readfile(os.path.join(os.path.dirname(job_path), job["geometry"]["file"]))
    outer = layer_polygons(ezdxf, doc, job["pocket"]["boundary"])
    if len(outer) != 1:
        sys.exit(f"pocket_peer: layer {job['pocket']['boundary']} has {len(outer)} contours, not 1")
    islands = layer_polygons(ezdxf, doc, job["pocket"]["islands"]) if job["pocket"].get("islands") else []

    # FreeCAD: Adaptive2d, then its G-code.
    results, fc_wall = run_adaptive(area, job, outer[0], islands, os.path.join(work, "freecad_adaptive.log"))
    if not results or not results[0]["AdaptivePaths"]:
        sys.exit("pocket_peer: Adaptive2d returned no path (see freecad_adaptive.log)")
    g, helix_angle, depths = freecad_gcode(area, job, results)
    fc_ngc = os.path.join(work, "freecad.ngc")
    with open(fc_ngc, "w") as f:
        f.write(g.text())

    # trochomill: plan (timed), and once more without the finishing pass to find where it begins.
    tm_ngc = os.path.join(work, "trochomill.ngc")
    t0 = time.perf_counter()
    run([binary, "plan", job_path, "-o", tm_ngc])
    tm_wall = time.perf_counter() - t0
    tm_nofin = os.path.join(work, "trochomill_nofinish.ngc")
    run([binary, "plan", job_path, "-o", tm_nofin, "--set", "pocket.finish_pass=false"])
    full, short = program_blocks(tm_ngc), program_blocks(tm_nofin)
    k = next((i for i, (a, b) in enumerate(zip(full, short)) if a[1] != b[1]), len(short))
    first = full[k][0] if k < len(full) else len(full) + 1
    with open(tm_ngc) as f:
        n_lines = len(f.read().splitlines())
    tm_finishing = set(range(first, n_lines + 1))  # 1-based lines from the first difference

    target = float(job["pocket"]["max_engagement"])
    tm = measure(binary, job_path, target, tm_ngc, tm_finishing, os.path.join(work, "trochomill"))
    fc = measure(binary, job_path, target, fc_ngc, g.finishing, os.path.join(work, "freecad"))

    # The table.
    def share(a, key="above"):
        return f"{100.0 * a[key] / a['n']:.2f}" if a["n"] else "-"

    def touched(r, kind):
        o = r["other"][kind]
        return f"{len(o['moves'])} / {o['max']:.1f}"

    tm_bytes, tm_lines = program_size(tm_ngc)
    fc_bytes, fc_lines = program_size(fc_ngc)
    both = (tm, fc)
    rows = [
        ("largest engagement after the entry, analyze (deg)",
         *(f"{r['metrics']['engagement_max_after_entry_deg']:.1f}" for r in both)),
        ("largest engagement cutting, entries excepted (deg)",
         *(f"{r['acc']['all']['max']:.1f}" for r in both)),
        ("  clearing only, finishing excepted (deg)",
         *(f"{r['acc']['clearing']['max']:.1f}" for r in both)),
        (f"cutting samples above {target:g} deg (%)", *(share(r["acc"]["all"]) for r in both)),
        ("  clearing only (%)", *(share(r["acc"]["clearing"]) for r in both)),
        (f"cutting samples above {target + 5:g} deg (%)",
         *(share(r["acc"]["all"], "above5") for r in both)),
        ("  clearing only (%)", *(share(r["acc"]["clearing"], "above5") for r in both)),
        ("helix entries: largest engagement (deg)", *(f"{r['other']['helix']['max']:.1f}" for r in both)),
        ("plunges in material (moves / largest deg)", *(touched(r, "plunge") for r in both)),
        ("rapids into material (moves / largest deg)", *(touched(r, "rapid") for r in both)),
        ("machining time at programmed feed (s)",
         *(f"{r['metrics']['machining_time_s']:.1f}" for r in both)),
        ("  with acceleration (s)",
         *(f"{r['metrics']['machining_time_with_acceleration_s']:.1f}" for r in both)),
        ("path length (mm)", *(f"{r['metrics']['path_length_mm']:.0f}" for r in both)),
        ("removed volume (mm^3)", *(f"{r['metrics']['removed_volume_mm3']:.0f}" for r in both)),
        ("program size (bytes)", f"{tm_bytes}", f"{fc_bytes}"),
        ("program size (lines)", f"{tm_lines}", f"{fc_lines}"),
        ("generation time (s)", f"{tm_wall:.2f}", f"{fc_wall:.2f}"),
    ]
    w0 = max(len(r[0]) for r in rows)
    print(f"pocket {job['pocket']['boundary']} of {job['geometry']['file']} "
          f"({os.path.basename(job_path)}): tool {job['tool']['diameter']:g} mm, target "
          f"{target:g} deg, levels {', '.join(f'{d:g}' for d in depths)} mm")
    print(f"{'':{w0}}  {'trochomill':>12}  {'FreeCAD Adaptive':>16}")
    for name, a, b in rows:
        print(f"{name:{w0}}  {a:>12}  {b:>16}")
    print()
    print("notes:")
    print(f"  both programs measured by `trochomill analyze --gcode`; samples are equally spaced "
          f"in time, a cutting sample is one of a feed move (entries excepted) engaged > "
          f"{ENGAGED_DEG} deg")
    print(f"  entries: feed moves changing Z (a helix when they run along a circle, with the turn "
          f"at depth after it; a plunge otherwise): {tm['entries']} moves in trochomill's "
          f"program, {fc['entries']} in FreeCAD's")
    print("  trochomill: generation = wall clock of `plan` (its kernel proof included); "
          "finishing = its finishing pass at full depth")
    print(f"  FreeCAD: generation = wall clock of Adaptive2d.Execute; step-over "
          f"{round(100 * (1 - math.cos(math.radians(target))) / 2)} % (straight-cut engagement "
          f"{math.degrees(math.acos(1 - 2 * round(100 * (1 - math.cos(math.radians(target))) / 2) / 100)):.1f} deg), "
          f"tolerance 0.1, stock to leave {job['pocket'].get('stock_to_leave', 0):g} mm, helix "
          f"angle {helix_angle:.2f} deg (the job's entry pitch); finishing = libarea's finishing "
          f"profile, at every level")
    for name, r in (("trochomill", tm), ("FreeCAD", fc)):
        for label, at in (("largest cutting", r["acc"]["all"]["at"]),
                          ("largest clearing", r["acc"]["clearing"]["at"]),
                          ("worst plunge", r["other"]["plunge"]["at"]),
                          ("worst rapid", r["other"]["rapid"]["at"])):
            if at:
                print(f"  {name}: {label} at ({at[0]:.3f}, {at[1]:.3f}, {at[2]:.3f}), line {at[3]}")
        o = r["other"]["retract"]
        if o["moves"]:
            print(f"  {name}: {len(o['moves'])} straight-up rapids start touching a wall "
                  f"(up to {o['max']:.1f} deg; not counted above)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
