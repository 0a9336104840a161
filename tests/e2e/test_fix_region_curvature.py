"""A sphere in a spherical bowl: region walls take the region's curvature.

A sphere of radius 0.5 rests inside a spherical region of radius 1 (`side in`), its centre at
angle theta from the bottom. Both twins have one pair_coeff: hertz with explicit k_n, mindlin,
rolling sds with mu_roll 0.3, damping tsuji; native LAMMPS's wall is fix wall/gran/region with
the same coefficients.

LAMMPS gives a region contact the surface's radius of curvature (-R inside a sphere), and the
wall's laws the effective radius r R / (r + R) = 1.0, twice the sphere's. Friction holds the
contact point, so the sphere can only roll, and the rolling resistance mu_roll r_eff F_n holds
it for tan(theta) up to mu_roll r_eff / r = 0.6 (31 degrees). With a flat wall's r_eff = r it
would roll from tan(theta) = 0.3 (16.7 degrees).

Checked against native LAMMPS at a 25x smaller step: from 20 degrees both stay within a degree
of where they start; from 40 degrees both roll back to the same angle at 1 s (within 1
degree). On one process and on two. Before region walls took the curvature (r_eff = r), the
sphere rolled from 20 degrees to 13.3, and from 40 degrees past the bottom to -3.4.
"""

import math

import fibre_e2e as e2e

MATERIAL = ("hertz 1e5 0.3 tangential mindlin 2e4 1.0 0.5 rolling sds 1e3 10 0.3 "
            "damping tsuji")
BOWL, RADIUS = 1.0, 0.5


def deck(native, np, theta):
    lines = e2e.sphere_box("-2 2 -2 2 -2 2", processors="2 1 1" if np == 2 else None)
    d = BOWL - RADIUS + 1e-4  # the centre's distance from the bowl's centre
    x, z = d * math.sin(math.radians(theta)), -d * math.cos(math.radians(theta))
    lines += [
        "create_atoms 1 single %.12g 0 %.12g units box" % (x, z),
        "set atom * diameter %g density 1.0" % (2 * RADIUS),
        "region bowl sphere 0 0 0 %g side in units box" % BOWL,
        "pair_style granular",
        "pair_coeff * * " + MATERIAL,
        "neighbor 0.3 bin",
        "fix g all gravity 9.81 vector 0 0 -1",
        "timestep %g" % (1e-4 if native else 2.5e-3),
    ]
    if native:
        lines += ["fix i all nve/sphere",
                  "fix w all wall/gran/region granular " + MATERIAL + " region bowl"]
    else:
        lines += ["fix fc all fibre_contact wall region bowl"]
    lines += [
        "variable theta equal atan2(x[1],-z[1])*180/PI",
        "thermo_style custom step time v_theta",
        "thermo_modify format float %.12g",
        "thermo %d" % (10000 if native else 400),
        "run %d" % (10000 if native else 400),
    ]
    return "\n".join(lines) + "\n"


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("a sphere in a spherical bowl: the region's curvature")
    angle = {}
    for theta in (20.0, 40.0):
        for tag, native, np in [("native", True, 1), ("fibre_np1", False, 1),
                                ("fibre_np2", False, 2)]:
            run = e2e.run_lmp(args, deck(native, np, theta), "bowl_%g_%s" % (theta, tag), np=np)
            if not ck.ran(run):
                continue
            angle[(theta, tag)] = run.last("v_theta")  # at 1 s
            if not native:
                ck.check(run.output.count("did not converge") == 0,
                         "%s from %g degrees: every step converged" % (tag, theta))
    for tag in ("fibre_np1", "fibre_np2"):
        held, native_held = angle.get((20.0, tag)), angle.get((20.0, "native"))
        if held is not None and native_held is not None:
            ck.check(abs(held - 20.0) < 1.0 and abs(native_held - 20.0) < 1.0,
                     "%s: from 20 degrees the rolling resistance holds it, as native's" % tag,
                     "%.4f and native %.4f degrees at 1 s" % (held, native_held))
        back, native_back = angle.get((40.0, tag)), angle.get((40.0, "native"))
        if back is not None and native_back is not None:
            ck.check(abs(back - native_back) < 1.0,
                     "%s: from 40 degrees it rolls back as native's does" % tag,
                     "%.4f and native %.4f degrees at 1 s" % (back, native_back))
    ck.close()


if __name__ == "__main__":
    main()
