#!/usr/bin/python3
"""Write the mixer's meshes as ASCII STL (SI units, metres).

meshes/drum.stl:  a cylindrical drum, axis z, radius R, floor at z = 0, open top at z = H;
                  side wall as NSEG rectangles (2 triangles each), floor as a fan of NSEG
                  triangles. Normals point into the drum (the granular side).
meshes/blade.stl: a straight two-armed paddle through the axis, a closed box from x = -L to
                  x = +L, y = -w/2 .. +w/2, z = z0 .. z1; each face divided into NX strips
                  along x. Normals point out of the box (the granular side).
                  The deck turns it about the z axis (fix move/mesh ... rotate).

    /usr/bin/python3 make_mesh.py            # -> meshes/ next to this script
    /usr/bin/python3 make_mesh.py --out DIR

Defaults (matching scene.mixer): R = 0.05, H = 0.12, 32 facets; blade L = 0.048 (2 mm from
the drum, less than a sphere diameter), w = 0.006, z0 = 0.002 (2 mm above the floor), z1 = 0.022.
"""
import argparse
import math
import os


def cross(u, v):
    return [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]


def facet(out, a, b, c, want):
    """Triangle a, b, c; reorder it so that its normal points along `want` (a vector)."""
    n = cross([b[i] - a[i] for i in range(3)], [c[i] - a[i] for i in range(3)])
    if sum(n[i] * want[i] for i in range(3)) < 0:
        b, c = c, b
        n = [-x for x in n]
    ln = math.sqrt(sum(x * x for x in n))
    n = [x / ln for x in n]
    out.append("  facet normal %.9e %.9e %.9e\n    outer loop\n" % tuple(n)
               + "".join("      vertex %.9e %.9e %.9e\n" % tuple(p) for p in (a, b, c))
               + "    endloop\n  endfacet\n")


def quad(out, a, b, c, d, want):
    facet(out, a, b, c, want)
    facet(out, a, c, d, want)


def write(path, name, out):
    with open(path, "w") as f:
        f.write("solid %s\n%sendsolid %s\n" % (name, "".join(out), name))
    print("%s: %d triangles" % (path, len(out)))


def drum(R, H, nseg):
    out = []
    pts = [(R * math.cos(2 * math.pi * k / nseg), R * math.sin(2 * math.pi * k / nseg))
           for k in range(nseg)]
    for k in range(nseg):
        (x0, y0), (x1, y1) = pts[k], pts[(k + 1) % nseg]
        xm, ym = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        inward = (-xm, -ym, 0.0)
        quad(out, (x0, y0, 0.0), (x1, y1, 0.0), (x1, y1, H), (x0, y0, H), inward)
        facet(out, (0.0, 0.0, 0.0), (x0, y0, 0.0), (x1, y1, 0.0), (0.0, 0.0, 1.0))
    return out


def blade(L, w, z0, z1, nx):
    out = []
    xs = [-L + 2 * L * i / nx for i in range(nx + 1)]
    y0, y1 = -0.5 * w, 0.5 * w
    for xa, xb in zip(xs[:-1], xs[1:]):
        quad(out, (xa, y0, z0), (xb, y0, z0), (xb, y0, z1), (xa, y0, z1), (0, -1, 0))  # -y face
        quad(out, (xa, y1, z0), (xb, y1, z0), (xb, y1, z1), (xa, y1, z1), (0, 1, 0))   # +y face
        quad(out, (xa, y0, z0), (xb, y0, z0), (xb, y1, z0), (xa, y1, z0), (0, 0, -1))  # bottom
        quad(out, (xa, y0, z1), (xb, y0, z1), (xb, y1, z1), (xa, y1, z1), (0, 0, 1))   # top
    quad(out, (-L, y0, z0), (-L, y1, z0), (-L, y1, z1), (-L, y0, z1), (-1, 0, 0))      # tips
    quad(out, (L, y0, z0), (L, y1, z0), (L, y1, z1), (L, y0, z1), (1, 0, 0))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default=os.path.join(os.path.dirname(os.path.abspath(__file__)),
                                                  "meshes"))
    ap.add_argument("--R", type=float, default=0.05, help="drum radius (m)")
    ap.add_argument("--H", type=float, default=0.12, help="drum height (m)")
    ap.add_argument("--nseg", type=int, default=32, help="facets around the drum")
    ap.add_argument("--L", type=float, default=0.048, help="blade half-length (m)")
    ap.add_argument("--w", type=float, default=0.006, help="blade thickness (m)")
    ap.add_argument("--z0", type=float, default=0.002, help="blade bottom (m)")
    ap.add_argument("--z1", type=float, default=0.022, help="blade top (m)")
    ap.add_argument("--nx", type=int, default=8, help="strips along the blade")
    a = ap.parse_args()
    # the inscribed polygon's flat sides are closer to the axis than R
    assert a.L < a.R * math.cos(math.pi / a.nseg), "blade tip outside the drum's facets"
    os.makedirs(a.out, exist_ok=True)
    write(os.path.join(a.out, "drum.stl"), "drum", drum(a.R, a.H, a.nseg))
    write(os.path.join(a.out, "blade.stl"), "blade", blade(a.L, a.w, a.z0, a.z1, a.nx))


if __name__ == "__main__":
    main()
