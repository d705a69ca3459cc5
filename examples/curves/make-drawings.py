#!/usr/bin/env python3
"""Writes the drawings of examples/curves with ezdxf (Debian's python3-ezdxf, an independent
DXF writer; the format: Autodesk's DXF Reference, R2010). Run from this folder:
/usr/bin/python3 make-drawings.py"""
import ezdxf

doc = ezdxf.new("R2010")
doc.header["$INSUNITS"] = 4  # mm
m = doc.modelspace()
# RING: a circle of radius 30 mm about (40, 40): the centreline of a ring slot.
m.add_circle((40, 40), 30, dxfattribs={"layer": "RING"})
# BEND: a line, a 90 degree arc of radius 20 mm and a line: an L-shaped slot with a round bend.
m.add_line((0, 0), (40, 0), dxfattribs={"layer": "BEND"})
m.add_arc((40, 20), 20, -90, 0, dxfattribs={"layer": "BEND"})
m.add_line((60, 20), (60, 50), dxfattribs={"layer": "BEND"})
# OUTLINE: the part's outline (not cut; the report draws it).
m.add_lwpolyline([(-15, -15), (95, -15), (95, 85), (-15, 85)], close=True,
                 dxfattribs={"layer": "OUTLINE"})
doc.saveas("part.dxf")
