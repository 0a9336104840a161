"""Faults: deep overlaps at the start are removed at the recovery speed the log promises.

Spheres of d = 1 and 2500 kg/m^3 created into each other or into the floor (zplane 0) by 6, 20
and 50% of a diameter, pair style granular hertz/material E = 1e5, 1e8 and 7e10 (tsuji damping,
Mindlin friction), dt 1e-3, no gravity, under compliance material (the default) and compliance
auto. The log's warning names the recovery speed; the pass rule:
- no sphere faster than it (a pair of equal spheres: each at half of it), no NaN, none lost;
- under compliance material no faster than native LAMMPS's own spring pushes the same start
  apart (nve/sphere with the pair style, fix wall/gran for the floor), where native finishes:
  a soft overlap is released as slowly as native releases it;
- where the recovery speed binds (E >= 1e8, and native's spring pushes faster or native's
  state turns NaN), the spheres part at no less than 90% of it; overlaps beyond 5% of a
  diameter (10 steps of it) are penetrations, opened by the split recovery's displacement at
  no less than 90% of it (the gap over the first five steps) while the spheres stay at rest.
The pair at 20% also on two processes (one sphere each): the same speeds. A lattice of 1694
spheres (E = 1e7, dt 0.002, gravity) whose bottom layer's centres lie on the floor: none lost
and none rises faster than the recovery speed, serial and on two processes.
A sphere at 1e3 m/s onto the floor (E = 7e10), moving 1 a step against a neighbor skin of 0.2:
the log says that it outruns the skin (no deck above does), and the sphere does not pass the
floor: it rebounds, its centre always above it.
"""

import re

import fibre_e2e as e2e

LAW = "hertz/material {E} 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"

# the spheres' material, the step and the fix of the pair and wall decks
SPHERES = """set atom * diameter 1.0 density 2500
pair_style granular
pair_coeff * * """ + LAW + """
neighbor 0.2 bin
timestep 1e-3
{fix}
"""

PAIR = "units si\n" + "\n".join(e2e.sphere_box("-2 2 -2 2 -2 2", processors="{procs}")) + """
create_atoms 1 single -0.4 0 0 units box
create_atoms 1 single {xb} 0 0 units box
""" + SPHERES + """compute vmax all reduce max vx
compute vmin all reduce min vx
variable gap equal x[2]-x[1]-1.0
thermo_style custom step atoms c_vmax c_vmin v_gap
thermo_modify lost warn format float %.15g
thermo 1
run 60
"""

WALL = "units si\n" + "\n".join(e2e.sphere_box("-2 2 -2 2 -1 3")) + """
create_atoms 1 single 0 0 {z0} units box
""" + SPHERES + """variable vz equal vz[1]
variable gap equal z[1]-0.5
thermo_style custom step atoms v_vz v_gap
thermo_modify lost warn format float %.15g
thermo 1
run 60
"""

LATTICE = "units si\n" + "\n".join(e2e.sphere_box("0 11 0 11 -0.5 20", boundary="p p f",
                                   processors="{procs}")) + """
lattice sc 1.0
region fill block 0 11 0 11 0 13 units box
create_atoms 1 region fill
set atom * diameter 1.0 density 2500
pair_style granular
pair_coeff * * """ + LAW.format(E="1e7") + """
neighbor 0.2 bin
neigh_modify every 1 delay 0
timestep 0.002
fix g all gravity 9.81 vector 0 0 -1
fix f all fibre_contact wall zplane 0 NULL
compute vmax all reduce max vz
thermo_style custom step atoms c_vmax ke
thermo_modify lost warn format float %.15g
thermo 10
run 300
"""

FAST = "units si\n" + "\n".join(e2e.sphere_box("-5 5 -5 5 -1 2000")) + """
create_atoms 1 single 0 0 10.3 units box
velocity all set 0 0 -1000
""" + SPHERES.format(E="7e10", fix="fix f all fibre_contact wall zplane 0 NULL") + """variable z equal z[1]
variable vz equal vz[1]
thermo_style custom step atoms v_z v_vz
thermo_modify lost warn format float %.15g
thermo 1
run 30
"""

NATIVE_WALL = ("fix f all nve/sphere\nfix w all wall/gran granular " + LAW +
               " zplane 0 NULL")


def recovery_speed(run):
    m = re.search(r"removed at recovery_speed ([0-9.eE+-]+)", run.output)
    return float(m.group(1)) if m else None


def fastest(run, columns):
    values = [v for c in columns for v in run.column(c)]
    return max(abs(v) for v in values) if values and e2e.finite(values) else float("nan")


def main():
    args = e2e.parse_args()
    checks = e2e.Checks("deep overlaps at the start")
    serial = {}
    for kind in ("pair", "wall"):
        for E in ("1e5", "1e8", "7e10"):
            for overlap in (0.06, 0.2, 0.5):
                deck = PAIR if kind == "pair" else WALL
                columns = ["c_vmax", "c_vmin"] if kind == "pair" else ["v_vz"]
                share = 0.5 if kind == "pair" else 1.0  # each of two equal spheres: half
                where = dict(E=E, xb=0.6 - overlap, z0=0.5 - overlap, procs="1 1 1")
                native = e2e.run_lmp(args, deck.format(
                    fix=NATIVE_WALL.format(E=E) if kind == "wall" else "fix f all nve/sphere",
                    **where), "native_%s_%s_%g" % (kind, E, overlap))
                native_speed = fastest(native, columns) if native.rc == 0 else None
                if native_speed is not None and not native_speed < float("inf"):
                    native_speed = None  # native's state is NaN: no reference
                for compliance in ("material", "auto"):
                    if kind == "wall" and compliance == "auto" and overlap != 0.2:
                        continue
                    walls = "wall zplane 0 NULL " if kind == "wall" else ""
                    fix = "fix f all fibre_contact %scompliance %s" % (walls, compliance)
                    name = "%s_%s_%g_%s" % (kind, E, overlap, compliance)
                    run = e2e.run_lmp(args, deck.format(fix=fix, **where), name)
                    if not checks.ran(run):
                        continue
                    v_rec = recovery_speed(run)
                    speed = fastest(run, columns)
                    serial[name] = (speed, run.column("v_gap"))
                    what = "%s %s%% E %s compliance %s" % (kind, 100 * overlap, E, compliance)
                    checks.check(v_rec is not None, what + ": the log names the recovery speed")
                    checks.check("neighbor skin" not in run.output, what + ": no skin warning")
                    if v_rec is None:
                        continue
                    checks.check(run.last("Atoms") == (2 if kind == "pair" else 1),
                                 what + ": none lost")
                    checks.check(speed <= share * v_rec * (1 + 1e-6),
                                 what + ": no faster than the recovery speed",
                                 "%.6g against %.6g" % (speed, share * v_rec))
                    bound = share * v_rec
                    if compliance == "material" and native_speed is not None:
                        checks.check(speed <= 1.05 * native_speed,
                                     what + ": no faster than native's spring",
                                     "%.6g against native %.6g" % (speed, native_speed))
                    # where the recovery speed binds (native's spring is faster, or blows up)
                    split = overlap > 0.05  # beyond 10 steps of the recovery speed
                    if E != "1e5" and not split and (compliance == "auto" or
                                                     native_speed is None or
                                                     native_speed > bound):
                        checks.check(speed >= 0.9 * bound, what + ": removed at that speed",
                                     "%.6g against %.6g" % (speed, bound))
                    if E != "1e5" and split:
                        gaps = run.column("v_gap")
                        rate = (gaps[6] - gaps[1]) / (5 * 1e-3)
                        checks.check(rate >= 0.9 * v_rec and rate <= v_rec * (1 + 1e-6),
                                     what + ": opened at that speed by displacement",
                                     "%.6g against %.6g, the spheres at %.3g" % (rate, v_rec,
                                                                                speed))
    for E in ("1e8", "7e10"):
        fix = "fix f all fibre_contact compliance material"
        run = e2e.run_lmp(args, PAIR.format(E=E, xb=0.4, procs="2 1 1", fix=fix),
                          "pair_np2_%s" % E, np=2)
        if checks.ran(run):
            speed, gaps = fastest(run, ["c_vmax", "c_vmin"]), run.column("v_gap")
            speed1, gaps1 = serial["pair_%s_0.2_material" % E]
            # the spheres stay at rest while the displacement opens them: round-off speeds
            checks.check(e2e.rel_err(speed, speed1) < 1e-6 or max(speed, speed1) < 1e-9,
                         "pair 20%% E %s: two processes as one, speeds" % E,
                         "%.6g vs %.6g" % (speed, speed1))
            checks.check(len(gaps) == len(gaps1) and
                         max(abs(a - b) for a, b in zip(gaps, gaps1)) < 1e-9,
                         "pair 20%% E %s: two processes as one, the gap" % E)
    for np in (1, 2):
        run = e2e.run_lmp(args, LATTICE.format(procs="2 1 1" if np == 2 else "1 1 1"),
                          "lattice_np%d" % np, np=np)
        if not checks.ran(run):
            continue
        v_rec = recovery_speed(run)
        checks.check(v_rec is not None, "lattice np %d: the log names the recovery speed" % np)
        checks.check(min(run.column("Atoms")) == 1694, "lattice np %d: none lost" % np)
        speed = max(run.column("c_vmax"))
        checks.check(v_rec is not None and speed <= v_rec * (1 + 1e-6),
                     "lattice np %d: none rises faster than the recovery speed" % np,
                     "%.6g against %s" % (speed, v_rec))
        checks.check(e2e.finite(run.column("KinEng")), "lattice np %d: finite" % np)
    run = e2e.run_lmp(args, FAST, "fast")
    if checks.ran(run):
        checks.check("moves 1 in a step (speed 1000), more than the neighbor skin 0.2" in
                     run.output, "fast sphere: the log says it outruns the skin")
        checks.check(min(run.column("v_z")) > 0 and run.last("v_vz") > 0,
                     "fast sphere: rebounds from the floor without passing it",
                     "lowest centre %.4g, last vz %.4g" % (min(run.column("v_z")),
                                                           run.last("v_vz")))
    checks.close()


if __name__ == "__main__":
    main()
