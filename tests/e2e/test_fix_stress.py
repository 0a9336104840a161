"""Stress: the contact forces' virial in compute stress/atom, compute pressure and thermo press.

- A resting column of N spheres of different sizes on a zplane wall under gravity g: the
  contact below sphere k carries the weight W_k of the spheres above it (k included), so the
  zz virial summed over the atoms is sum_k W_k l_k, with l_k the distance between the
  centres of sphere k and the one below it (the wall's surface point for the lowest). The
  sum of compute stress/atom (which is minus the virial) must equal it to 1e-6, on one
  process and on two, where the column crosses the boundary between the domains.
- compute pressure with the virial alone, times 3 V, equals the trace of the summed per-atom
  virial (global and per-atom tallies agree), and the off-diagonal terms vanish.
- A disordered bed of 80 spheres with friction, periodic in x and y, settling on a floor at
  z = 0: the zz virial of all contacts is sum_i z_i F_i, with the contact force F_i on each
  sphere taken from its momentum change over the step, m_i (dv_z / dt + g) (the wall enters
  at its surface point, z = 0): to 1e-9 on one and two processes. Near rest it is close to
  sum_i m_i g z_i.
"""

import random

import fibre_e2e as e2e

DIAMETERS = [1.0, 0.8, 1.2, 0.9, 1.1, 1.0, 0.7, 1.3]
DT = 0.01
G = 1.0
STEPS = 600


def deck(np):
    lines = e2e.sphere_box("-3 3 -3 3 0 12", processors="1 1 2" if np == 2 else None)
    lines += e2e.stacked_column(DIAMETERS)[1]
    lines += [
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity %g vector 0 0 -1" % G,
        "fix fc all fibre_contact wall zplane 0.0 NULL solver cg tol none linear_tol 1e-10 "
        "sweep_tol 1e-10 sweeps 200",
        "compute sa all stress/atom NULL virial",
        "compute s all reduce sum c_sa[1] c_sa[2] c_sa[3] c_sa[4] c_sa[5] c_sa[6]",
        "compute p all pressure NULL virial",
        "variable vol equal vol",
        "thermo_style custom step c_s[1] c_s[2] c_s[3] c_s[4] c_s[5] c_s[6] c_p v_vol",
        "thermo_modify format float %.17g norm no",
        "thermo 100",
        "dump a all custom %d stress_np%d.atoms id z mass" % (STEPS, np),
        "dump_modify a sort id format float %.17g",
        "run %d" % STEPS,
    ]
    return "\n".join(lines) + "\n"


def column(args, ck, np):
    tag = "column_np%d" % np
    run = e2e.run_lmp(args, deck(np), tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    atoms = e2e.dump_by_id(e2e.parse_dump(args.workdir + "/stress_np%d.atoms" % np)[-1])
    ids = sorted(atoms)
    expected = 0.0
    for k, i in enumerate(ids):
        below = atoms[ids[k - 1]]["z"] if k > 0 else 0.0
        weight = G * sum(atoms[j]["mass"] for j in ids[k:])
        expected += weight * (atoms[i]["z"] - below)
    last = run.thermo[-1][-1]
    zz = -last["c_s[3]"]
    ck.agree(zz, expected, 1e-6, "%s: summed stress/atom zz = sum of weight times height" % tag)
    trace = -(last["c_s[1]"] + last["c_s[2]"] + last["c_s[3]"])
    ck.agree(last["c_p"] * 3 * last["v_vol"], trace, 1e-9,
             "%s: compute pressure (virial) times 3 V = trace of the per-atom virial" % tag)
    off = max(abs(last["c_s[%d]" % k]) for k in (1, 2, 4, 5, 6))
    ck.check(off <= 1e-9 * abs(zz), "%s: no lateral or shear virial in a straight column" % tag,
             "largest %.3g against zz %.3g" % (off, zz))


def bed_deck(np):
    lines = e2e.sphere_box("0 5 0 5 0 12", boundary="p p f",
                           processors="1 1 2" if np == 2 else None)
    # 5 layers of 4 x 4, 1.25 apart, each sphere shifted sideways by up to 0.12
    rng = random.Random(4821)
    for k in range(80):
        i, j, layer = k % 4, (k // 4) % 4, k // 16
        x = 0.625 + 1.25 * i + rng.uniform(-0.12, 0.12)
        y = 0.625 + 1.25 * j + rng.uniform(-0.12, 0.12)
        lines.append("create_atoms 1 single %.6f %.6f %.6f units box" % (x, y, 0.6 + 1.25 * layer))
    lines += [
        "set group all diameter 1.0",
        "set group all density 1.0",
        "pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0",
        "pair_coeff * *",
        "neighbor 0.2 bin",
        "timestep %g" % DT,
        "fix g all gravity %g vector 0 0 -1" % G,
        "fix fc all fibre_contact wall zplane 0.0 NULL mu 0.5 mu_roll 0.1 damping 4",
        "run 3000",
        "compute sa all stress/atom NULL virial",
        "compute s all reduce sum c_sa[3]",
        "thermo_style custom step c_s",
        "thermo_modify format float %.17g norm no",
        "thermo 1",
        "dump a all custom 1 bed_np%d.atoms id z vz mass" % np,
        "dump_modify a sort id format float %.17g",
        "run 2",
    ]
    return "\n".join(lines) + "\n"


def bed(args, ck, np):
    tag = "bed_np%d" % np
    run = e2e.run_lmp(args, bed_deck(np), tag, np=np)
    if not ck.ran(run, "%s: run completes" % tag):
        return
    frames = e2e.parse_dump(args.workdir + "/bed_np%d.atoms" % np)
    before, after = e2e.dump_by_id(frames[-2]), e2e.dump_by_id(frames[-1])
    # the contact force on each sphere from its momentum change over the last step
    expected = sum(a["z"] * a["mass"] * ((a["vz"] - before[i]["vz"]) / DT + G)
                   for i, a in after.items())
    virial = -run.thermo[-1][-1]["c_s"]
    ck.agree(virial, expected, 1e-9,
             "%s: zz virial = sum of z times contact force from the momentum change" % tag)
    weight = sum(a["mass"] * G * a["z"] for a in after.values())
    ck.agree(virial, weight, 1e-2, "%s: near rest, within 1%% of sum of m g z" % tag)


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("stress")
    for np in (1, 2):
        column(args, ck, np)
        bed(args, ck, np)
    ck.close()


if __name__ == "__main__":
    main()
