#!/usr/bin/python3
"""Write the hopper's wall mesh as an ASCII STL (SI units, metres).

A cylindrical bin (radius R, from z = hc to z = H) on a conical hopper section that narrows
to a circular orifice of radius ro at z = 0 (the orifice plane). Both are open polygonal
surfaces with NSEG facets around the axis; the top is open. Every triangle is wound so that
its normal points into the bin, towards the axis (the granular side). The orifice is closed
during filling by a plane wall at z = 0 defined in the deck (fix plug), not by this mesh.

    /usr/bin/python3 make_mesh.py            # -> meshes/hopper.stl next to this script
    /usr/bin/python3 make_mesh.py --out DIR  # -> DIR/hopper.stl

Defaults (matching scene.hopper): R = 0.040, ro = 0.0175 (orifice diameter 35 mm = 7 mean
particle diameters of 5 mm), cone half-angle 30 degrees (hc = 0.039), H = 0.215, 32 facets.
"""
import argparse
import math
import os


def facet(out, a, b, c):
    """One triangle a, b, c (counter-clockwise seen from the side its normal points to)."""
    u = [b[i] - a[i] for i in range(3)]
    v = [c[i] - a[i] for i in range(3)]
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    ln = math.sqrt(sum(x * x for x in n))
    n = [x / ln for x in n]
    out.append("  facet normal %.9e %.9e %.9e\n    outer loop\n" % tuple(n)
               + "".join("      vertex %.9e %.9e %.9e\n" % tuple(p) for p in (a, b, c))
               + "    endloop\n  endfacet\n")
    return n


def ring(r, z, nseg):
    return [(r * math.cos(2 * math.pi * k / nseg), r * math.sin(2 * math.pi * k / nseg), z)
            for k in range(nseg)]


def band(out, lower, upper):
    """Quads between two rings as two triangles each, normals towards the axis."""
    nseg = len(lower)
    for k in range(nseg):
        a, b = lower[k], lower[(k + 1) % nseg]
        c, d = upper[(k + 1) % nseg], upper[k]
        # a -> d -> c is clockwise seen from outside, i.e. its normal points inwards
        for tri in ((a, d, c), (a, c, b)):
            n = facet(out, *tri)
            centre = [sum(p[i] for p in tri) / 3 for i in range(3)]
            assert n[0] * centre[0] + n[1] * centre[1] < 0, "normal points outwards"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "meshes"))
    ap.add_argument("--R", type=float, default=0.040, help="bin radius (m)")
    ap.add_argument("--ro", type=float, default=0.0175, help="orifice radius (m)")
    ap.add_argument("--angle", type=float, default=30.0,
                    help="cone half-angle from the vertical (degrees)")
    ap.add_argument("--H", type=float, default=0.215, help="height of the bin's top (m)")
    ap.add_argument("--nseg", type=int, default=32, help="facets around the axis")
    a = ap.parse_args()
    hc = (a.R - a.ro) / math.tan(math.radians(a.angle))
    out = []
    band(out, ring(a.ro, 0.0, a.nseg), ring(a.R, hc, a.nseg))   # cone
    band(out, ring(a.R, hc, a.nseg), ring(a.R, a.H, a.nseg))    # cylinder
    os.makedirs(a.out, exist_ok=True)
    path = os.path.join(a.out, "hopper.stl")
    with open(path, "w") as f:
        f.write("solid hopper\n" + "".join(out) + "endsolid hopper\n")
    print("%s: %d triangles, cone z = 0 .. %.4f m, cylinder to z = %.4f m, orifice D = %.4f m"
          % (path, len(out), hc, a.H, 2 * a.ro))


if __name__ == "__main__":
    main()
