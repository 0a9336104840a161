"""Acceptance 1: a resting column of spheres on a floor.

Six spheres of different sizes, stacked exactly touching on a zplane wall under gravity,
for 1000 steps with every solver and both forms. Checks:
- the column settles to the compliant static solution: every sphere sits lower by the sum
  of eps_n * (weight carried) of the contacts below it (eps_n = 1e-2 dt^2 / m_min, the
  default), to 1%;
- then it stays at rest: drift between step 500 and step 1000 below 1e-9 diameters in
  contact form (body form: 5e-7, MUMPS: 1e-12), final kinetic energy below 1e-10 (MUMPS:
  1e-20);
- the normal impulse of every contact equals dt * g * (mass above it): relative error below
  1e-9 with MUMPS, 1e-5 in contact form and 1e-3 in body form at linear_tol 1e-6, 2e-3 with
  the default (projected Gauss-Seidel to tol 1e-4) (read
  from the fix's per-contact local output through dump local);
- the fix's global vector: 6 contacts, 1 wall contact, converged, and the deepest overlap
  (f_fc[7]) equals eps_n times the column's weight;
- 'export' writes the contact system (system_io format) and the same impulses.
"""

import math
import os

import fibre_e2e as e2e

DIAMETERS = [1.0, 0.8, 1.2, 0.9, 1.1, 1.0]
DT = 0.01
GRAVITY = 1.0
STEPS = 1000


def deck(opts):
    lines = e2e.sphere_box("-3 3 -3 3 0 10") + e2e.stacked_column(DIAMETERS)[1]
    lines += [
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity %g vector 0 0 -1" % GRAVITY,
        "fix fc all fibre_contact wall zplane 0.0 NULL " + opts,
        "compute rot all erotate/sphere",
        "compute ke all ke",
        "thermo_style custom step c_ke c_rot f_fc[1] f_fc[2] f_fc[3] f_fc[6] f_fc[7] f_fc[10] "
        "f_fc[11]",
        "thermo_modify format float %.10g",
        "thermo 100",
        "dump a all custom %d col.${tag}.atoms id x y z vx vy vz" % (STEPS // 2),
        "dump_modify a sort id format float %.17g",
        "dump c all local %d col.${tag}.contacts f_fc[1] f_fc[2] f_fc[3] f_fc[4] f_fc[5]"
        % STEPS,
        "dump_modify c format float %.17g",
        "run %d" % STEPS,
    ]
    return "\n".join(lines) + "\n"


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("resting column: %d spheres on a floor, %d steps" % (len(DIAMETERS), STEPS))
    masses = [math.pi / 6 * d ** 3 for d in DIAMETERS]
    z0 = e2e.stacked_column(DIAMETERS)[0]
    # (tag, options, impulse tolerance, kinetic energy bound, drift bound)
    cases = [
        ("cr_body", "form body solver cr linear_tol 1e-6", 1e-3, 1e-10, 5e-7),
        ("cr_contact", "form contact solver cr linear_tol 1e-6", 1e-5, 1e-10, 1e-9),
        ("minres_body", "form body solver minres linear_tol 1e-6", 1e-3, 1e-10, 5e-7),
        ("uzawa_contact", "form contact solver uzawa linear_tol 1e-6", 1e-5, 1e-10, 1e-9),
        ("direct", "solver direct export 500 col_export", 1e-9, 1e-20, 1e-12),
        ("fibre_rows3", "solver cg tol none form body precond fibre rows 3 linear_tol 1e-6", 1e-3,
         1e-10, 5e-7),
        ("tree_contact", "solver cg tol none form contact precond tree linear_tol 1e-6", 1e-5,
         1e-10, 1e-9),
        # the default step: projected Gauss-Seidel to tol 1e-4
        ("default", "", 2e-3, 1e-10, 5e-7),
    ]
    eps = 1e-2 * DT ** 2 / min(masses)
    carried = [GRAVITY * sum(masses[i:]) for i in range(len(masses))]  # by the contact below i
    sink = [eps * sum(carried[: i + 1]) for i in range(len(masses))]
    for tag, opts, impulse_tol, ke_bound, drift_bound in cases:
        run = e2e.run_lmp(args, deck(opts), "column_" + tag, variables={"tag": tag})
        if not ck.ran(run, "%s: run completes" % tag):
            continue
        frames = e2e.parse_dump(os.path.join(args.workdir, "col.%s.atoms" % tag))
        mid, end = e2e.dump_by_id(frames[-2]), e2e.dump_by_id(frames[-1])
        settle = max(e2e.rel_err(z0[i] - end[i + 1]["z"], sink[i]) for i in range(len(z0)))
        ck.check(settle < 1e-2, "%s: static compression eps_n * load" % tag,
                 "top sphere %.4g lower (predicted %.4g), max rel err %.2g"
                 % (z0[-1] - end[len(z0)]["z"], sink[-1], settle))
        drift = max(abs(end[i]["z"] - mid[i]["z"]) / DIAMETERS[i - 1] for i in end)
        lateral = max(max(abs(a["x"]), abs(a["y"])) for a in end.values())
        ck.check(drift < drift_bound, "%s: column at rest" % tag,
                 "drift from step %d to %d: %.3g diameters, bound %.0e"
                 % (frames[-2][0], frames[-1][0], drift, drift_bound))
        ck.check(lateral < 1e-9, "%s: no lateral drift" % tag, "max |x|,|y| = %.3g" % lateral)
        ke = run.last("c_ke") + run.last("c_rot")
        ck.check(ke < ke_bound, "%s: kinetic energy vanishes" % tag,
                 "KE = %.3g, bound %.0e" % (ke, ke_bound))

        contacts = e2e.parse_dump(os.path.join(args.workdir, "col.%s.contacts" % tag))[-1][2]
        worst, detail = 0.0, []
        for row in contacts:
            tag_a, tag_b, wall, gap, impulse = row[:5]
            # a pair contact carries the spheres above its lower sphere tag_a, the floor all
            above = sum(masses[int(tag_a):]) if tag_b > 0 else sum(masses)
            expected = DT * GRAVITY * above
            err = e2e.rel_err(impulse, expected)
            worst = max(worst, err)
            detail.append("%d-%d: %.8g vs %.8g" % (tag_a, tag_b, impulse, expected))
        ck.check(len(contacts) == len(DIAMETERS), "%s: %d contacts" % (tag, len(DIAMETERS)),
                 "%d found" % len(contacts))
        ck.check(worst < impulse_tol, "%s: impulses = dt g (mass above)" % tag,
                 "max rel err %.2g, bound %.0e; %s"
                 % (worst, impulse_tol, ", ".join(detail[:3])))
        ck.check(run.last("f_fc[3]") == len(DIAMETERS) and run.last("f_fc[11]") == 1
                 and run.last("f_fc[10]") == 1, "%s: f_fc[3] contacts, f_fc[11] wall "
                 "contacts, f_fc[10] converged" % tag,
                 "%g %g %g" % (run.last("f_fc[3]"), run.last("f_fc[11]"), run.last("f_fc[10]")))
        if "export" in opts:
            # the exported system and solution of the last step (one process: rank 0)
            base = os.path.join(args.workdir, "col_export.%d.0" % STEPS)
            with open(base + ".sys") as f:
                sys_lines = f.read().split("\n")
            with open(base + ".lambda") as f:
                lam = [line.split() for line in f if not line.startswith("#")]
            ncont = [int(line.split()[1]) for line in sys_lines if line.startswith("contacts")]
            exported = {(int(w[1]), int(w[2])): float(w[4]) for w in lam}
            err = max(e2e.rel_err(exported[(int(r[0]), int(r[1]))], r[4]) for r in contacts)
            # format version 4; each line: index, tags, wall, the
            # impulses and the warm start of every row
            rows = [int(line.split()[1]) for line in sys_lines if line.startswith("rows")]
            ck.check(sys_lines[0] == "fibre_contact_system 11" and ncont == [len(contacts)]
                     and len(lam) == len(contacts) and err < 1e-12
                     and all(len(w) == 4 + 2 * rows[0] for w in lam),
                     "%s: export writes the system and the same impulses" % tag,
                     "header '%s', %s contacts, %d impulse lines, max rel diff %.2g"
                     % (sys_lines[0], ncont, len(lam), err))
        overlap = run.last("f_fc[7]")
        floor = eps * GRAVITY * sum(masses)  # the floor contact carries everything
        ck.check(e2e.rel_err(overlap, floor) < 1e-2, "%s: f_fc[7] = deepest overlap = eps_n "
                 "* weight" % tag, "%.4g, predicted %.4g" % (overlap, floor))
    ck.close()


if __name__ == "__main__":
    main()
