#!/usr/bin/env python3
"""Writes the pocket examples' drawing (plate.dxf) with ezdxf, a DXF library independent of
trochomill's reader (Debian's python3-ezdxf). Units mm ($INSUNITS = 4).

Layer POCKET: an 80 x 50 mm pocket with 3 mm corner fillets.
Layer ISLANDS: a 16 mm round boss at (55, 25) and a 12 x 8 mm block at (20, 12).
Layer L: an L-shaped pocket (two 30 mm arms, 16 mm wide) at x 100 .. 130, sharp corners.
Layer GROOVE: a U-shaped groove 14 mm wide at x 150 .. 217: its centre line runs from (150, 10)
to (190, 10), half round (190, 30) with radius 20 and back to (150, 50); its walls are lines
and half circles of radius 27 and 13 (bulges of +-1).
"""
import math
import sys

import ezdxf

doc = ezdxf.new("R2010", setup=False)
doc.header["$INSUNITS"] = 4
msp = doc.modelspace()

# The pocket: lines and fillet arcs (counter-clockwise).
r = 3.0
W, H = 80.0, 50.0
lines = [((r, 0), (W - r, 0)), ((W, r), (W, H - r)), ((W - r, H), (r, H)), ((0, H - r), (0, r))]
for a, b in lines:
    msp.add_line(a, b, dxfattribs={"layer": "POCKET"})
for cx, cy, start in [(W - r, r, 270), (W - r, H - r, 0), (r, H - r, 90), (r, r, 180)]:
    msp.add_arc((cx, cy), r, start, start + 90, dxfattribs={"layer": "POCKET"})

msp.add_circle((55, 25), 8.0, dxfattribs={"layer": "ISLANDS"})
msp.add_lwpolyline([(14, 8), (26, 8), (26, 16), (14, 16)], close=True,
                   dxfattribs={"layer": "ISLANDS"})

msp.add_lwpolyline([(100, 0), (130, 0), (130, 16), (116, 16), (116, 30), (100, 30)], close=True,
                   dxfattribs={"layer": "L"})

# (x, y, bulge): the bulge is tan(sweep / 4) of the arc to the next point, + counter-clockwise.
msp.add_lwpolyline([(150, 3, 0), (190, 3, 1), (190, 57, 0), (150, 57, 0), (150, 43, 0),
                    (190, 43, -1), (190, 17, 0), (150, 17, 0)], format="xyb", close=True,
                   dxfattribs={"layer": "GROOVE"})

out = sys.argv[1] if len(sys.argv) > 1 else "plate.dxf"
doc.saveas(out)
