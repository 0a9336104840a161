"""Walls keep their own material: the fix wall/gran they replace, or an atom type.

One sphere (d = 1, density 1, g = 9.81) comes to rest on a wall of pair granular spheres of
E = 1e6. Its resting height is the wall law's, against native LAMMPS (fix wall/gran with the
same words, nve/sphere) and against the analytic overlap d = (m g / (k_n sqrt(r_eff)))^(2/3)
of Hertz or m g / k_n of Hooke:
- 'wall granular hertz/material 1e5 0.3 0.3 ... zplane 0 NULL': fix wall/gran's constant
  k_n = 4/3 E / (2 (1 - nu)), not the spheres' E;
- 'wall hooke/history 2000 NULL 50 NULL 0.5 1 zplane 0 NULL': k_n = 2000;
- 'wall type 2 zplane 0 NULL' with type 2 of E = 1e5: the mixed pair (1, 2),
  k_n = 4/3 / ((1 - nu^2) / E1 + (1 - nu^2) / E2);
- 'wall granular hertz/material ... zcylinder 2': gravity along x presses the sphere on the
  inside of a cylinder of radius 2, whose curvature fix wall/gran takes as -2 R
  (r_eff = 2 R r / (2 R - r)).
Each serial; the interaction walls also on two processes (the sphere's height identical).
"""

import math

import fibre_e2e as e2e

BASE = "\n".join(e2e.sphere_box("-3 3 -3 3 -1 5", types=2)) + """
create_atoms 1 single {x0} 0 0.6 units box
set atom 1 diameter 1.0 density 1.0
pair_style granular
pair_coeff 1 1 hertz/material 1e6 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji
pair_coeff 2 2 hertz/material 1e5 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji
neighbor 0.2 bin
timestep {dt}
fix g all gravity 9.81 vector {gravity}
{walls}
variable x equal x[1]
variable z equal z[1]
thermo_style custom step v_x v_z
thermo_modify norm no format float %.15g
thermo 1000
run 4000
"""

HERTZ = "granular hertz/material 1e5 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"
HOOKE = "hooke/history 2000 NULL 50 NULL 0.5 1"
M, G, R, NU = math.pi / 6, 9.81, 0.5, 0.3


def hertz_overlap(k_n, r_eff):
    return (M * G / (k_n * math.sqrt(r_eff))) ** (2.0 / 3.0)


# name, native wall fix (None: the pair's own), fix wall keyword, gravity, start x, coordinate,
# analytic rest position
CASES = [
    ("hertz_material", "wall/gran " + HERTZ + " zplane 0 NULL", "wall " + HERTZ + " zplane 0 NULL",
     "0 0 -1", 0.0, "v_z", R - hertz_overlap(4.0 / 3.0 * 1e5 / (2 * (1 - NU)), R)),
    ("hooke_history", "wall/gran " + HOOKE + " zplane 0 NULL", "wall " + HOOKE + " zplane 0 NULL",
     "0 0 -1", 0.0, "v_z", R - M * G / 2000.0),
    ("type", None, "wall type 2 zplane 0 NULL", "0 0 -1", 0.0, "v_z",
     R - hertz_overlap(4.0 / 3.0 / ((1 - NU * NU) / 1e6 + (1 - NU * NU) / 1e5), R)),
    ("cylinder", "wall/gran " + HERTZ + " zcylinder 2", "wall " + HERTZ + " zcylinder 2",
     "1 0 0", 1.0, "v_x",
     2.0 - R + hertz_overlap(4.0 / 3.0 * 1e5 / (2 * (1 - NU)), 2 * 2.0 * R / (2 * 2.0 - R))),
]


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("walls' own materials, against native and the analytic rest")
    for name, native_wall, wall, gravity, x0, coord, expected in CASES:
        fields = {"x0": x0, "gravity": gravity, "dt": 0.001}
        fibre = dict(fields, walls="fix fc all fibre_contact " + wall)
        runs = [e2e.run_lmp(args, BASE.format(**fibre), name + "_np%d" % np, np=np)
                for np in ((1, 2) if name in ("hertz_material", "cylinder") else (1,))]
        if not all(ck.ran(run) for run in runs):
            continue
        rest = runs[0].last(coord)
        ck.check(abs(rest - expected) < 1e-6, "%s: rests at the wall law's analytic position"
                 % name, "%.12g vs %.12g" % (rest, expected))
        if len(runs) > 1:
            ck.check(runs[1].last(coord) == rest, "%s: np 2 rests at the serial position"
                     % name, "%.15g vs %.15g" % (runs[1].last(coord), rest))
        if native_wall:
            deck = BASE.format(**dict(fields, walls="fix n all nve/sphere\nfix w all "
                                      + native_wall))
            native = e2e.run_lmp(args, deck, name + "_native")
            if ck.ran(native):
                ck.check(abs(native.last(coord) - rest) < 1e-6, "%s: rests where native does"
                         % name, "%.12g vs native %.12g" % (rest, native.last(coord)))
    ck.close()


if __name__ == "__main__":
    main()
