"""Walls: LAMMPS regions (a funnel: union of an open cone and a cylinder) and planes.

Stage 1: 40 spheres poured (fix pour) into a funnel closed at the bottom ('wall region hopper', the
union of a cone and a cylinder as in LAMMPS's granregion funnel example), frictionless so that
this test is about the walls alone. Every sphere stays inside the funnel, overlaps
(sphere-sphere and sphere-wall, f_fc[7]) stay below 1% of the diameter, and the pile comes
to rest.
Stage 2: the regions are deleted and redefined between runs with the cylinder open at the
bottom: the fix picks up the new region (looked up by ID at every run) and the spheres drain
out of the funnel.
Wall loads (f_ID[w][1..6]): a column of 4 spheres resting on the floor of a region box, beside
a plane it does not touch, loads the region with its weight (force down, torque about the
origin (0, W, 0): the weight acts at x = 1) and the plane it does not touch with nothing.
Planes: 64 spheres with random velocities in a box of six plane walls
('wall xplane/yplane/zplane lo hi', no friction, no gravity) never leave it.
"""

import math
import os

import fibre_e2e as e2e

D = 0.6
R_CYL, Z_CONE, R_TOP, Z_TOP = 0.8, 2.0, 3.0, 5.0

FUNNEL = """atom_style sphere
boundary f f f
newton off
comm_modify vel yes
region box block -4 4 -4 4 -6 8.5 units box
create_box 1 box
region cyl cylinder z 0 0 {rc} 0 {zc} side in units box open 2
region cone cone z 0 0 {rc} {rt} {zc} {zt} side in units box open 1 open 2
region hopper union 2 cone cyl
region ins cylinder z 0 0 2.0 5.2 7.8 side in units box
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.1 bin
timestep 0.005
fix g all gravity 1.0 vector 0 0 -1
fix fc all fibre_contact mu 0.0 wall region hopper
fix ins all pour 40 1 4551 region ins diam one {d} dens 1.0 1.0 vol 0.15 50
compute ke all ke
compute zmin all reduce min z
thermo_style custom step atoms c_ke c_zmin f_fc[3] f_fc[7] f_fc[11]
thermo_modify lost ignore norm no format float %.10g
thermo 100
dump d all custom 2000 funnel.*.atoms id x y z
dump_modify d sort id
run 2000
region hopper delete
region cyl delete
region cyl cylinder z 0 0 {rc} 0 {zc} side in units box open 1 open 2
region hopper union 2 cone cyl
run 1000
"""

BOX = """atom_style sphere
boundary f f f
newton off
comm_modify vel yes
region box block -3 3 -3 3 -3 3 units box
create_box 1 box
lattice sc 1.3717421
region ins block -1.5 1.5 -1.5 1.5 -1.5 1.5 units box
create_atoms 1 region ins
set group all diameter 0.7 density 1.0
velocity all create 1.0 5511 loop geom
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.2 bin
timestep 0.005
fix fc all fibre_contact mu 0.0 wall xplane -2 2 wall yplane -2 2 wall zplane -2 2
compute xmax all reduce max x y z
compute xmin all reduce min x y z
thermo_style custom step atoms c_xmin[1] c_xmin[2] c_xmin[3] c_xmax[1] c_xmax[2] c_xmax[3] &
             f_fc[7] f_fc[11]
thermo_modify format float %.10g
thermo 10
run 1000
"""


COLUMN = """atom_style sphere
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
region box block -3 3 -3 3 -1 6 units box
create_box 1 box
create_atoms 1 single 1.0 0 0.5 units box
create_atoms 1 single 1.0 0 1.5 units box
create_atoms 1 single 1.0 0 2.5 units box
create_atoms 1 single 1.0 0 3.5 units box
set group all diameter 1.0 density 1.0
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.1 bin
timestep 0.005
fix g all gravity 1.0 vector 0 0 -1
region cup block -2 2 -2 2 0 5 side in units box
fix fc all fibre_contact mu 0.5 wall region cup wall xplane -2.5 NULL
thermo_style custom step f_fc[1][1] f_fc[1][2] f_fc[1][3] f_fc[1][4] f_fc[1][5] &
             f_fc[1][6] f_fc[2][1] f_fc[2][3]
thermo_modify norm no format float %.15g
thermo 100
run 400
"""


def inside_funnel(x, y, z, tol):
    rad = math.hypot(x, y)
    if z <= Z_CONE:
        return z >= D / 2 - tol and rad <= R_CYL - D / 2 + tol
    r_local = R_CYL + (z - Z_CONE) * (R_TOP - R_CYL) / (Z_TOP - Z_CONE)
    return rad <= r_local + tol


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("walls: region funnel and plane box")
    deck = FUNNEL.format(rc=R_CYL, zc=Z_CONE, rt=R_TOP, zt=Z_TOP, d=D)
    run = e2e.run_lmp(args, deck, "walls_funnel")
    if ck.ran(run, "funnel: run completes"):
        first, second = run.thermo[0], run.thermo[1]
        ck.check(first[-1]["Atoms"] == 40, "funnel: 40 spheres", "%g" % first[-1]["Atoms"])
        worst = max(r["f_fc[7]"] for r in first)
        ck.check(worst < 0.01 * D, "funnel: overlaps below 1% of the diameter",
                 "max f_fc[7] = %.3g (%.3g%% of d)" % (worst, 100 * worst / D))
        ck.check(first[-1]["f_fc[11]"] > 0, "funnel: region wall contacts",
                 "%g wall contacts of %g" % (first[-1]["f_fc[11]"], first[-1]["f_fc[3]"]))
        frame = e2e.parse_dump(os.path.join(args.workdir, "funnel.2000.atoms"))[-1]
        atoms = e2e.dump_by_id(frame)
        outside = [i for i, a in atoms.items() if not inside_funnel(a["x"], a["y"], a["z"],
                                                                    0.01 * D)]
        ck.check(not outside, "funnel: every sphere inside the funnel",
                 "%d outside%s, lowest z %.4g"
                 % (len(outside), "".join(" (id %d at %.4g %.4g %.4g)" % (i, atoms[i]["x"],
                                          atoms[i]["y"], atoms[i]["z"]) for i in outside[:3]),
                    min(a["z"] for a in atoms.values())))
        # Frictionless spheres in a cone keep rearranging a little: the largest KE of the
        # last 500 steps against the peak of the pour (measured 0.0097 and, before the
        # Gauss-Seidel sweeps, 0.0064, of 13.7).
        peak = max(r["c_ke"] for r in first)
        late = max(r["c_ke"] for r in first if r["Step"] >= 1500)
        ck.check(late < 1e-3 * peak, "funnel: the pile comes to rest",
                 "largest KE of steps 1500-2000 %.3g, peak %.3g" % (late, peak))
        zmin = second[-1]["c_zmin"]
        ck.check(zmin < -1.0, "funnel: redefined region (bottom opened) drains the funnel",
                 "lowest sphere at z = %.3g after the second run" % zmin)

    run = e2e.run_lmp(args, COLUMN, "walls_column")
    if ck.ran(run, "column: run completes"):
        weight = 4 * math.pi / 6
        load = [run.last("f_fc[1][%d]" % k) for k in range(1, 7)]
        # the weight acts at x = 1: torque about the origin r x F = (1, 0, 0) x (0, 0, -W)
        expected = [0.0, 0.0, -weight, 0.0, weight, 0.0]
        worst = max(abs(a - b) for a, b in zip(load, expected))
        ck.check(worst < 1e-4 * weight, "column: the region's load f_fc[1][1..6] is the weight "
                 "W = %.6g down, torque (0, W, 0) about the origin" % weight,
                 "F = (%.3g, %.3g, %.9g), T = (%.3g, %.9g, %.3g)" % tuple(load))
        ck.check(run.last("f_fc[2][1]") == 0 and run.last("f_fc[2][3]") == 0,
                 "column: the untouched plane carries nothing")

    run = e2e.run_lmp(args, BOX, "walls_box")
    if ck.ran(run, "box of planes: run completes"):
        rows = run.thermo[0]
        lo = min(min(r["c_xmin[1]"], r["c_xmin[2]"], r["c_xmin[3]"]) for r in rows)
        hi = max(max(r["c_xmax[1]"], r["c_xmax[2]"], r["c_xmax[3]"]) for r in rows)
        bound = 2 - 0.35 + 0.01 * 0.7
        ck.check(lo >= -bound and hi <= bound, "box of planes: spheres stay inside",
                 "centres in [%.4g, %.4g], walls allow +-%.4g" % (lo, hi, bound))
        ck.check(max(r["f_fc[11]"] for r in rows) > 0, "box of planes: wall contacts",
                 "max %g" % max(r["f_fc[11]"] for r in rows))
    ck.close()


if __name__ == "__main__":
    main()
