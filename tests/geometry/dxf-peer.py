#!/usr/bin/env python3
"""DXF drawings written by ezdxf (an independent DXF writer and NURBS evaluator), read by
`trochomill check-drawing`: every entity kind, chained into the contours the drawing means, with
lengths and areas against closed forms and ezdxf's own curve evaluation; the same drawing in
inches; and the drawings trochomill must refuse, with what the message must say.
Usage: dxf-peer.py TROCHOMILL WORK_DIR"""
import json
import math
import os
import subprocess
import sys

import ezdxf

cli, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def run(*args):
    r = subprocess.run([cli, *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


def bulge_arc(p0, p1, bulge):
    """Length and signed segment area (left of the chord positive) of a bulge arc."""
    th = 4 * math.atan(bulge)
    d = math.dist(p0, p1)
    r = d / (2 * math.sin(abs(th) / 2))
    return r * abs(th), math.copysign(0.5 * r * r * (abs(th) - math.sin(abs(th))), th)


def drawing(path, unit_code, scale):
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = unit_code
    m = doc.modelspace()
    s = 1 / scale  # drawing units per mm
    # SLOT: an open chain of a line, an arc, a polyline with a bulge and a cubic spline.
    m.add_line((0, 0), (20 * s, 0), dxfattribs={"layer": "SLOT"})
    m.add_arc((20 * s, 10 * s), 10 * s, -90, 0, dxfattribs={"layer": "SLOT"})
    m.add_lwpolyline([(30 * s, 10 * s, 0, 0, 0.5), (40 * s, 20 * s), (50 * s, 20 * s)],
                     format="xyseb", dxfattribs={"layer": "SLOT"})
    ctrl = [(50 * s, 20 * s), (60 * s, 25 * s), (70 * s, 15 * s), (80 * s, 20 * s)]
    m.add_open_spline(ctrl, degree=3, dxfattribs={"layer": "SLOT"})
    # POCKET: a closed polyline with a bulge on its right side (clockwise: bulging inward).
    m.add_lwpolyline([(0, 40 * s), (30 * s, 40 * s, 0, 0, -0.4), (30 * s, 60 * s), (0, 60 * s)],
                     format="xyseb", close=True, dxfattribs={"layer": "POCKET"})
    # ISLAND: a circle; WALL: a closed outline drawn clockwise from four lines in scrambled
    # order and directions; CURVE: a whole ellipse.
    m.add_circle((15 * s, 50 * s), 4 * s, dxfattribs={"layer": "ISLAND"})
    sq = [(100, 0), (100, 30), (130, 30), (130, 0)]
    for a, b in [(1, 2), (0, 3), (3, 2), (0, 1)]:
        m.add_line((sq[a][0] * s, sq[a][1] * s), (sq[b][0] * s, sq[b][1] * s),
                   dxfattribs={"layer": "WALL"})
    m.add_ellipse((60 * s, 50 * s), major_axis=(10 * s, 5 * s), ratio=0.5,
                  dxfattribs={"layer": "CURVE"})
    doc.saveas(path)
    return doc


def spline_length(doc):
    sp = [e for e in doc.modelspace() if e.dxftype() == "SPLINE"][0].construction_tool()
    n = 100000  # chords of ezdxf's own evaluation: short of the length by O(1/n^2), < 1e-8 mm
    pts = list(sp.points([i / n * sp.max_t for i in range(n + 1)]))
    return sum(math.dist(pts[i], pts[i + 1]) for i in range(n))


def ellipse_perimeter(a, b, n=200000):
    return sum(math.hypot(a * math.sin(2 * math.pi * (i + 0.5) / n),
                          b * math.cos(2 * math.pi * (i + 0.5) / n)) * 2 * math.pi / n
               for i in range(n))


for name, code, scale in [("mm", 4, 1.0), ("in", 1, 25.4)]:
    f = os.path.join(work, f"parts-{name}.dxf")
    doc = drawing(f, code, scale)
    rc, out, err = run("check-drawing", f, "--arc-tolerance", "0.0005", "--json", "-")
    check(rc == 0, f"{name}: check-drawing exit {rc}: {err}")
    if rc != 0:
        continue
    d = json.loads(out)
    check(d["units"] == name and abs(d["mm_per_unit"] - scale) < 1e-12, f"{name}: units {d['units']}")
    by = {c["layer"]: c for c in d["contours"]}
    check(sorted(d["layers"]) == ["CURVE", "ISLAND", "POCKET", "SLOT", "WALL"], f"layers {d['layers']}")
    check(len(d["contours"]) == 5, f"{name}: {len(d['contours'])} contours, want 5")
    # SLOT, open: 20 + a quarter circle of 10 + the bulge arc (30,10)->(40,20) + 10 + the spline.
    arc_len, _ = bulge_arc((30, 10), (40, 20), 0.5)
    want = 20 + 5 * math.pi + arc_len + 10 + spline_length(doc) * scale
    slot = by["SLOT"]
    check(not slot["closed"], "SLOT is open")
    # Lines and arcs are exact; the spline's biarcs within 0.0005 mm change its length by far
    # less than 1e-4 mm (second order in the deviation).
    check(abs(slot["length_mm"] - want) < 1e-4, f"{name}: SLOT length {slot['length_mm']} want {want}")
    check(slot["entities"][0].startswith("LINE") and slot["entities"][-1].startswith("SPLINE"),
          f"SLOT entities in order {slot['entities']}")
    check(max(abs(a - b) for a, b in zip(slot["start_mm"], [0, 0])) < 1e-9 and
          max(abs(a - b) for a, b in zip(slot["end_mm"], [80, 20])) < 1e-9,
          f"SLOT runs from (0,0) to (80,20): {slot['start_mm']} {slot['end_mm']}")
    # POCKET: 30 x 20 less the segment the clockwise bulge cuts in.
    blen, bseg = bulge_arc((30, 40), (30, 60), -0.4)
    pocket = by["POCKET"]
    check(pocket["closed"] and pocket["orientation"] == "ccw", f"POCKET {pocket['orientation']}")
    check(abs(pocket["area_mm2"] - (600 - abs(bseg))) < 1e-9 * 600, f"POCKET area {pocket['area_mm2']}")
    check(abs(pocket["length_mm"] - (30 + 30 + 20 + blen)) < 1e-9 * 100, f"POCKET length")
    isl = by["ISLAND"]
    check(isl["closed"] and abs(isl["area_mm2"] - 16 * math.pi) < 1e-9, f"ISLAND area {isl['area_mm2']}")
    wall = by["WALL"]
    check(wall["closed"] and abs(wall["area_mm2"] - 900) < 1e-9 and wall["lines"] == 4,
          f"WALL: four scrambled lines chained into a square {wall}")
    # CURVE: the ellipse's area pi a b exactly enough (biarcs within 0.0005 mm: the area moves by
    # less than perimeter x tolerance = 0.03 mm^2), its perimeter by numeric integration.
    a = math.hypot(10, 5)
    b = 0.5 * a
    cur = by["CURVE"]
    check(cur["closed"] and abs(cur["area_mm2"] - math.pi * a * b) < 0.03, f"CURVE area {cur['area_mm2']}")
    check(abs(cur["length_mm"] - ellipse_perimeter(a, b)) < 1e-3, f"CURVE length {cur['length_mm']}")

    # Only one layer, case as typed differently.
    rc, out, err = run("check-drawing", f, "--layer", "pocket", "--json", "-")
    check(rc == 0 and len(json.loads(out)["contours"]) == 1, f"--layer pocket: {rc} {err}")


def refused(name, build, expect):
    f = os.path.join(work, name + ".dxf")
    doc = ezdxf.new("R2010")
    doc.header["$INSUNITS"] = 4
    build(doc.modelspace(), doc)
    doc.saveas(f)
    rc, out, err = run("check-drawing", f)
    check(rc == 2 and expect in err, f"{name}: exit {rc}, want 2 and '{expect}' in: {err.strip()}")


def branch(m, doc):
    for b in [(10, 0), (0, 10), (-10, 0)]:
        m.add_line((0, 0), b)


def gap(m, doc):
    m.add_line((0, 0), (10, 0))
    m.add_line((10.05, 0), (20, 0))


def insert(m, doc):
    blk = doc.blocks.new("BOLT")
    blk.add_circle((0, 0), 3)
    m.add_blockref("BOLT", (5, 5))


def fit_only(m, doc):
    m.add_spline([(0, 0), (10, 5), (20, 0)])


def far_splines(m, doc):
    # Arches 100 km across (about 2,900 arcs each within 0.002 mm): 18 of them need more arcs
    # than a drawing is fitted with.
    s = 1e8
    for i in range(18):
        m.add_open_spline([(0, 0), (0, s), (s, s), (s, 0)], degree=3)


# A spline that turns back on itself (a cusp: the cubic through (0, 0) (10, -10) (0, -10)
# (10, 0), its cusp at (5, -7.5)), closed by a line: read as the corner it is (it was refused:
# no biarc turns back), its area that of ezdxf's own evaluation of the curve (the shoelace over
# 200,000 points: within 1e-8 of the curve's) within the length x the arc tolerance.
cusp = os.path.join(work, "cusp.dxf")
doc = ezdxf.new("R2010")
doc.header["$INSUNITS"] = 4
spline = ezdxf.math.BSpline([(0, 0), (10, -10), (0, -10), (10, 0)], order=4)
doc.modelspace().add_spline(dxfattribs={"layer": "CUSP"}).apply_construction_tool(spline)
doc.modelspace().add_line((10, 0), (0, 0), dxfattribs={"layer": "CUSP"})
doc.saveas(cusp)
rc, out, err = run("check-drawing", cusp, "--json", "-")
check(rc == 0, f"cusp: check-drawing exit {rc}: {err}")
if rc == 0:
    c = json.loads(out)["contours"]
    pts = [spline.point(i / 200000) for i in range(200001)]
    area = 0.5 * abs(sum(a[0] * b[1] - b[0] * a[1] for a, b in zip(pts, pts[1:] + pts[:1])))
    check(len(c) == 1 and c[0]["closed"] and abs(c[0]["area_mm2"] - area) < c[0]["length_mm"] * 0.002,
          f"cusp: {len(c)} contours, area {c and c[0]['area_mm2']} against ezdxf's {area}")

refused("far-splines", far_splines, "the drawing's curves need more than 50000 arcs within "
        "0.002 mm (the arc tolerance)")
refused("branch", branch, "a branch at (0, 0) mm")
refused("gap", gap, "a gap of 0.05 mm")
refused("insert", insert, "INSERT of block 'BOLT'")
refused("fit-only", fit_only, "fit points only")
rc, out, err = run("check-drawing", os.path.join(work, "parts-mm.dxf"), "--layer", "NOPE")
check(rc == 2 and "no line, arc or curve on layer 'NOPE' (the layers with entities: CURVE, ISLAND, "
      "POCKET, SLOT, WALL)" in err, f"missing layer: {err}")
rc, out, err = run("check-drawing", os.path.join(work, "missing.dxf"))
check(rc == 2 and "cannot open" in err, f"missing file: {rc} {err}")

print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
