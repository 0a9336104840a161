"""Acceptance 3: collisions.

- Head-on collision of two unequal spheres (no gravity): the contact impulses are equal and
  opposite, so linear momentum is conserved to round-off at every step; kinetic energy
  never grows; the overlap never exceeds the relative approach per step (v_rel dt) and
  never grows after its peak; SPOOK collisions are inelastic (no restitution): the spheres
  end up moving together at p / (m1 + m2).
- Oblique collision with friction: linear and angular momentum (orbital plus spin) conserved
  to round-off.
- A row of four touching spheres hit by a fifth (redundant contacts at once): momentum
  conserved, no energy gain.
- A cluster of 27 touching spheres with random velocities, without and with friction (also
  with MUMPS): momentum conserved, no energy gain.
- Two spheres that close by 0.2 diameters a step, with the neighbor list kept for 10 steps (neigh_modify
  delay 10, which a converted deck may carry): the fix checks the list every step instead and
  says so, so they collide and come to rest touching (SPOOK is inelastic) where the list's delay let
  them pass through each other (they swapped sides); one and two processes.
- A sphere dropped onto a floor: total energy (kinetic + rotational + potential, the
  potential taken at the midpoint z + dt vz / 2 of the next drift, which the scheme conserves
  exactly in free fall) never grows, the overlap stays below v_impact dt and decays, the
  sphere comes to rest on the floor.
"""

import math

import fibre_e2e as e2e

DT = 0.01


def header(box="-20 20 -20 20 -20 20", processors=None):
    return e2e.sphere_box(box, processors=processors)


def momentum_thermo(extra=""):
    return [
        "compute pa all property/atom radius omegaz",
        "variable mvx atom mass*vx",
        "variable mvy atom mass*vy",
        "variable mvz atom mass*vz",
        "variable lz atom mass*(x*vy-y*vx)+0.4*mass*c_pa[1]*c_pa[1]*c_pa[2]",
        "compute p all reduce sum v_mvx v_mvy v_mvz v_lz",
        "compute ke all ke",
        "compute rot all erotate/sphere",
        "thermo_style custom step c_p[1] c_p[2] c_p[3] c_p[4] c_ke c_rot f_fc[3] f_fc[7] "
        "f_fc[10] " + extra,
        "thermo_modify format float %.17g",
        "thermo 1",
    ]


def pair_and_fix(opts, walls=""):
    return [
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.3 bin",
        "timestep %g" % DT,
        "fix fc all fibre_contact %s %s" % (walls, opts),
    ]


def check_conservation(ck, tag, run, pscale, lscale=None):
    rows = run.thermo[-1]
    p0 = [rows[0]["c_p[%d]" % k] for k in (1, 2, 3)]
    dp = max(abs(r["c_p[%d]" % k] - p0[k - 1]) for r in rows for k in (1, 2, 3))
    ck.check(dp <= 1e-13 * pscale, "%s: linear momentum conserved to round-off" % tag,
             "max |p - p0| = %.3g (|p| scale %.3g)" % (dp, pscale))
    if lscale is not None:
        l0 = rows[0]["c_p[4]"]
        dl = max(abs(r["c_p[4]"] - l0) for r in rows)
        ck.check(dl <= 1e-12 * lscale, "%s: angular momentum L_z conserved to round-off" % tag,
                 "max |L - L0| = %.3g (scale %.3g)" % (dl, lscale))
    e0 = rows[0]["c_ke"] + rows[0]["c_rot"]
    gain = max(r["c_ke"] + r["c_rot"] - e0 for r in rows)
    ck.check(gain <= 1e-12 * e0, "%s: no energy gain" % tag,
             "max (E - E0) / E0 = %.3g, final E / E0 = %.4g"
             % (gain / e0, (rows[-1]["c_ke"] + rows[-1]["c_rot"]) / e0))
    return rows


def head_on(args, ck, opts, tag):
    d1, d2, v1, v2 = 1.0, 1.4, 1.0, -0.5
    lines = header() + [
        "create_atoms 1 single -2 0 0 units box",
        "create_atoms 1 single 2 0 0 units box",
        "set atom 1 diameter %g density 1.0" % d1,
        "set atom 2 diameter %g density 1.0" % d2,
        "velocity all set 0 0 0",
        "group a id 1",
        "group b id 2",
        "velocity a set %g 0 0" % v1,
        "velocity b set %g 0 0" % v2,
        "variable v1 equal vx[1]",
        "variable v2 equal vx[2]",
    ] + pair_and_fix(opts) + momentum_thermo("v_v1 v_v2") + ["run 600"]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_headon_" + tag)
    if not ck.ran(run, "head-on %s: run completes" % tag):
        return
    m1, m2 = math.pi / 6 * d1 ** 3, math.pi / 6 * d2 ** 3
    rows = check_conservation(ck, "head-on " + tag, run, abs(m1 * v1) + abs(m2 * v2))
    overlaps = [r["f_fc[7]"] for r in rows]
    bound = (v1 - v2) * DT
    ck.check(max(overlaps) <= bound, "head-on %s: overlap below v_rel dt" % tag,
             "max overlap %.4g, v_rel dt = %.4g" % (max(overlaps), bound))
    # SPOOK has no restitution: the spheres end up moving together at p / (m1 + m2)
    common = (m1 * v1 + m2 * v2) / (m1 + m2)
    dv = max(abs(rows[-1]["v_v1"] - common), abs(rows[-1]["v_v2"] - common))
    ck.check(dv < 1e-9 and overlaps[-1] < 1e-9,
             "head-on %s: inelastic, common velocity p/M, no overlap left" % tag,
             "v1 %.12g, v2 %.12g, p/M %.12g, overlap %.3g"
             % (rows[-1]["v_v1"], rows[-1]["v_v2"], common, overlaps[-1]))
    peak = overlaps.index(max(overlaps))
    grows_after = any(overlaps[k + 1] > overlaps[k] * (1 + 1e-12) for k in range(peak,
                                                                                 len(overlaps) - 1))
    ck.check(not grows_after, "head-on %s: overlap only shrinks after its peak" % tag,
             "peak %.4g at step %d" % (overlaps[peak], int(rows[peak]["Step"])))


def oblique(args, ck, opts, tag):
    lines = header() + [
        "create_atoms 1 single -2 0.35 0 units box",
        "create_atoms 1 single 2 -0.2 0 units box",
        "set atom 1 diameter 1.0 density 1.0",
        "set atom 2 diameter 1.2 density 2.0",
        "velocity all set 0 0 0",
        "group a id 1",
        "group b id 2",
        "velocity a set 1.0 0.1 0",
        "velocity b set -0.6 0 0",
    ] + pair_and_fix(opts) + momentum_thermo() + ["run 500"]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_oblique_" + tag)
    if not ck.ran(run, "oblique %s: run completes" % tag):
        return
    rows = check_conservation(ck, "oblique " + tag, run, 2.0, lscale=2.0)
    ck.check(max(r["c_rot"] for r in rows) > 0, "oblique %s: friction spins the spheres" % tag,
             "max rotational energy %.3g" % max(r["c_rot"] for r in rows))


def row_hit(args, ck, opts, tag):
    lines = header() + ["create_atoms 1 single -5 0 0 units box"]
    for k in range(4):
        lines.append("create_atoms 1 single %.17g 0 0 units box" % (1.0 * k))
    lines += [
        "set group all diameter 1.0 density 1.0",
        "velocity all set 0 0 0",
        "group a id 1",
        "velocity a set 2.0 0 0",
    ] + pair_and_fix(opts) + momentum_thermo() + ["run 600"]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_row_" + tag)
    if not ck.ran(run, "row hit %s: run completes" % tag):
        return
    rows = check_conservation(ck, "row hit " + tag, run, 2.0 * math.pi / 6)
    ck.check(max(r["f_fc[7]"] for r in rows) <= 2.0 * DT, "row hit %s: overlap below v dt" % tag,
             "max overlap %.4g" % max(r["f_fc[7]"] for r in rows))


def cluster(args, ck, opts, tag):
    """27 touching spheres (3 x 3 x 3), random velocities, no gravity: many redundant contacts
    at once, with friction."""
    lines = header() + [
        "lattice sc 1.0",
        "region fill block 0 2 0 2 0 2",
        "create_atoms 1 region fill",
        "set group all diameter 1.0 density 1.0",
        "velocity all create 0.01 4928 loop geom",
    ] + pair_and_fix(opts) + momentum_thermo() + ["run 50"]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_cluster_" + tag)
    if not ck.ran(run, "cluster %s: run completes" % tag):
        return
    check_conservation(ck, "cluster " + tag, run, 0.5)


def drop(args, ck, opts, tag):
    z0, g = 3.0, 1.0
    lines = header("-5 5 -5 5 0 10") + [
        "create_atoms 1 single 0 0 %g units box" % z0,
        "set atom 1 diameter 1.0 density 1.0",
        "velocity all set 0.2 0 0",
        "fix g all gravity %g vector 0 0 -1" % g,
    ] + pair_and_fix(opts, walls="wall zplane 0.0 NULL") + [
        "compute ke all ke",
        "compute rot all erotate/sphere",
        # v is the velocity of the drift x += dt v that follows: the energy of the scheme
        # takes the potential at the midpoint of that drift (exact in free fall)
        "variable pe equal mass[1]*%g*(z[1]+0.5*%g*vz[1])" % (g, DT),
        "variable e equal c_ke+c_rot+v_pe",
        "variable z equal z[1]",
        "thermo_style custom step v_e c_ke c_rot v_z f_fc[3] f_fc[7] f_fc[10]",
        "thermo_modify format float %.17g",
        "thermo 1",
        "run 1000",
    ]
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_drop_" + tag)
    if not ck.ran(run, "drop %s: run completes" % tag):
        return
    rows = run.thermo[-1]
    e0 = rows[0]["v_e"]
    gain = max(r["v_e"] - e0 for r in rows)
    ck.check(gain <= 1e-12 * e0, "drop %s: total energy never grows" % tag,
             "max (E - E0)/E0 = %.3g, final E/E0 = %.4g" % (gain / e0, rows[-1]["v_e"] / e0))
    v_impact = math.sqrt(2 * g * (z0 - 0.5))
    overlap = max(r["f_fc[7]"] for r in rows)
    ck.check(overlap <= v_impact * DT, "drop %s: overlap below v_impact dt" % tag,
             "max overlap %.4g, v_impact dt = %.4g" % (overlap, v_impact * DT))
    ck.check(abs(rows[-1]["v_z"] - 0.5) < 1e-5 and rows[-1]["f_fc[7]"] < 1e-5,
             "drop %s: comes to rest on the floor" % tag,
             "z = %.8g, overlap %.3g" % (rows[-1]["v_z"], rows[-1]["f_fc[7]"]))


def fast_pass(args, ck, np):
    lines = header(processors="2 1 1" if np > 1 else None) + [
        "create_atoms 1 single -3 0 0 units box",
        "create_atoms 1 single 3 0 0 units box",
        "set group all diameter 1.0 density 1.0",
        "group a id 1",
        "group b id 2",
        "velocity a set 10 0 0",
        "velocity b set -10 0 0",
        "variable x1 equal x[1]",
        "variable x2 equal x[2]",
    ] + pair_and_fix("") + ["neigh_modify delay 10", "thermo_style custom step v_x1 v_x2",
                            "thermo 10", "run 60"]
    tag = "fast_pass_np%d" % np
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", "collision_" + tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    warned = "neigh_modify every 1 delay 10 check yes can miss contacts" in run.output
    ck.check(warned, "%s: the fix says it checks the neighbor list every step" % tag,
             "warning %s" % ("given" if warned else "missing"))
    last = run.thermo[-1][-1]
    gap = last["v_x2"] - last["v_x1"] - 1.0
    ck.check(abs(gap) < 1e-6, "%s: the spheres collide and come to rest touching, not pass" % tag,
             "x1 %.6g, x2 %.6g (passed through: x1 > x2)" % (last["v_x1"], last["v_x2"]))
    ck.check("Dangerous builds = 0" in run.output, "%s: no dangerous neighbor list builds" % tag,
             "; ".join(line for line in run.output.splitlines() if "Dangerous" in line))


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("collisions")
    for tag, opts in [("default", ""), ("body_minres", "form body solver minres"),
                      ("direct", "solver direct")]:
        head_on(args, ck, opts, tag)
        oblique(args, ck, opts, tag)
        row_hit(args, ck, opts, tag)
        drop(args, ck, opts, tag)
    for tag, opts in [("frictionless", "mu 0"), ("friction", "mu 0.5"),
                      ("friction_direct", "mu 0.5 solver direct")]:
        cluster(args, ck, opts, tag)
    for np in (1, 2):
        fast_pass(args, ck, np)
    ck.close()


if __name__ == "__main__":
    main()
