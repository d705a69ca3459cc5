#!/usr/bin/env python3
"""Writes meander.dxf (ezdxf, Debian's python3-ezdxf): the 1 m centreline of the planning
benchmark, five 160 mm legs joined by four U-turns of radius 20 mm (1051.3 mm in all), on
layer MEANDER. Run here: /usr/bin/python3 make-meander.py"""
import ezdxf

doc = ezdxf.new("R2010")
doc.header["$INSUNITS"] = 4  # mm
m = doc.modelspace()
r, leg = 20.0, 160.0
for k in range(5):
    y = 2 * r * k
    x0, x1 = (0.0, leg) if k % 2 == 0 else (leg, 0.0)
    m.add_line((x0, y), (x1, y), dxfattribs={"layer": "MEANDER"})
    if k < 4:  # a U-turn to the next leg: on the right after an even leg, on the left after odd
        if k % 2 == 0:
            m.add_arc((leg, y + r), r, -90, 90, dxfattribs={"layer": "MEANDER"})
        else:
            m.add_arc((0.0, y + r), r, 90, 270, dxfattribs={"layer": "MEANDER"})
doc.saveas("meander.dxf")
