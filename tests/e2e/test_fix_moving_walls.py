"""Moving walls and kinematic obstacles (issue #15).

- Conveyor: a sphere dropped onto a block region that moves at U = 1 m/s (`region ... move`).
  Friction drags it until it rolls without slipping on the belt: its centre then moves at
  2 U / 7 (angular momentum about the contact point is conserved from rest). With a rolling
  resistance that forbids rolling it moves with the belt, at U. The energy balance: the belt
  does the work F U t = m U v (f_fc[17]); Coulomb sliding dissipates mu m g times the mean
  slip speed U / 2 over the slip time (f_fc[18]): 2/7 and 1/7 m U^2 rolling, m U^2 and
  1/2 m U^2 without rolling; the kinetic energy gained is their difference.
- Drum: a sphere inside a cylinder that rotates about its axis at omega = 10 rad/s
  (`region ... rotate`, omega^2 (R - r) = 25 g: a centrifuge). Friction and rolling resistance
  carry it with the wall: its speed becomes omega (R - r), and over 10 revolutions it stays on
  the wall (distance from the axis R - r within 1% of r: the step's straight drift overlaps
  the curved wall by (h v)^2 / 2 (R - r)) without crossing it.
- Unions (side in): the drum made of two rotating cylinders, the sphere in the second,
  carries it as the single cylinder does; the spaces above two belts moving in opposite
  directions (a union of two moving blocks) carry a sphere each at 2 U / 7 in its belt's
  direction: each contact takes the velocity of the sub-region it touches.
- Obstacle: an atom outside the group moved by `fix move linear` pushes a free sphere
  (frictionless, no gravity): the sphere moves at the obstacle's speed and the overlap stays
  below that speed times dt.
- Moving planes (fix wall/gran's keywords): a sphere on a zplane that shears along x at U
  ends at 2 U / 7, rolling without slipping; on a plane wiggling along z with A omega^2 below
  g it follows the plane (z = r + A sin(omega t)); above g it leaves the plane.
The conveyor without rolling resistance and the drum again with contact_every 4 (a solve every
four steps, over them): the same speeds.
All serial and on two processes.
"""

import math

import fibre_e2e as e2e

DT = 1e-3


def header(np, box):
    return e2e.sphere_box(box, types=2, processors="2 1 1" if np == 2 else None)


def thermo(extra=""):
    return [
        "variable x1 equal x[1]",
        "variable z1 equal z[1]",
        "variable vx1 equal vx[1]",
        "variable vy1 equal vy[1]",
        "variable vz1 equal vz[1]",
        "thermo_style custom step v_x1 v_z1 v_vx1 v_vy1 v_vz1 f_fc[7] " + extra,
        "thermo_modify format float %.12g",
    ]


def conveyor(args, ck, np, mu_roll, every=1):
    U = 1.0
    lines = header(np, "-20 20 -3 3 -2 5") + [
        "create_atoms 1 single -10 0 0.5 units box",
        "set atom 1 diameter 1.0 density 1.0",
        "variable shift equal %g*time" % U,
        "region belt block -100 100 -2 2 -1 0 side out move v_shift NULL NULL units box",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.5 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall region belt mu 0.5 mu_roll %g contact_every %d"
        % (mu_roll, every),
        "compute rot all erotate/sphere",
        "compute ke all ke",  # thermo ke leaves out the centre of mass: 0 for one sphere
    ] + thermo("f_fc[17] f_fc[18] c_ke c_rot") + ["thermo 100", "run 3000"]
    tag = "conveyor_roll%g_np%d" % (mu_roll, np) + ("_every%d" % every if every > 1 else "")
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    last = run.thermo[-1][-1]
    expected = U * (2.0 / 7.0 if mu_roll == 0 else 1.0)
    ck.agree(last["v_vx1"], expected, 1e-3, "%s: the belt carries the sphere at %s" %
             (tag, "2 U / 7 (rolling)" if mu_roll == 0 else "U (no rolling)"))
    zs = run.column("v_z1")
    ck.check(min(zs[1:]) > 0.5 - 0.01 and abs(last["v_vz1"]) < 1e-6,
             "%s: the sphere stays on the belt's surface" % tag,
             "lowest z %.6g, final vz %.3g" % (min(zs[1:]), last["v_vz1"]))
    m = math.pi / 6.0  # diameter 1, density 1
    work, dissipated = (1.0, 0.5) if mu_roll > 0 else (2.0 / 7.0, 1.0 / 7.0)
    ck.agree(last["f_fc[17]"], work * m * U * U, 2e-2, "%s: the belt's work is m U v" % tag)
    ck.agree(last["f_fc[18]"], dissipated * m * U * U, 2e-2,
             "%s: sliding dissipates mu m g U t / 2" % tag)
    first = run.thermo[-1][0]
    gained = last["c_ke"] + last["c_rot"] - (first["c_ke"] + first["c_rot"])
    # exact but for gravity's work on the sphere's micro-motion in the compliant normal row
    # (and with contact_every, the velocity between solves: gravity's since the last one)
    ck.agree(last["f_fc[17]"] - last["f_fc[18]"], gained, 1e-4 if every == 1 else 1e-3,
             "%s: the work less the dissipation is the kinetic energy gained" % tag)


def drum(args, ck, np, union=False, every=1):
    R, r, omega = 3.0, 0.5, 10.0
    revolutions = 10
    steps = int(revolutions * 2 * math.pi / omega / DT)
    lines = header(np, "-4 4 -2 2 -4 4") + [
        "create_atoms 1 single 0 0 %g units box" % (-(R - r)),
        "set atom 1 diameter 1.0 density 1.0",
        "variable theta equal %g*time" % omega,
    ] + ([
        "region left cylinder y 0 0 %g -1.5 -0.3 rotate v_theta 0 0 0 0 1 0 units box" % R,
        "region right cylinder y 0 0 %g -0.3 1.5 rotate v_theta 0 0 0 0 1 0 units box" % R,
        "region drum union 2 left right side in units box",
    ] if union else [
        "region drum cylinder y 0 0 %g -1.5 1.5 side in rotate v_theta 0 0 0 0 1 0 units box" % R,
    ]) + [
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 1.0 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall region drum mu 1.0 mu_roll 1.0 contact_every %d" % every,
        "variable rho equal sqrt(x[1]^2+z[1]^2)",
        "variable speed equal sqrt(vx[1]^2+vy[1]^2+vz[1]^2)",
    ] + thermo("v_rho v_speed") + ["thermo 50", "run %d" % steps]
    tag = "drum%s_np%d" % ("_union" if union else "", np) + ("_every%d" % every if every > 1
                                                             else "")
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    rows = run.thermo[-1]
    late = [row for row in rows if row["Step"] > steps // 2]
    speed = [row["v_speed"] for row in late]
    ck.check(all(abs(s - omega * (R - r)) < 1e-2 * omega * (R - r) for s in speed),
             "%s: the sphere moves with the wall, at omega (R - r)" % tag,
             "speeds %.5g .. %.5g against %.5g" % (min(speed), max(speed), omega * (R - r)))
    rho = [row["v_rho"] for row in rows[1:]]
    # the straight drift of a step leaves the circle by (h v)^2 / (2 (R - r)) = 1.25e-4 before
    # the contact pulls the sphere back: overlaps of that order, far from crossing
    ck.check(max(rho) < R - r + 0.01 * r and min(rho) > R - r - 0.01 * r,
             "%s: %d revolutions on the wall, never through it" % (tag, revolutions),
             "distance from the axis %.6g .. %.6g (R - r = %g)" % (min(rho), max(rho), R - r))
    ck.check(rows[-1]["v_vy1"] == 0.0 or abs(rows[-1]["v_vy1"]) < 1e-9,
             "%s: no motion along the axis" % tag, "vy %.3g" % rows[-1]["v_vy1"])


def belts(args, ck, np):
    """Two belts, one union: each sphere rides its own belt's velocity."""
    U1, U2 = 1.0, -0.5
    lines = header(np, "-20 20 -3 3 -2 5") + [
        "create_atoms 1 single -10 0 0.5 units box",
        "create_atoms 1 single 10 0 0.5 units box",
        "set atom * diameter 1.0 density 1.0",
        "variable s1 equal %g*time" % U1,
        "variable s2 equal %g*time" % U2,
        "region b1 block -100 0 -2.5 2.5 0 4 move v_s1 NULL NULL units box",
        "region b2 block 0 100 -2.5 2.5 0 4 move v_s2 NULL NULL units box",
        "region belts union 2 b1 b2 side in units box",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.5 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall region belts mu 0.5",
        "variable vx2 equal vx[2]",
    ] + thermo("v_vx2") + ["thermo 100", "run 3000"]
    tag = "belts_union_np%d" % np
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    ck.agree(run.last("v_vx1"), 2.0 * U1 / 7.0, 1e-3, "%s: the first belt's sphere at 2 U1 / 7" % tag)
    ck.agree(run.last("v_vx2"), 2.0 * U2 / 7.0, 1e-3, "%s: the second's at 2 U2 / 7" % tag)


def obstacle(args, ck, np):
    u = 0.5
    lines = header(np, "-5 10 -3 3 -3 3") + [
        "create_atoms 1 single 0 0 0 units box",
        "create_atoms 2 single -1.2 0 0 units box",
        "set atom * diameter 1.0 density 1.0",
        "group free type 1",
        "group pusher type 2",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.3 bin",
        "timestep %g" % DT,
        "fix push pusher move linear %g 0 0" % u,
        "fix fc free fibre_contact mu 0",
    ] + thermo() + ["thermo 100", "run 2000"]
    tag = "obstacle_np%d" % np
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    last = run.thermo[-1][-1]
    ck.agree(last["v_vx1"], u, 1e-6, "%s: the pushed sphere moves at the obstacle's speed" % tag)
    overlap = max(run.column("f_fc[7]"))
    ck.check(overlap <= u * DT, "%s: the overlap stays below u dt" % tag,
             "deepest %.3g against %.3g" % (overlap, u * DT))


def plane(args, ck, np, motion, tag):
    lines = header(np, "-20 20 -3 3 -2 5") + [
        "create_atoms 1 single -10 0 0.5 units box",
        "set atom 1 diameter 1.0 density 1.0",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.5 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity 9.81 vector 0 0 -1",
        "fix fc all fibre_contact wall zplane 0.0 NULL %s" % motion,
        "variable t equal time",
    ] + thermo("v_t") + ["thermo 10", "run 3000"]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    ck.ran(run, "%s: run completes" % tag)
    return run


def planes(args, ck, np):
    U = 1.0
    run = plane(args, ck, np, "shear x %g" % U, "plane_shear_np%d" % np)
    if run.rc == 0:
        ck.agree(run.last("v_vx1"), 2.0 * U / 7.0, 1e-3,
                 "plane_shear_np%d: the shearing plane rolls the sphere at 2 U / 7" % np)
    A, T = 0.01, 0.5  # A omega^2 = 1.58 < g
    run = plane(args, ck, np, "wiggle z %g %g" % (A, T), "plane_wiggle_np%d" % np)
    if run.rc == 0:
        rows = run.thermo[-1][1:]
        dev = max(abs(r["v_z1"] - 0.5 - A * math.sin(2 * math.pi * r["v_t"] / T)) for r in rows)
        ck.check(dev < 0.02 * A, "plane_wiggle_np%d: the sphere rides the wiggling plane" % np,
                 "largest deviation %.3g against amplitude %g" % (dev, A))
    A, T = 0.1, 0.2  # A omega^2 = 98.7 > g
    run = plane(args, ck, np, "wiggle z %g %g" % (A, T), "plane_shaker_np%d" % np)
    if run.rc == 0:
        lift = max(r["v_z1"] - 0.5 - A * math.sin(2 * math.pi * r["v_t"] / T)
                   for r in run.thermo[-1][1:])
        ck.check(lift > A, "plane_shaker_np%d: a plane shaken harder than g throws it" % np,
                 "largest height above the plane %.3g" % lift)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("moving walls and obstacles")
    for np in (1, 2):
        conveyor(args, ck, np, 0.0)
        conveyor(args, ck, np, 1.0)
        drum(args, ck, np)
        drum(args, ck, np, union=True)
        # the contacts solved every 4 steps: the walls' speeds differenced every step
        conveyor(args, ck, np, 0.0, every=4)
        drum(args, ck, np, every=4)
        belts(args, ck, np)
        obstacle(args, ck, np)
        planes(args, ck, np)
    ck.close()


if __name__ == "__main__":
    main()
