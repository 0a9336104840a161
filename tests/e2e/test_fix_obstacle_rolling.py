"""A sphere rolling off a fixed sphere: an obstacle atom takes the pair's effective radius.

Two spheres of diameter 1 and density 1. The lower one stays outside the fix's group (a fixed
obstacle). The upper one starts at rest on top of it, its centre at angle theta from the
vertical. Both twins have one pair_coeff: hertz with explicit k_n, mindlin, rolling sds with
mu_roll 0.3, damping tsuji.

Friction (mu 0.5) holds the contact point, so the sphere can only roll. At rest, the torque
of gravity about its centre (m g sin(theta) r) must be carried by the rolling resistance,
mu_roll r_eff m g cos(theta), with LAMMPS's r_eff = r r / (r + r) = r / 2 for two spheres. So
it rolls off for tan(theta) > mu_roll / 2 = 0.15 (8.5 degrees) and stays below.

Checked against native LAMMPS (the pair style with fix nve/sphere on the upper sphere,
a 25x smaller step): from 15 degrees the angle at 0.5 s and 1 s within 10% of native's rise;
from 7 degrees both stop within a degree and then rock on the damped rolling spring by less
than 0.1 degree, and every fibre step converges. On one process and on two (the spheres on
different processes). Before the obstacle took the pair's r_eff (it took r, as for a plane),
the sphere stopped at 15.5 degrees (tan(theta) up to mu_roll).
"""

import math

import fibre_e2e as e2e

MATERIAL = ("hertz 1e5 0.3 tangential mindlin 2e4 1.0 0.5 rolling sds 1e3 10 0.3 "
            "damping tsuji")


def deck(native, np, theta):
    lines = e2e.sphere_box("-3 3 -3 3 -3 3", processors="2 1 1" if np == 2 else None)
    x, z = math.sin(math.radians(theta)) * 0.9999, math.cos(math.radians(theta)) * 0.9999
    lines += [
        "create_atoms 1 single -0.01 0 0 units box",
        "create_atoms 1 single %.12g 0 %.12g units box" % (x - 0.01, z),
        "set atom * diameter 1.0 density 1.0",
        "group top id 2",
        "pair_style granular",
        "pair_coeff * * " + MATERIAL,
        "neighbor 0.3 bin",
        "fix g top gravity 9.81 vector 0 0 -1",
        "timestep %g" % (1e-4 if native else 2.5e-3),
        "fix i top nve/sphere" if native else "fix fc top fibre_contact",
        "variable theta equal atan2(x[2]-x[1],z[2]-z[1])*180/PI",
        "thermo_style custom step time v_theta",
        "thermo_modify format float %.12g",
        "thermo %d" % (500 if native else 20),
        "run %d" % (10000 if native else 400),
    ]
    return "\n".join(lines) + "\n"


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("a sphere rolling off an obstacle sphere: the pair's effective radius")
    runs = [("native", True, 1), ("fibre_np1", False, 1), ("fibre_np2", False, 2)]
    angles = {}
    run_warnings = {"fibre_np1": 0, "fibre_np2": 0}
    for theta in (15.0, 7.0):
        for tag, native, np in runs:
            run = e2e.run_lmp(args, deck(native, np, theta), "obstacle_%g_%s" % (theta, tag), np=np)
            if not ck.ran(run):
                continue
            angles[(theta, tag)] = run.column("v_theta")  # every 0.05 s from 0 to 1 s
            if not native:
                run_warnings[tag] += run.output.count("did not converge")
    for tag in ("fibre_np1", "fibre_np2"):
        native, fibre = angles.get((15.0, "native")), angles.get((15.0, tag))
        if native and fibre:
            for k, when in ((10, "0.5 s"), (20, "1 s")):
                ck.agree(fibre[k] - 15.0, native[k] - 15.0, 0.1,
                         "%s: from 15 degrees it rolls off as native does (rise at %s)"
                         % (tag, when), "%.4g")
        held, native_held = angles.get((7.0, tag)), angles.get((7.0, "native"))
        if held and native_held:
            # both settle by less than a degree (the springs load as the sphere starts to
            # roll) and from 0.5 s on only rock on the damped rolling spring, by a few
            # hundredths of a degree
            swing = [max(a[10:]) - min(a[10:]) for a in (held, native_held)]
            ck.check(all(abs(a[-1] - 7.0) < 1.0 for a in (held, native_held))
                     and all(s < 0.1 for s in swing),
                     "%s: from 7 degrees the rolling resistance holds it, as native's" % tag,
                     "%.4f and native %.4f degrees at 1 s; from 0.5 s within %.3f and %.3f"
                     % (held[-1], native_held[-1], swing[0], swing[1]))
            ck.check(run_warnings[tag] == 0, "%s: every step converged" % tag)
    ck.close()


if __name__ == "__main__":
    main()
