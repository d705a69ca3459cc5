#!/usr/bin/env python3
"""SVG drawings read by svgelements (Debian's python3-svgelements: an independent SVG parser with
its own path, transform and viewport handling) and by `trochomill check-drawing`: every path
command absolute and relative, the basic shapes, nested transforms, viewBoxes in mm, cm, in and
px, Inkscape layers. For each element (by its id) the length, the enclosed area and its sign, and
the bounding box must agree; then the inputs trochomill must refuse, with what the message says.
Usage: svg-peer.py TROCHOMILL WORK_DIR"""
import json
import math
import os
import subprocess
import sys

import svgelements as se

cli, work = sys.argv[1], sys.argv[2]
os.makedirs(work, exist_ok=True)
failures = []
ARC_TOL = 0.0005  # --arc-tolerance: Béziers and elliptical arcs as biarcs within 0.5 um
INK = "http://www.inkscape.org/namespaces/inkscape"
HEAD = ('<svg xmlns="http://www.w3.org/2000/svg" xmlns:inkscape="%s" ' % INK)


def check(ok, what):
    if not ok:
        failures.append(what)
        print("FAIL:", what)


def run(*args):
    r = subprocess.run([cli, *args], capture_output=True, text=True)
    return r.returncode, r.stdout, r.stderr


# svgelements converts mm and cm with 1 in = 1 / 0.0393701 mm (5.4e-7 off 25.4): a document sized
# in mm or cm is turned back into mm with its own factor, one sized in in or px with CSS's.
PX_PER_MM_SE = 96 * 0.0393701
PX_PER_MM_CSS = 96 / 25.4

DOCS = {
    # Every path command, absolute and relative (the second path is the first 60 mm to the
    # right), a circle from two arcs, implicit repeats and compact numbers, an elliptical arc,
    # arc flags without separators.
    "paths-mm": (PX_PER_MM_SE, HEAD + 'width="200mm" height="150mm" viewBox="0 0 200 150">'
                 '<g inkscape:groupmode="layer" inkscape:label="Paths">'
                 '<path id="abs" d="M 10 10 L 30 10 H 40 V 20 C 45 25 45 30 40 35 S 30 40 25 35 '
                 'Q 20 30 15 35 T 10 30 A 5 8 20 0 1 10 10 Z"/>'
                 '<path id="rel" d="m 70 10 l 20 0 h 10 v 10 c 5 5 5 10 0 15 s -10 5 -15 0 '
                 'q -5 -5 -10 0 t -5 -5 a 5 8 20 0 1 0 -20 z"/>'
                 '<path id="ring" d="M 130 30 a 10 10 0 1 0 20 0 a 10 10 0 1 0 -20 0 Z"/>'
                 '<path id="zigzag" d="M10 60 20 70 30 60l10 10 10-10 1e1,1e1H9e1v-.5-.5"/>'
                 '<path id="elliptic" d="M 150 80 A 30 15 -30 1 1 180 100"/>'
                 '<path id="flags" d="M 10 120 a25 25 0 00 50 0"/>'
                 '</g></svg>'),
    # Shapes under nested transforms (uniform, sheared, stretched) in a page of 8 x 6 in. No
    # ellipse under a shear: svgelements 1.7.2 gets those wrong (an ellipse under
    # skewX(20) measures 81.5 mm against 76.40 by integrating its parametric form).
    "shapes-in": (PX_PER_MM_CSS, HEAD + 'width="8in" height="6in" viewBox="0 0 800 600">'
                  '<g id="moved" transform="translate(100 50) rotate(30)">'
                  '<rect id="rounded" width="120" height="80" rx="15" ry="10"/>'
                  '<g transform="scale(1.5)"><circle id="round" cx="150" cy="40" r="20"/></g></g>'
                  '<g id="sheared" transform="matrix(1 0.2 0 1 0 0) skewX(20)">'
                  '<polygon id="quad" points="200,250 300,260 280,350 210,330"/></g>'
                  '<g id="turned" transform="rotate(15) scale(1 0.8)">'
                  '<ellipse id="egg" cx="100" cy="300" rx="60" ry="30"/></g>'
                  '<g transform="rotate(-45 500 300) scale(2 1)">'
                  '<circle id="stretched" cx="250" cy="300" r="30"/></g>'
                  '<polyline id="wave" points="50 500 100 550 150 500 200 550"/>'
                  '<line id="bar" x1="300" y1="500" x2="450" y2="560"/>'
                  '<rect id="tilted" x="500" y="450" width="150" height="100" '
                  'transform="skewY(10)"/></svg>'),
    # A square viewBox centred in a wide page (xMidYMid meet), negative origin.
    "meet-cm": (PX_PER_MM_SE, HEAD + 'width="20cm" height="10cm" viewBox="-50 -50 100 100">'
                '<rect id="frame" x="-40" y="-40" width="80" height="80" rx="10"/>'
                '<circle id="hub" cx="0" cy="0" r="25"/></svg>'),
    # No viewBox: user units are px.
    "px": (PX_PER_MM_CSS, HEAD + 'width="400" height="300">'
           '<rect id="plate" x="20" y="20" width="200" height="100"/>'
           '<path id="hook" d="M 250 50 q 50 0 50 50 t 50 50"/></svg>'),
    # Inkscape layers (sublayer inside), a group with an id, an element outside any group.
    "layers": (PX_PER_MM_SE, HEAD + 'width="100mm" height="100mm" viewBox="0 0 100 100">'
               '<g inkscape:groupmode="layer" inkscape:label="Outline" id="layer1">'
               '<rect id="outer" x="5" y="5" width="90" height="90" rx="5"/>'
               '<g inkscape:groupmode="layer" inkscape:label="Holes" id="layer2">'
               '<circle id="h1" cx="25" cy="25" r="5"/><circle id="h2" cx="75" cy="25" r="5"/>'
               '</g></g><circle id="loose" cx="50" cy="60" r="8"/></svg>'),
}


def segments(shape):
    """The shape's segments with its transforms applied (svgelements' reified path)."""
    return [s for s in abs(se.Path(shape)).segments() if not isinstance(s, se.Move)]


def sampled(shape, to_mm):
    """Points along the shape (mm, y up), dense on curves: 2000 per segment."""
    pts = []
    for seg in segments(shape):
        if isinstance(seg, se.Move):
            continue
        n = 1 if isinstance(seg, (se.Line, se.Close)) else 2000
        for i in range(0 if not pts else 1, n + 1):
            pts.append(to_mm(seg.point(i / n)))
    return pts


def shoelace(pts):
    return 0.5 * sum(pts[i][0] * pts[(i + 1) % len(pts)][1] - pts[(i + 1) % len(pts)][0] * pts[i][1]
                     for i in range(len(pts)))


GROUP_OF = {"rounded": "moved", "round": "moved", "egg": "turned", "quad": "sheared"}


def layer_of(shape):
    return shape.values.get("{%s}label" % INK, "0")


for name, (px_per_mm, text) in DOCS.items():
    f = os.path.join(work, name + ".svg")
    with open(f, "w") as out:
        out.write(text)
    doc = se.SVG.parse(f, ppi=96)
    height_mm = doc.height / px_per_mm

    def to_mm(p):  # svgelements' px (y down) into the drawing's mm (y up, from the page's foot)
        return (p[0] / px_per_mm, height_mm - p[1] / px_per_mm)

    rc, out, err = run("check-drawing", f, "--arc-tolerance", str(ARC_TOL), "--json", "-")
    check(rc == 0, f"{name}: check-drawing exit {rc}: {err}")
    if rc != 0:
        continue
    got = json.loads(out)
    by_id = {c["entities"][0].split("#")[1]: c for c in got["contours"]}
    shapes = [e for e in doc.elements() if isinstance(e, se.Shape) and e.id]
    check(len(got["contours"]) == len(shapes), f"{name}: {len(got['contours'])} contours, "
          f"svgelements has {len(shapes)} shapes")
    for e in shapes:
        c = by_id.get(e.id)
        check(c is not None, f"{name}: no contour of #{e.id}")
        if c is None:
            continue
        what = f"{name} #{e.id}"
        pts = sampled(e, to_mm)
        closed = math.dist(pts[0], pts[-1]) < 1e-9 * max(1, abs(pts[0][0]))
        check(c["closed"] == closed, f"{what}: closed {c['closed']}, svgelements {closed}")
        # Lengths: lines and circular arcs exact; biarcs within e = 0.5 um of a curve cut its
        # corners by O(e^4/3) (measured: 0.24 e on the quadratic "hook", 1.2e-4 mm), allowed
        # 0.5 e per element; svgelements integrates to 1e-12.
        want = sum(s.length(error=1e-12) for s in segments(e)) / px_per_mm
        check(abs(c["length_mm"] - want) <= 0.5 * ARC_TOL + 1e-9 * want,
              f"{what}: length {c['length_mm']} svgelements {want}")
        if closed:
            # Area: the biarcs move it by at most perimeter x tolerance; 2000 chords a curve
            # segment lose less than 1e-6 of a segment's area.
            a = shoelace(pts[:-1])
            check(abs(c["area_mm2"] - abs(a)) <= want * ARC_TOL + 1e-6 * abs(a),
                  f"{what}: area {c['area_mm2']} sampled {abs(a)}")
            check(c["orientation"] == ("ccw" if a > 0 else "cw"),
                  f"{what}: {c['orientation']}, the picture turns {'ccw' if a > 0 else 'cw'}")
        # The box: trochomill's from chords within 1 um, the samples' within the arc tolerance.
        lo = [min(p[k] for p in pts) for k in (0, 1)]
        hi = [max(p[k] for p in pts) for k in (0, 1)]
        for k in (0, 1):
            check(abs(c["bbox_min_mm"][k] - lo[k]) <= 2e-3 and abs(c["bbox_max_mm"][k] - hi[k]) <= 2e-3,
                  f"{what}: box {c['bbox_min_mm']} {c['bbox_max_mm']} sampled {lo} {hi}")
        # Inkscape layers: svgelements' inherited label; else the enclosing group's id.
        layer = layer_of(e) if name in ("layers", "paths-mm") else GROUP_OF.get(e.id, "0")
        check(c["layer"] == layer, f"{what}: layer {c['layer']}, want {layer}")
    if name == "paths-mm":
        check(got["units"] == "mm" and abs(got["mm_per_unit"] - 1) < 1e-12,
              f"paths-mm: units {got['units']} {got['mm_per_unit']}")
        check(abs(by_id["abs"]["length_mm"] - by_id["rel"]["length_mm"]) < 1e-9,
              "absolute and relative commands draw the same")
        check(abs(by_id["ring"]["area_mm2"] - 100 * math.pi) < 1e-9 and by_id["ring"]["arcs"] == 2,
              f"two arcs make the circle of radius 10: {by_id['ring']}")
    if name == "px":
        check(got["units"] == "px (96 per in)", f"px: units {got['units']}")
    if name == "meet-cm":
        # 100 units into 200 mm x 100 mm: 1 mm a unit, centred: x from 50 mm.
        check(abs(by_id["hub"]["bbox_min_mm"][0] - 75) < 2e-3, f"meet: hub at {by_id['hub']}")

# Layers chosen by name, sublayers their own; ids choose elements.
f = os.path.join(work, "layers.svg")
for names, count in [(["Holes"], 2), (["Outline"], 1), (["0"], 1), (["h2", "loose"], 2)]:
    args = [a for n in names for a in ("--layer", n)]
    rc, out, err = run("check-drawing", f, *args, "--json", "-")
    check(rc == 0 and len(json.loads(out)["contours"]) == count, f"--layer {names}: {rc} {err}")
rc, out, err = run("check-drawing", f, "--layer", "Nope")
check(rc == 2 and "the layers with shapes: 0, Holes, Outline" in err, f"missing layer: {err}")


def refused(name, text, expect):
    f = os.path.join(work, name + ".svg")
    with open(f, "w") as out:
        out.write(text)
    rc, out, err = run("check-drawing", f)
    check(rc == 2 and expect in err, f"{name}: exit {rc}, want 2 and '{expect}' in: {err.strip()}")


refused("use", HEAD + '><defs><circle id="c" r="3"/></defs><use href="#c" x="5"/></svg>',
        "a <use> of '#c': references are not read")
refused("bad-path", HEAD + '><path id="p" d="M 0 0 L 5 5 Q 1"/></svg>',
        "path #p on layer '0': bad d at its end (character 16): expected a number")
refused("not-xml", "<svg><rect></svg>", "not-xml.svg:1:14: not an SVG file (XML: ")
refused("not-svg", "<html/>", "the root element is <html>, not <svg>")
refused("unit", HEAD + 'width="3em" viewBox="0 0 1 1"><rect width="1" height="1"/></svg>',
        "expected a unit of mm, cm, in, pt, pc, px, Q or none")
refused("branch", HEAD + '><path d="M 0 0 H 10 M 0 0 V 10 M 0 0 L -10 -10"/></svg>',
        "a branch at (0, 0) mm")

print(f"{len(failures)} failures")
sys.exit(1 if failures else 0)
