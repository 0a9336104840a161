"""Restitution (keywords restitution and bounce_speed).

- A sphere dropped from a height h (of its lowest point) onto a plane wall rebounds to e^2 h
  within 2% for e = 0.3, 0.5 and 0.9, on one process and (e = 0.5) on two, where the sphere
  crosses the boundary between the processes' domains.
- The bounces then die out: once the approach speed is at or below bounce_speed the contact
  is plastic and the sphere comes to rest on the plane.
- Without the keyword (e = 0) the drop is plastic: no rebound higher than a few overlaps.
- A head-on pair of unequal spheres without gravity separates at e times the approach
  speed, with its momentum kept.
- A struck sphere does not pass through the floor: a heavy sphere (e 0.9, 8 m/s, step 0.01 s)
  hits one at rest 2 cm above the plane, which the impact throws down at about 11 m/s within
  the step. Its own velocity does not reach the plane, so the contact search covers the
  impact's speed (before: 9 cm into the plane in one step); deepest overlap below 0.5% of the
  diameter, on one process and on two.
"""

import fibre_e2e as e2e

DT = 5e-4
G = 9.81
H = 5.0  # drop height of the sphere's lowest point


def header(box):
    return e2e.sphere_box(box)


def drop(args, ck, e, np, steps):
    opts = "mu 0" + (" restitution %g" % e if e is not None else "")
    lines = header("-2 2 -2 2 0 8") + [
        "create_atoms 1 single 0 0 %g units box" % (H + 0.5),
        "set atom 1 diameter 1.0 density 1.0",
        "fix g all gravity %g vector 0 0 -1" % G,
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.3 bin",
        "timestep %g" % DT,
        "fix fc all fibre_contact wall zplane 0.0 NULL %s" % opts,
        "variable z equal z[1]",
        "variable vz equal vz[1]",
        "thermo_style custom step v_z v_vz",
        "thermo_modify format float %.17g",
        "thermo 1",
        "run %d" % steps,
    ]
    tag = "drop_e%s_np%d" % ("none" if e is None else "%g" % e, np)
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return None
    rows = run.thermo[-1]
    first = next((k for k in range(1, len(rows)) if rows[k]["v_vz"] > 0), None)
    if first is None:
        ck.check(False, "%s: the sphere reaches the plane" % tag)
        return None
    # the top of the first rebound: up to the next time the sphere falls back to the plane
    top = first
    while top + 1 < len(rows) and rows[top + 1]["v_vz"] > 0:
        top += 1
    return tag, rows, rows[top]["v_z"] - 0.5


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("restitution")
    for e, np in [(0.3, 1), (0.5, 1), (0.9, 1), (0.5, 2)]:
        res = drop(args, ck, e, np, 4000)
        if res is None:
            continue
        tag, rows, rebound = res
        ck.agree(rebound, e * e * H, 0.02, "%s: rebounds to e^2 h within 2%%" % tag)
    res = drop(args, ck, 0.5, 1, 9000)
    if res is not None:
        tag, rows, _ = res
        last = rows[-1]
        ck.check(abs(last["v_vz"]) < 1e-3 * G * DT and abs(last["v_z"] - 0.5) < 1e-3,
                 "%s: the bounces die out and the sphere rests on the plane" % tag,
                 "z = %.6g, vz = %.3g after %g s" % (last["v_z"], last["v_vz"], 9000 * DT))
    res = drop(args, ck, None, 1, 2500)
    if res is not None:
        tag, rows, rebound = res
        ck.check(rebound < 1e-3, "%s: no restitution keyword, no rebound" % tag,
                 "rebound %.3g m" % rebound)
    head_on(args, ck)
    for np in (1, 2):
        struck(args, ck, np)
    ck.close()


def head_on(args, ck):
    for e in (0.3, 0.9):
        lines = header("-10 10 -10 10 -10 10") + [
            "create_atoms 1 single -1.5 0 0 units box",
            "create_atoms 1 single 1.5 0 0 units box",
            "set atom 1 diameter 1.0 density 1.0",
            "set atom 2 diameter 1.0 density 3.0",
            "velocity all set 0 0 0",
            "set atom 1 vx 2.0",
            "set atom 2 vx -1.0",
            "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
            "pair_coeff * *",
            "neighbor 0.3 bin",
            "timestep 0.01",
            "fix fc all fibre_contact mu 0 restitution %g" % e,
            "variable va equal vx[1]",
            "variable vb equal vx[2]",
            "variable p equal mass[1]*vx[1]+mass[2]*vx[2]",
            "thermo_style custom step v_va v_vb v_p",
            "thermo_modify format float %.17g",
            "thermo 1",
            "run 200",
        ]
        tag = "head_on_e%g" % e
        run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag)
        if not ck.ran(run, "%s: run completes" % tag):
            continue
        rows = run.thermo[-1]
        last = rows[-1]
        ck.agree(last["v_vb"] - last["v_va"], e * 3.0, 1e-6,
                 "%s: separates at e times the approach speed" % tag)
        ck.check(abs(last["v_p"] - rows[0]["v_p"]) <= 1e-12 * abs(rows[0]["v_p"]),
                 "%s: momentum kept" % tag, "p %.17g -> %.17g" % (rows[0]["v_p"], last["v_p"]))


def struck(args, ck, np):
    processors = "2 1 1" if np == 2 else None  # the spheres sit on the boundary
    lines = e2e.sphere_box("-5 5 -5 5 0 10", processors=processors) + [
        "create_atoms 1 single 0 0 2.6 units box",
        "create_atoms 1 single 0 0 0.52 units box",
        "set atom 1 diameter 1.0 density 3.0",
        "set atom 2 diameter 1.0 density 1.0",
        "velocity all set 0 0 0",
        "set atom 1 vz -8.0",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.3 bin",
        "timestep 0.01",
        "fix fc all fibre_contact mu 0 restitution 0.9 wall zplane 0.0 NULL",
        "variable z2 equal z[2]",
        "thermo_style custom step v_z2 f_fc[7]",
        "thermo_modify format float %.17g",
        "thermo 1",
        "run 40",
    ]
    tag = "struck_sphere_np%d" % np
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    deepest = max(run.column("f_fc[7]"))
    lowest = min(run.column("v_z2"))
    ck.check(deepest < 0.005 and lowest > 0.495,
             "%s: the struck sphere does not pass through the plane" % tag,
             "deepest overlap %.3g, lowest centre %.4g" % (deepest, lowest))


if __name__ == "__main__":
    main()
