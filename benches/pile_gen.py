#!/usr/bin/env python3
"""Write the pile scenes of benches/pile_compare.py: N floating one-link models dropped into a bin.

Usage: python benches/pile_gen.py   (writes benches/scenes/pile_{boxes,mixed}_{16,64,256,1024}.json)

A bin: the ground and four wall obstacles (0.1 m thick, 0.6 m high) around a square floor whose
side grows with N (about 2.2 objects of 0.1 m per 0.2 m cell: side = 0.2·ceil(sqrt(N/2.2)) m, at
least 0.6 m). The objects start on a lattice of 0.2 m cells, layer over layer from 0.1 m up (N/
(cells per layer) layers), each turned by a small deterministic angle so that they do not land flat
on one another; "boxes": 0.1 m cubes of 1 kg (benches/pile/box.urdf); "mixed": balls (r 0.05 m),
boxes and cylinders (r 0.05 m, 0.1 m long) in turn. Friction 0.8 everywhere. Deterministic (no
random numbers): the committed files are what this writes.
"""
import json
import math
import os

HERE = os.path.dirname(os.path.abspath(__file__))
SIZES = [16, 64, 256, 1024]
KINDS = {"boxes": ["box"], "mixed": ["ball", "box", "cylinder"]}
CELL = 0.2
WALL_T, WALL_H = 0.1, 0.6
FRICTION = 0.8


def quat_xyzw(axis, angle):
    n = math.sqrt(sum(a * a for a in axis))
    s = math.sin(angle / 2) / n
    return [axis[0] * s, axis[1] * s, axis[2] * s, math.cos(angle / 2)]


def scene(kind, n):
    per_side = max(3, math.ceil(math.sqrt(n / 2.2)))
    side = CELL * per_side
    per_layer = per_side * per_side
    models = []
    for k in range(n):
        layer, cell = divmod(k, per_layer)
        i, j = divmod(cell, per_side)
        x = -side / 2 + CELL * (i + 0.5)
        y = -side / 2 + CELL * (j + 0.5)
        z = 0.1 + CELL * layer
        shape = KINDS[kind][k % len(KINDS[kind])]
        ang = 0.3 + 0.37 * ((k * 7919) % 11) / 11.0
        axis = [1.0, 0.5 * ((k % 3) - 1), 0.3 * ((k % 5) - 2)]
        models.append({"name": "o%d" % k, "urdf": "../pile/%s.urdf" % shape, "base": "floating",
                       "position": [round(x, 6), round(y, 6), round(z, 6)],
                       "orientation_xyzw": [round(a, 9) for a in quat_xyzw(axis, ang)],
                       "friction": FRICTION})
    h = side / 2 + WALL_T / 2
    long = side + 2 * WALL_T
    walls = [("wall_x0", [WALL_T, long, WALL_H], [-h, 0, WALL_H / 2]),
             ("wall_x1", [WALL_T, long, WALL_H], [h, 0, WALL_H / 2]),
             ("wall_y0", [side, WALL_T, WALL_H], [0, -h, WALL_H / 2]),
             ("wall_y1", [side, WALL_T, WALL_H], [0, h, WALL_H / 2])]
    obstacles = [{"name": nm, "box": [round(x, 6) for x in b], "position": [round(x, 6) for x in p],
                  "friction": FRICTION} for nm, b, p in walls]
    return {"ground": {"height": 0.0, "friction": FRICTION}, "obstacles": obstacles, "models": models}


def main():
    out = os.path.join(HERE, "scenes")
    for kind in KINDS:
        for n in SIZES:
            path = os.path.join(out, "pile_%s_%d.json" % (kind, n))
            with open(path, "w") as fh:
                json.dump(scene(kind, n), fh, indent=1)
                fh.write("\n")
            print(path)


if __name__ == "__main__":
    main()
