"""Coefficients per type pair from the pair style (keyword coefficients, default pair).

- Two types on an incline (gravity tilted by theta, tan theta = 0.45) with pair_style granular:
  type 1 has mu 0.2, type 2 mu 0.8, both rolling sds with mu_roll 1 (no rolling). The plane
  wall takes each sphere's own type's coefficients. Type 1 slides with a = g (sin theta -
  0.2 cos theta), type 2 sticks; on one process and on two.
- The fix's typed mu overrides every pair: with mu 0.9 both stick.
- Restitution per type from hertz/material's e with damping tsuji: a type-1 sphere (e 0.3)
  and a type-2 sphere (e 0.9) dropped side by side rebound to e'^2 h each, within 2%, where
  e' is the rebound of LAMMPS's own damped law: native LAMMPS (the pair style without the
  fix) runs two spheres of that pair_coeff head on, and e' is their separation / approach ratio (0.439
  and 0.928, not the 0.3 and 0.9 typed); on one process and on two (one sphere on each).
- The older styles: gran/hooke/history's xmu is every pair's mu (a sphere slides with
  xmu 0.2), and the log says which coefficients were read and what is not used.
- coefficients fix: the pair style is ignored and the fix's defaults hold (mu 0.5: sticks).
- compliance material: a resting column of spheres of hertz/material overlaps as Hertz says,
  also with normal_relaxation law at E = 2e8 (np 1 and 2),
  d = (W / (k_n sqrt(r_eff)))^(2/3) with W the weight above each contact and k_n = 4/3 E_eff:
  every sphere's height within 1% of the overlaps below it, serial (typed) and on two
  processes (untyped: the default with pair_style granular, and the log says so); with
  gran/hooke/history the default is compliance auto (rigid rows).
"""

import math
import os
import re

import fibre_e2e as e2e

G = 1.0
TAN = 0.45
SIN, COS = TAN / math.sqrt(1 + TAN * TAN), 1 / math.sqrt(1 + TAN * TAN)
DT = 1e-3
T = 2.0

GRANULAR = """pair_style granular
pair_coeff 1 1 hertz/material 1e6 0.3 0.3 tangential mindlin NULL 1.0 0.2 rolling sds 1e3 50 1.0 damping tsuji
pair_coeff 2 2 hertz/material 1e6 0.9 0.3 tangential mindlin NULL 1.0 0.8 rolling sds 1e3 50 1.0 damping tsuji"""


def deck(pair, gravity, atoms, fix_extra, np, steps):
    lines = e2e.sphere_box("-10 10 -10 10 0 10", types=2, processors="2 1 1" if np == 2 else None)
    for k, (t, x, z) in enumerate(atoms):
        lines += ["create_atoms %d single %g 0 %g units box" % (t, x, z),
                  "set atom %d diameter 1.0 density 1.0" % (k + 1)]
    lines += pair.splitlines() + [
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity %g vector %s" % (G, gravity),
        "fix fc all fibre_contact wall zplane 0.0 NULL %s" % fix_extra,
        "variable vx1 equal vx[1]",
        "variable vx2 equal vx[2]",
        "variable z1 equal z[1]",
        "variable z2 equal z[2]",
        "variable vz1 equal vz[1]",
        "variable vz2 equal vz[2]",
        "thermo_style custom step v_vx1 v_vx2 v_z1 v_z2 v_vz1 v_vz2",
        "thermo_modify format float %.17g",
        "thermo 1",
        "run %d" % steps,
    ]
    return "\n".join(lines) + "\n"


def incline(args, ck, tag, pair, fix_extra, slides, np=1, types=(1, 2)):
    gravity = "%.17g 0 %.17g" % (SIN, -COS)
    atoms = [(types[0], -5.0, 0.5), (types[1], 5.0, 0.5)]
    run = e2e.run_lmp(args, deck(pair, gravity, atoms, fix_extra, np, int(T / DT)), tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return run
    last = run.thermo[-1][-1]
    for k, (slide, mu) in enumerate(slides):
        v = last["v_vx%d" % (k + 1)]
        if slide:
            expected = G * (SIN - mu * COS) * T
            ck.agree(v, expected, 1e-2, "%s: sphere %d slides with g (sin - %g cos)" %
                     (tag, k + 1, mu))
        else:
            # at rest up to the solver's tolerance: 1e-4 of the free slide's speed
            ck.check(abs(v) < 1e-4 * G * SIN * T, "%s: sphere %d sticks" % (tag, k + 1),
                     "vx %.3g" % v)
    return run


# Two unit spheres of one pair_coeff head on at 1 m/s under native LAMMPS (no fix): the
# separation / approach ratio once the collision is over.
NATIVE_PAIR = """units si
atom_style sphere
atom_modify map array
boundary f f f
comm_modify vel yes
region box block -3 3 -3 3 -3 3 units box
create_box 1 box
create_atoms 1 single -0.51 0 0 units box
create_atoms 1 single 0.51 0 0 units box
set atom * diameter 1.0 density 1.0
set atom 1 vx 1.0
set atom 2 vx -1.0
pair_style granular
pair_coeff * * %s
neighbor 0.3 bin
timestep 1e-4
fix nve all nve/sphere
run 2000
print "rebound $((vx[2]-vx[1])/2.0)"
"""


def native_rebound(args, coeff, tag):
    # lmp_fibre without the fix is LAMMPS (Debian's liblammps, as /usr/bin/lmp links it)
    run = e2e.run_lmp(args, NATIVE_PAIR % coeff, tag)
    found = re.findall(r"^rebound (\S+)", run.output, re.M)
    return float(found[-1]) if run.rc == 0 and found else None


def native_rebounds(args, ck):
    rebounds = {}
    for k, line in enumerate(GRANULAR.splitlines()[1:], start=1):
        coeff = line.split(None, 3)[3]
        rebounds[k] = native_rebound(args, coeff, "native_pair_type%d" % k)
        typed = float(coeff.split()[2])  # hertz/material E e nu
        ck.check(rebounds[k] is not None and typed < rebounds[k] < 1.0,
                 "native LAMMPS's head-on rebound of type %d (e %g typed) is %s" %
                 (k, typed, rebounds[k]))
    return rebounds


def drop(args, ck, rebounds, np):
    h = 2.0
    atoms = [(1, -3.0, h + 0.5), (2, 3.0, h + 0.5)]
    tag = "drop_two_types_np%d" % np
    run = e2e.run_lmp(args, deck(GRANULAR, "0 0 -1", atoms, "", np, 4000), tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    rows = run.thermo[-1]
    for k, e in rebounds.items():
        if e is None:
            continue
        first = next(i for i in range(1, len(rows)) if rows[i]["v_vz%d" % k] > 0)
        top = first
        while top + 1 < len(rows) and rows[top + 1]["v_vz%d" % k] > 0:
            top += 1
        rebound = rows[top]["v_z%d" % k] - 0.5
        ck.agree(rebound, e * e * h, 0.02,
                 "%s: type %d rebounds to e^2 h with native LAMMPS's e %.4f" % (tag, k, e))


def hertz_column(args, ck, np, fix_extra, E=2e4, name="hertz_column"):
    """Five Hertz spheres stacked on the floor come to rest at the law's overlaps. Their
    contacts are damped by the law's dashpot (tsuji, e = 0.5), as native's: the column rings
    for seconds, as native LAMMPS's does (velocity 0.009 m/s at 3 s in both), and rests by
    20 s. At E = 2e8 the dashpot is shorter than two steps, and with normal_relaxation law the
    rows are the law's spring and dashpot by implicit Euler."""
    nu, n = 0.3, 5
    k_n = 4.0 / 3.0 * E / (2 * (1 - nu * nu))
    atoms = [(1, 0.0, 0.5 + k) for k in range(n)]
    pair = ("pair_style granular\npair_coeff * * hertz/material %g 0.5 %g tangential mindlin "
            "NULL 1.0 0.5 damping tsuji" % (E, nu))
    lines = deck(pair, "0 0 -1", atoms, fix_extra, np, 20000).splitlines()
    lines = [ln.replace("thermo 1", "thermo 1000") for ln in lines]
    tag = "%s_np%d" % (name, np)
    lines.insert(-1, "dump a all custom 20000 %s.atoms id z mass" % tag)
    lines.insert(-1, "dump_modify a sort id format float %.17g")
    run = e2e.run_lmp(args, "\n".join(lines) + "\n", tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    atoms = e2e.dump_by_id(e2e.parse_dump(args.workdir + "/%s.atoms" % tag)[-1])
    ids = sorted(atoms)
    z_expected, worst = 0.0, 0.0
    for k, i in enumerate(ids):
        weight = G * sum(atoms[j]["mass"] for j in ids[k:])
        r_eff = 0.5 if k == 0 else 0.25  # the floor, then a pair of equal spheres
        overlap = (weight / (k_n * r_eff ** 0.5)) ** (2.0 / 3.0)
        z_expected += (0.5 if k == 0 else 1.0) - overlap
        worst = max(worst, abs(atoms[i]["z"] - z_expected) / overlap)
    ck.check(worst < 0.01, "%s: Hertz overlaps at rest (largest error per overlap)" % tag,
             "%.3g of an overlap" % worst)
    if not fix_extra:
        ck.check("compliance material (pair style, else 0.01 dt^2 / m_min; the pair style is a "
                 "material)" in run.output, "%s: the log names the default compliance" % tag)


def collision_log(ck, run, tag):
    """The log states the step against the law's collision time: two spheres of the smallest
    radius (0.5) and mass meeting at 1 velocity unit, Hertz with k_n = 4/3 E / (2 (1 - nu^2)),
    t_c = 2 * 0.4 B(0.4, 0.5) d_max / v, d_max = (5 m_eff v^2 / (4 k_n sqrt(r_eff)))^(2/5)."""
    found = re.search(r"the step (\S+) is (\S+) collision times of the pair style's law "
                      r"\(t_c (\S+): two spheres of the smallest radius (\S+) and mass (\S+) "
                      r"meeting at 1 velocity unit, type pair (\d+) (\d+)\)", run.output)
    if not ck.check(found is not None, "%s: the log states the step against the collision time"
                    % tag):
        return
    E, nu, r, v = 1e6, 0.3, 0.5, 1.0
    m = 4.0 / 3.0 * math.pi * r ** 3
    k_n = 4.0 / 3.0 * E / (2 * (1 - nu * nu))
    d_max = (5 * (m / 2) * v * v / (4 * k_n * (r / 2) ** 0.5)) ** 0.4
    half = 0.4 * math.gamma(0.4) * math.gamma(0.5) / math.gamma(0.9)
    t_c = 2 * half * d_max / v
    step, ratio, logged = (float(found.group(k)) for k in (1, 2, 3))
    ck.check(abs(logged - t_c) < 1e-4 * t_c and abs(ratio - DT / t_c) < 1e-4 * ratio and
             step == DT and found.group(6, 7) == ("1", "1"),
             "%s: the logged t_c is Hertz's for the pair's E and nu" % tag,
             "t_c %s against %.6g, ratio %s against %.6g" % (found.group(3), t_c, found.group(2),
                                                             DT / t_c))


def incline_example(args, ck, np):
    """examples/incline/in.incline, the shipped example of two materials: type 1 slides at
    g (sin - 0.2 cos) within 1%, type 2 sticks (below 1e-4 of the free slide's speed)."""
    with open(os.path.join(args.source, "examples", "incline", "in.incline")) as f:
        deck = f.read()
    tag = "example_incline_np%d" % np
    run = e2e.run_lmp(args, deck, tag, np=np, variables={"px": np})
    if not ck.ran(run, "%s: run completes" % tag):
        return
    found = re.findall(r"^incline: type 1 vx (\S+) \(g \(sin - 0.2 cos\) t = (\S+)\), "
                       r"type 2 vx (\S+)$", run.output, re.M)
    if not ck.check(bool(found), "%s: the deck prints both speeds" % tag):
        return
    v1, slide, v2 = (float(x) for x in found[-1])
    ck.agree(v1, slide, 1e-2, "%s: type 1 (mu 0.2) slides at g (sin - 0.2 cos)" % tag)
    ck.check(abs(v2) < 1e-4 * slide, "%s: type 2 (mu 0.8) sticks" % tag, "vx %.3g" % v2)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("coefficients per type pair")
    incline_example(args, ck, 1)
    incline_example(args, ck, 2)
    run = incline(args, ck, "incline_types", GRANULAR, "", [(True, 0.2), (False, 0.8)])
    if run.rc == 0:
        ck.check("1 1: mu 0.2, mu_roll 1, twisting none, restitution 0.439" in run.output and
                 "2 2: mu 0.8, mu_roll 1, twisting none, restitution 0.928" in run.output,
                 "incline_types: the log lists the coefficients read per type pair")
        collision_log(ck, run, "incline_types")
    run = incline(args, ck, "incline_types_np2", GRANULAR, "", [(True, 0.2), (False, 0.8)], np=2)
    if run.rc == 0:
        collision_log(ck, run, "incline_types_np2")
    incline(args, ck, "incline_typed_mu", GRANULAR, "mu 0.9", [(False, 0.9), (False, 0.9)])
    rebounds = native_rebounds(args, ck)
    drop(args, ck, rebounds, 1)
    drop(args, ck, rebounds, 2)
    hooke = "pair_style gran/hooke/history 2000.0 NULL 50.0 NULL 0.2 0\npair_coeff * *"
    run = incline(args, ck, "incline_gran_hooke", hooke, "mu_roll 1.0",
                  [(True, 0.2), (True, 0.2)], types=(1, 1))
    if run.rc == 0:
        ck.check("mu = xmu 0.2" in run.output and
                 "used by 'compliance material' only" in run.output,
                 "incline_gran_hooke: the log says xmu is used and the springs are not")
        ck.check(", compliance auto (0.01 dt^2 / m_min)," in run.output,
                 "incline_gran_hooke: the default compliance of gran/* is auto")
        ck.check("collision times" not in run.output,
                 "incline_gran_hooke: no collision time where the pair style is no material")
    incline(args, ck, "incline_coefficients_fix", GRANULAR, "coefficients fix mu_roll 1.0",
            [(False, 0.5), (False, 0.5)])
    hertz_column(args, ck, 1, "compliance material")
    hertz_column(args, ck, 2, "")
    for np in (1, 2):
        hertz_column(args, ck, np, "normal_relaxation law", E=2e8, name="hertz_column_law")
    ck.close()


if __name__ == "__main__":
    main()
