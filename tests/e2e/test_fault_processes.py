"""Faults: a process with no atoms, and every atom migrating between processes within steps
that take substeps. A row of 4 touching spheres (d = 1, density 1000, hertz/material E = 1e7,
Mindlin, tsuji, walls of the same material, no gravity) starts in the left half of a box
10 long, at 2 m/s along it, at a step of 0.79 collision times (3 substeps). On 2 processes
(`processors 2 1 1`) the right one owns nothing at the start; the row crosses into it,
strikes the far wall in steps of 3 substeps, and comes back across.

Pass rule: nothing lost or NaN on 1 and 2 processes; every sphere crosses to the right half
and back (the row's lowest x above 5, later its highest below 5); on 2 processes the kinetic
energy within 1e-3 of the initial one and the row's centre within 1e-3 of the serial run's at
every output (a row's collisions are not chaotic: the processes change only the sweeps'
order, within the solver's tolerance).
"""

import fibre_e2e as e2e

LAW = "hertz/material 1e7 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"
WALLS = " ".join("wall granular %s %s" % (LAW, w)
                 for w in ("xplane 0 10", "yplane 0 4", "zplane 0 4"))

DECK = "\n".join(e2e.sphere_box("0 10 0 4 0 4", processors="{procs}")) + """
lattice sc 1.0
region row block 0.5 4.5 1.5 2.5 1.5 2.5 units box
create_atoms 1 region row
set type 1 diameter 1.0
set type 1 density 1000
velocity all set 2.0 0.0 0.0 units box
pair_style granular
pair_coeff * * """ + LAW + """
neighbor 0.3 bin
neigh_modify every 1 delay 0
timestep 0.05
fix f all fibre_contact """ + WALLS + """
variable xc equal xcm(all,x)
variable xlo equal bound(all,xmin)
variable xhi equal bound(all,xmax)
thermo_style custom step atoms ke v_xc v_xlo v_xhi f_f[21]
thermo_modify lost warn format float %.12g
thermo 5
run 600
"""


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("faults: an empty process, and atoms migrating in steps with substeps")
    runs = {}
    for np in (1, 2):
        run = e2e.run_lmp(args, DECK.format(procs="2 1 1" if np == 2 else "1 1 1"),
                          "row_np%d" % np, np=np)
        what = "np %d: " % np
        if not ck.ran(run):
            continue
        runs[np] = run
        ke, xlo, xhi = run.column("KinEng"), run.column("v_xlo"), run.column("v_xhi")
        ck.check(min(run.column("Atoms")) == 4 and e2e.finite(ke), what + "nothing lost or NaN")
        crossed = [k for k, x in enumerate(xlo) if x > 5.0]
        back = crossed and any(x < 5.0 for x in xhi[crossed[0]:])
        ck.check(bool(crossed) and back, what + "every sphere crosses to the right half and back",
                 "lowest x at most %.4g" % max(xlo))
        ck.check(max(run.column("f_f[21]")) >= 3, what + "the impacts take substeps",
                 "%d at most" % max(run.column("f_f[21]")))
    if 1 in runs and 2 in runs:
        a, b = runs[1], runs[2]
        ke0 = a.column("KinEng")[0]
        dke = max(abs(x - y) for x, y in zip(a.column("KinEng"), b.column("KinEng"))) / ke0
        dx = max(abs(x - y) for x, y in zip(a.column("v_xc"), b.column("v_xc")))
        ck.check(len(a.column("KinEng")) == len(b.column("KinEng")) and dke < 1e-3,
                 "np 2: kinetic energy as serial's within 1e-3 of the initial", "%.3g" % dke)
        ck.check(dx < 1e-3, "np 2: the row's centre as serial's within 1e-3", "%.3g" % dx)
    ck.close()


if __name__ == "__main__":
    main()
