#!/usr/bin/env python3
"""Writes cored-blank.stl, the stock of cored.toml, with FreeCAD (Debian's freecad-python3: its
OpenCASCADE solid and mesher, independent of trochomill). Units mm, the drawing's frame.

A blank 90 x 60 x 12 mm (x -5 .. 85, y -5 .. 55, z -12 .. 0) over plate.dxf's pocket, with a
cored cavity: a drafted round core, 20 mm across at the top face, 16 mm at its floor 4.5 mm
down, centred at (36, 33). Run from this folder: /usr/bin/python3 make-blank.py
"""
import sys

sys.path.append("/usr/lib/freecad-python3/lib")
import FreeCAD  # noqa: E402  (first: it sets up the other modules)
import MeshPart  # noqa: E402
import Part  # noqa: E402

Vector = FreeCAD.Vector

blank = Part.makeBox(90, 60, 12, Vector(-5, -5, -12)).cut(
    Part.makeCone(8, 10, 4.5, Vector(36, 33, -4.5)))
mesh = MeshPart.meshFromShape(Shape=blank, LinearDeflection=0.01, AngularDeflection=0.1,
                              Relative=False)
if not mesh.isSolid() or mesh.hasNonManifolds():
    sys.exit("make-blank: the mesh is not a closed solid")
mesh.write(sys.argv[1] if len(sys.argv) > 1 else "cored-blank.stl")
