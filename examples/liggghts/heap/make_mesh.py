#!/usr/bin/python3
"""Write the heap scene's plate as ASCII STL (SI units, metres).

meshes/plate.stl: a horizontal disc of radius Rp at z = 0, a fan of NSEG triangles around the
                  centre, normals up (+z, the granular side). Grains that roll off its rim
                  fall out of the box.

    /usr/bin/python3 make_mesh.py            # -> meshes/plate.stl next to this script
    /usr/bin/python3 make_mesh.py --out DIR
"""
import argparse
import math
import os


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "meshes"))
    ap.add_argument("--Rp", type=float, default=0.05, help="plate radius (m)")
    ap.add_argument("--nseg", type=int, default=32, help="triangles around the centre")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    rim = [(a.Rp * math.cos(2 * math.pi * k / a.nseg), a.Rp * math.sin(2 * math.pi * k / a.nseg))
           for k in range(a.nseg)]
    lines = ["solid plate\n"]
    for k in range(a.nseg):
        (x1, y1), (x2, y2) = rim[k], rim[(k + 1) % a.nseg]
        lines.append("  facet normal 0 0 1\n    outer loop\n"
                     "      vertex 0 0 0\n"
                     "      vertex %.9e %.9e 0\n      vertex %.9e %.9e 0\n"
                     "    endloop\n  endfacet\n" % (x1, y1, x2, y2))
    lines.append("endsolid plate\n")
    path = os.path.join(a.out, "plate.stl")
    with open(path, "w") as f:
        f.write("".join(lines))
    print("%s: %d triangles, plate radius %.4f m" % (path, a.nseg, a.Rp))


if __name__ == "__main__":
    main()
