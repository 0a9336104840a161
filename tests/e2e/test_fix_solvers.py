"""Every step solver gives the same physics on one and on two processes, to its tolerance.

A 4 x 4 x 3 lattice of spheres (radius 0.5, spacing 1.1) with random velocities (the same on
any process count: `velocity ... loop geom`) falls, collides and settles on a floor under gravity with
mu 0.5 and mu_roll 0.05, in a box split across x between the processes (`processors * 1 1`),
for 60 steps, with `solver cg` (the linear pass, then sweeps), `solver pgs`, `solver nncg`,
`solver fbgs` and `sweep_cg yes` (`solver pgs` as plain sweeps, `anderson 0`), each solved tightly (tol none: linear pass to 1e-10, sweeps to
1e-10), with the default solver at the step accuracy `tol 1e-6` (also with focused sweeps,
`focus_sweeps 3`; slow solves start again, `restart_sweeps`, on the same steps at np 2 as
serially), and with the defaults
(projected Gauss-Seidel to tol 1e-4: np 2 and np 4 within 1e-4 m and 2e-3 m/s of serial): the
collisions amplify any difference,
so the runs are compared after 10 steps (the first collisions), where a difference is still the
solver's own. On two processes each process sweeps its own contacts, the contacts on shared
bodies in its colour's phase of the sweep (pgs.hpp; block Jacobi across processes with
nonlinear CG and fibre blocks), so the runs agree to the sweeps' tolerance, not to round-off:
positions within 1e-9 m and velocities within 1e-6 m/s of the serial run (the largest velocity
is about 1 m/s). The difference after all 60 steps, grown by the collisions, is reported. The
default and plain sweeps take at most 15% more sweeps a step than serial at np 2 and 4, and
the defaults on a 2 x 2 x 1 grid of 4 processes at most 25% more (its corner's bodies are
split), within 1e-4 m and 2e-3 m/s of serial. Plain sweeps (solver
cg's finish and solver pgs) do not converge on some collision steps of this scene
(they stop at their cap): there the runs must say so (f_fc[12] > 0), and nonlinear CG, which
converges on every step, must agree. Fibre-block sweeps (fbgs) converge on every serial step;
at np 2 they agree to 1e-7 m and 1e-6 m/s after 10 steps. APGD (to 1e-8, capped at 1000
iterations) agrees to 1e-7 m and 1e-5 m/s and reports its unfinished steps alike in both runs.
"""

import fibre_e2e as e2e

DECK = """atom_style sphere
boundary p p f
newton off
processors {grid}
comm_modify vel yes
region box block -0.55 3.85 -0.55 3.85 0 8 units box
create_box 1 box
lattice sc 1.1
region pile block 0 4.3 0 4.3 0 3.2 units box
create_atoms 1 region pile units box
displace_atoms all move 0.0 0.0 0.5 units box
reset_atom_ids sort yes
set type 1 diameter 1.0 density 1.0
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
velocity all create 0.3 4928 loop geom
neighbor 0.2 bin
timestep 0.005
fix g all gravity 9.81 vector 0 0 -1
fix fc all fibre_contact mu 0.5 mu_roll 0.05 wall zplane 0.0 NULL {opts}
thermo_style custom step ke f_fc[3] f_fc[10] f_fc[12] f_fc[13] f_fc[14] f_fc[16] f_fc[23]
thermo 1
dump d all custom 10 {name}.dump id x y z vx vy vz
dump_modify d sort id format float %.17g
run 60
"""

SOLVERS = {
    "cg": "solver cg tol none linear_tol 1e-10 sweeps 5000 sweep_tol 1e-10",
    "pgs": "solver pgs anderson 0 tol none sweeps 5000 sweep_tol 1e-10",
    "nncg": "solver nncg tol none sweeps 5000 sweep_tol 1e-10",
    "fbgs": "solver fbgs tol none sweeps 5000 sweep_tol 1e-10",
    "apgd": "solver apgd tol none sweeps 1000 sweep_tol 1e-8",
    "sweep_cg": "solver cg tol none sweep_cg yes sweeps 5000 sweep_tol 1e-10",
    "tol": "tol 1e-6 sweeps 20000",
    "focus": "tol 1e-6 sweeps 20000 focus_sweeps 3",
    "anderson": "tol 1e-6 sweeps 20000 anderson 3",
    "default": "",
    "grid": "",  # the defaults at np 4 on a 2 x 2 x 1 grid
}


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("solvers: serial and two processes agree to the solver tolerance")
    for label, opts in SOLVERS.items():
        dumps, failed, worst_estimate, sweeps, restarts = {}, {}, {}, {}, {}
        for np in {"default": (1, 2, 4), "grid": (1, 4)}.get(label, (1, 2)):
            name = "solvers_%s_np%d" % (label, np)
            grid = "2 2 1" if label == "grid" and np == 4 else "* 1 1"
            run = e2e.run_lmp(args, DECK.format(opts=opts, name=name, grid=grid), name, np=np)
            if not ck.ran(run):
                continue
            failed[np] = run.last("f_fc[12]")
            restarts[np] = run.last("f_fc[23]")
            # the estimate of the steps that converged (f_fc[10] is 1 on those)
            worst_estimate[np] = max([row["f_fc[16]"] for block in run.thermo for row in block
                                      if row["f_fc[10]"] == 1] or [0.0])
            rows = [row["f_fc[14]"] for block in run.thermo for row in block]
            sweeps[np] = sum(rows) / max(len(rows), 1)  # the sweeps per step
            dumps[np] = [e2e.dump_by_id(f) for f in e2e.parse_dump(args.workdir + "/" + name + ".dump")]
        if 1 not in dumps or len(dumps) < 2:
            continue

        def difference(frame, np=2):
            a, b = dumps[1][frame], dumps[np][frame]
            dx = max(abs(a[i][k] - b[i][k]) for i in a for k in ("x", "y", "z"))
            dv = max(abs(a[i][k] - b[i][k]) for i in a for k in ("vx", "vy", "vz"))
            return dx, dv

        dx, dv = difference(1, min(n for n in dumps if n > 1))  # step 10
        agree = dx < 1e-9 and dv < 1e-6
        # checked below, with their own tolerances
        if label not in ("fbgs", "apgd", "tol", "focus", "anderson", "default", "grid"):
            ck.check(agree or (failed[1] > 0 and failed[2] > 0),
                     "%s: np 2 agrees with serial after 10 steps, or both runs report the steps "
                     "whose solve did not converge" % label,
                     "largest position difference %.2g m, velocity %.2g m/s; after 60 steps %.2g m, "
                     "%.2g m/s; non-converged steps %g and %g" % ((dx, dv) + difference(-1) +
                                                                   (failed[1], failed[2])))
        if label == "fbgs":
            # Serial fbgs converges on every step; at np 2 the blocks stop at the process
            # boundary and a few steps end above 1e-10 (as plain sweeps do), and say so.
            ck.check(failed[1] == 0 and dx < 1e-7 and dv < 1e-6,
                     "fbgs: serial converged on every step; np 2 within 1e-7 m and 1e-6 m/s",
                     "%.2g m, %.2g m/s" % (dx, dv))
        if label == "apgd":
            # APGD stalls near 1e-9 (tests/unit/test_pgs.cpp): capped at 1000 iterations and
            # 1e-8 it reports the collision steps it does not finish, in both runs alike.
            ck.check(dx < 1e-7 and dv < 1e-5 and abs(failed[1] - failed[2]) <= 5,
                     "apgd: np 2 within 1e-7 m and 1e-5 m/s; non-converged steps reported alike",
                     "%.2g m, %.2g m/s; non-converged steps %g and %g" % (dx, dv, failed[1],
                                                                         failed[2]))
        if label in ("tol", "focus", "anderson"):
            # tol is the step's accuracy: serial converges on every step, every converged
            # step's error estimate is within tol, and np 2 agrees to it (velocities of about
            # 1 m/s; a few np 2 steps stop at the cap, block Jacobi across the processes)
            ck.check(failed[1] == 0 and worst_estimate[1] <= 1e-6 and worst_estimate[2] <= 1e-6
                     and dx < 1e-7 and dv < 1e-5,
                     "%s (tol 1e-6): serial converged on every step, every converged step "
                     "estimates its error within tol; np 2 within 1e-7 m and 1e-5 m/s" % label,
                     "largest estimates %.2g and %.2g; %.2g m, %.2g m/s; non-converged steps "
                     "%g and %g" % (worst_estimate[1], worst_estimate[2], dx, dv, failed[1],
                                    failed[2]))
            # at tol 1e-6 some collision steps predict slow sweeps and start them again
            # (restart_sweeps 200; Anderson's sweeps only, not focused ones): the same solves on
            # both process counts
            if label != "focus":
                ck.check(restarts[1] > 0 and restarts[2] == restarts[1],
                         "%s (tol 1e-6): slow solves start again, as many at np 2 as serially"
                         % label, "%g and %g" % (restarts[1], restarts[2]))
        if label == "default":
            # the default step (projected Gauss-Seidel to tol 1e-4): every converged step within
            # its tol, and np 2 and 4 agree to it: each step's impulses differ by up to tol, and
            # 10 steps of collisions amplify that (velocities of about 1 m/s; tol 1e-6 above
            # agrees within 10 tol; measured here 3.8e-6 m, 2.1e-4 m/s at np 2 and 4 with
            # Anderson acceleration, 2.6e-5 m, 7.1e-4 m/s at np 2 with plain sweeps, whose runs
            # reported 1 and 4 of 60 steps at the sweeps' cap at np 1 and 2).
            ck.check(worst_estimate[1] <= 1e-4 and dx < 1e-4 and dv < 2e-3,
                     "default: every converged serial step within tol 1e-4; np 2 within "
                     "1e-4 m and 2e-3 m/s",
                     "largest estimates %.2g and %.2g; %.2g m, %.2g m/s; non-converged steps "
                     "%g and %g" % (worst_estimate[1], worst_estimate[2], dx, dv, failed[1],
                                    failed[2]))
            if 4 in dumps:
                dx4, dv4 = difference(1, 4)
                ck.check(dx4 < 1e-4 and dv4 < 2e-3, "default: np 4 within 1e-4 m and 2e-3 m/s "
                         "of serial", "%.2g m, %.2g m/s" % (dx4, dv4))
        if label == "grid":
            # 2 x 2 processes share bodies with all three others: the two colours separate the
            # neighbours across each face, and the diagonal pairs split the corner's bodies
            ck.check(dx < 1e-4 and dv < 2e-3, "grid: the defaults at np 4 on a 2 x 2 x 1 grid "
                     "within 1e-4 m and 2e-3 m/s of serial", "%.2g m, %.2g m/s" % (dx, dv))
        if label in ("pgs", "default", "grid"):
            # Two colours: each process sweeps the contacts on bodies it shares in its own
            # colour's phase, so a sweep on slabs (`processors * 1 1`) is one process's
            # Gauss-Seidel sweep, and on the grid nearly so (its corner's bodies are split).
            # Mass splitting alone, which shares out those bodies' masses, took 47% and 44%
            # more sweeps on slabs (355 and 30.3 a step against 241 and 21.1) and 66% more on
            # the grid (34.9); measured now: 0.4% and 8%, and 12% on the grid.
            limit = 1.25 if label == "grid" else 1.15
            for np in sorted(n for n in sweeps if n > 1):
                ck.check(sweeps[np] <= limit * sweeps[1],
                         "%s: np %d takes at most %d%% more sweeps a step than serial"
                         % (label, np, round(100 * (limit - 1))),
                         "%.1f against %.1f" % (sweeps[np], sweeps[1]))
        if label in ("nncg", "sweep_cg"):  # these converge on every step of this scene
            ck.check(agree and failed[1] == 0 and failed[2] == 0,
                     "%s: every step converged and np 2 agrees" % label)
    ck.close()


if __name__ == "__main__":
    main()
