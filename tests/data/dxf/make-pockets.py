#!/usr/bin/env python3
"""Writes pockets.dxf, the pocket tests' drawing, with ezdxf (Debian's python3-ezdxf, a DXF
writer independent of trochomill's reader). Units mm. Run from this folder:
/usr/bin/python3 make-pockets.py

Layers (sharp corners unless said):
  RECT     a 60 x 40 mm rectangle at the origin
  L        an L: 50 x 20 mm and 20 x 50 mm arms, at x 100
  ISLB     a 70 x 50 mm pocket at x 200 whose islands are on ISL
  ISL      a 12 x 8 mm block at (215, 12) and a 6 mm radius boss at (250, 25)
  NECK     two 30 x 30 mm rooms joined by a 14 mm wide neck, at x 300
  CIRC     a circle of radius 20 mm at (450, 20)
  CHAN     a 60 x 14 mm channel at x 500 (narrower than 2 D for a 10 mm tool)
  RING     a circle of radius 24 mm at (620, 30) about an island on RINGI, a circle of 10 mm:
           a ring channel 14 mm wide
  THIN     a 40 x 40 mm room at x 700 with a channel 11.2 mm wide and 40 mm long off its
           side (narrower than D + 2 stock + R / 2)
  BAR      two 30 x 30 mm rooms at x 800 joined by a bar 10.45 mm wide and 30 mm long (barely
           wider than D + 2 stock for a 10 mm tool and 0.2 mm)
  SMALL    a 10 x 6 mm pocket at x 1000 whose island is on SMALLI, a circle of 1 mm at
           (1006, 3): the plate's pocket at a tenth, for a 1 mm tool
  SLIT     a 40 x 10.5 mm pocket at x 1100: too narrow for any clearing with a 10 mm tool and
           0.2 mm of stock (10.4 mm), only the finishing pass reaches it
  NEST     a 40 x 30 mm pocket at x 1200 and a circle of 6 mm about (1215, 15) on the same
           layer, as shops draw a part's outline and holes: the circle is an island
  NESTO, NESTI  the same rectangle and circle on two layers (boundary and islands)
  NESTX    a 4 mm circle at (1215, 15), inside NEST's hole (an island there stands in stock)
  CROSS    two 20 x 20 mm squares at x 1300 that overlap by a quarter (walls that cross)
  OPEN     an open polyline (a pocket's wall must be closed)
  OUT      an island outside RECT;  OVER  two islands inside RECT that overlap
"""
import ezdxf

doc = ezdxf.new("R2010", setup=False)
doc.header["$INSUNITS"] = 4
m = doc.modelspace()


def poly(points, layer):
    m.add_lwpolyline(points, close=True, dxfattribs={"layer": layer})


poly([(0, 0), (60, 0), (60, 40), (0, 40)], "RECT")
poly([(100, 0), (150, 0), (150, 20), (120, 20), (120, 50), (100, 50)], "L")
poly([(200, 0), (270, 0), (270, 50), (200, 50)], "ISLB")
poly([(215, 12), (227, 12), (227, 20), (215, 20)], "ISL")
m.add_circle((250, 25), 6.0, dxfattribs={"layer": "ISL"})
poly([(300, 0), (330, 0), (330, 8), (345, 8), (345, 0), (375, 0), (375, 30), (345, 30),
      (345, 22), (330, 22), (330, 30), (300, 30)], "NECK")
m.add_circle((450, 20), 20.0, dxfattribs={"layer": "CIRC"})
poly([(500, 0), (560, 0), (560, 14), (500, 14)], "CHAN")
m.add_circle((620, 30), 24.0, dxfattribs={"layer": "RING"})
m.add_circle((620, 30), 10.0, dxfattribs={"layer": "RINGI"})
poly([(700, 0), (740, 0), (740, 14.4), (780, 14.4), (780, 25.6), (740, 25.6), (740, 40),
      (700, 40)], "THIN")
poly([(800, 0), (830, 0), (830, 9.775), (860, 9.775), (860, 0), (890, 0), (890, 30), (860, 30),
      (860, 20.225), (830, 20.225), (830, 30), (800, 30)], "BAR")
poly([(1000, 0), (1010, 0), (1010, 6), (1000, 6)], "SMALL")
m.add_circle((1006, 3), 1.0, dxfattribs={"layer": "SMALLI"})
poly([(1100, 0), (1140, 0), (1140, 10.5), (1100, 10.5)], "SLIT")
m.add_lwpolyline([(0, 100), (50, 100), (50, 140)], dxfattribs={"layer": "OPEN"})
m.add_circle((80, 20), 5.0, dxfattribs={"layer": "OUT"})
m.add_circle((20, 20), 6.0, dxfattribs={"layer": "OVER"})
m.add_circle((28, 20), 6.0, dxfattribs={"layer": "OVER"})
for layer in ("NEST", "NESTO"):
    poly([(1200, 0), (1240, 0), (1240, 30), (1200, 30)], layer)
for layer in ("NEST", "NESTI"):
    m.add_circle((1215, 15), 6.0, dxfattribs={"layer": layer})
m.add_circle((1215, 15), 4.0, dxfattribs={"layer": "NESTX"})
poly([(1300, 0), (1320, 0), (1320, 20), (1300, 20)], "CROSS")
poly([(1310, 10), (1330, 10), (1330, 30), (1310, 30)], "CROSS")
doc.saveas("pockets.dxf")
