"""Substeps (substeps auto): a head-on pair of stiff spheres at a step of five collision times.

The material deck's law at E = 1e8 (examples/material/in.headon: Hertz, Tsuji damping), no
gravity, each sphere at v towards the other, at the decks' step of 4.43 ms (5 t_c):
- native LAMMPS (fix nve/sphere at 2e-5 s, lmp_fibre as a drop-in) rebounds at its law's
  e (0.232 at 1 m/s, 0.234 at 0.05 m/s);
- the fix with substeps auto takes 16 substeps of 0.31 t_c (the log says so) and rebounds
  within 5% of native's e at 1 m/s (Newton's law at the substep that closes) and within 12% at
  0.05 m/s, below the automatic bounce speed, where the compliant rows resolve the collision
  (one solve a step, substeps 1, stops that pair dead, and the log warns of the step);
- on two processes (one sphere on each) the rebounds are the serial ones within 1e-6;
- substep_when moving: one solve where nothing moves at a contact (in flight, at rest).
"""

import os
import re
import shutil

import fibre_e2e as e2e

E, DT = 1e8, 0.0044343


def headon(args):
    with open(os.path.join(args.source, "examples", "material", "in.headon")) as f:
        return f.read()


def rebound(args, ck, tag, v, np=1, method="fibre", extra=""):
    variables = {"E": E, "v": v, "method": method}
    if extra:
        variables["fc_extra"] = extra
    variables.update({"dt": 2e-5, "n": 8000} if method == "native" else {"dt": DT, "n": 60})
    run = e2e.run_lmp(args, headon(args), "headon_" + tag, np=np, variables=variables)
    if not ck.ran(run):
        return None, run
    return run.last("v_e"), run


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("substeps: a stiff head-on pair at a step of five collision times")
    for v, tol in ((1.0, 0.05), (0.05, 0.12)):
        native, _ = rebound(args, ck, "native_%g" % v, v, method="native")
        fix, run = rebound(args, ck, "fibre_%g" % v, v)
        fix2, _ = rebound(args, ck, "fibre_np2_%g" % v, v, np=2)
        one, one_run = rebound(args, ck, "single_%g" % v, v, extra="substeps 1")
        if None in (native, fix, fix2, one):
            continue
        ck.check(0.2 < native < 0.26, "v %g: native rebounds at its law's e" % v, "%.4g" % native)
        ck.check(abs(fix - native) < tol * native,
                 "v %g: substeps auto rebounds at native's e within %g%%" % (v, 100 * tol),
                 "%.4g against %.4g" % (fix, native))
        ck.check(abs(fix2 - fix) < 1e-6, "v %g: two processes rebound as one" % v,
                 "%.7g against %.7g" % (fix2, fix))
        found = re.search(r"the contact solve takes (\d+) substeps of (\S+) t_c", run.output)
        ck.check(found is not None and found.group(1) == "16" and float(found.group(2)) <= 0.33,
                 "v %g: the log states 16 substeps of at most 0.33 t_c" % v,
                 found.group(0) if found else "no substeps line")
        if v < 0.1:
            ck.check(one < 0.01, "v %g: one solve a step stops the slow pair dead" % v,
                     "%.3g" % one)
            ck.check("Substeps longer than about a third of t_c" in one_run.output,
                     "v %g: substeps 1 at 5 t_c is warned of in the log" % v)
    plastic_pour(args, ck)
    quiet_steps(args, ck)
    restart_after_landing(args, ck)
    ck.close()


DROP = """
units       si
atom_style  sphere
atom_modify map array
boundary    f f f
newton      off
comm_modify vel yes
processors  ${px} 1 1
region      box block -2 2 -1 1 0 2 units box
create_box  1 box
create_atoms 1 single -1 0 0.30 units box
create_atoms 1 single 1 0 0.25 units box
set         atom * diameter 0.5 density 1.0
pair_style  granular
pair_coeff  * * hertz/material 1e8 0.1 0.2857142857 tangential mindlin NULL 1.0 0.5 &
            rolling sds 1.0e3 10.0 0.3 damping tsuji
neighbor    0.3 bin
neigh_modify delay 0 every 1 check yes
timestep    0.0044343
fix         g all gravity 9.81 vector 0 0 -1
fix         fc all fibre_contact wall zplane 0.0 NULL ${fc_extra}
variable    z1 equal z[1]
variable    z2 equal z[2]
variable    vz1 equal vz[1]
thermo_style custom step v_z1 v_z2 v_vz1 f_fc[21] f_fc[7]
thermo_modify format float %.10g
thermo      1
run         200
"""


def quiet_steps(args, ck):
    """substep_when moving: two spheres of the E = 1e8 law, one dropped from 5 cm onto the
    floor, one set on it. The steps in which the first lands take the 16 substeps, the others
    (in flight, at rest) one solve: f_fc[21] says which. Its rebound apex is native's e^2 h
    within 15% (e 0.232 at 1 m/s), as with substep_when always (the default: every step 16
    substeps; its flight follows the substeps, at most 0.1 mm a step apart from the plain
    step's), and both come to rest at the same height within 1e-6 m; on two processes (one
    sphere each) the trajectories are the serial ones within 1e-9 m. Between steps (the thermo
    line) the positions are those the step detected its contacts at: the deepest floor overlap
    they show is the step's f_fc[7], also in the steps whose substeps land and bounce (the
    substeps' displacement is added at the next step's start, not before the output)."""
    runs = {}
    for tag, np, extra in (("moving", 1, "substep_when moving"), ("always", 1, ""),
                           ("moving_np2", 2, "substep_when moving")):
        run = e2e.run_lmp(args, DROP, "quiet_" + tag, np=np,
                          variables={"fc_extra": extra, "px": np})
        if not ck.ran(run):
            return
        runs[tag] = [r for b in run.thermo for r in b]
    rows, always = runs["moving"], runs["always"]
    counts = [int(r["f_fc[21]"]) for r in rows[1:]]
    ck.check(set(counts) == {1, 16}, "substep_when moving: a step takes 16 substeps or one",
             "%s" % sorted(set(counts)))
    ck.check(0 < counts.count(16) < len(counts) // 4,
             "the landings take the substeps, a few steps of 200",
             "%d of %d" % (counts.count(16), len(counts)))
    ck.check(counts[-20:] == [1] * 20, "both spheres at rest: one solve a step",
             "%s" % counts[-20:])
    ck.check(all(int(r["f_fc[21]"]) == 16 for r in always[1:]),
             "substep_when always: every step 16 substeps")
    apexes = []
    for table in (rows, always):
        # the landing step's line: its velocity is the bounce's, its position the step's start
        first = next(k for k in range(1, len(table)) if table[k]["v_vz1"] > 0) + 1
        apexes.append(max(r["v_z1"] for r in table[first:first + 40]) - table[-1]["v_z1"])
    e, h = 0.232, 0.05
    for name, apex in zip(("moving", "always"), apexes):
        ck.check(abs(apex - e * e * h) < 0.15 * e * e * h,
                 "substep_when %s: the dropped sphere rebounds to e^2 h within 15%%" % name,
                 "%.4g m against %.4g" % (apex, e * e * h))
    radius = 0.25
    for name, table in (("moving", rows), ("always", always)):
        shown = [max(0.0, radius - r["v_z1"], radius - r["v_z2"]) for r in table[1:]]
        worst = max(abs(a - r["f_fc[7]"]) for a, r in zip(shown, table[1:]))
        ck.check(worst < 1e-9, "substep_when %s: the positions between steps are the step's, "
                 "their floor overlap its f_fc[7]" % name, "%.3g m off" % worst)
    rest = max(abs(rows[-1][c] - always[-1][c]) for c in ("v_z1", "v_z2"))
    ck.check(rest < 1e-6, "at rest both at always's heights within 1e-6 m", "%.3g m" % rest)
    worst = max(abs(a[c] - b[c]) for a, b in zip(rows, runs["moving_np2"])
                for c in ("v_z1", "v_z2"))
    ck.check(worst < 1e-9, "two processes: the serial trajectories", "%.3g m" % worst)


# the same spheres continued from the restart file of step 23, with the drop's fixes and output
RESUME = """
atom_modify map array
processors  1 1 1
read_restart drop.23.restart
neighbor    0.3 bin
neigh_modify delay 0 every 1 check yes
comm_modify vel yes
""" + DROP[DROP.index("fix         g"):].replace("run         200", "run         177")


def restart_after_landing(args, ck):
    """A restart file written within a run, at the end of the step whose substeps land the
    dropped sphere and bounce it (step 23), continues the run's trajectory: the substeps'
    displacement still to be added at the next step's start is in the file."""
    deck = DROP.replace("run         200", "restart     23 drop.*.restart\nrun         200")
    full = e2e.run_lmp(args, deck, "restart_full", variables={"fc_extra": "", "px": 1})
    if not ck.ran(full):
        return
    rest = e2e.run_lmp(args, RESUME, "restart_resumed", variables={"fc_extra": ""})
    if not ck.ran(rest):
        return
    a = {int(r["Step"]): r for b in full.thermo for r in b}
    b = {int(r["Step"]): r for blk in rest.thermo for r in blk}
    steps = [n for n in range(24, 201) if n in a and n in b]
    worst = max(abs(a[n][c] - b[n][c]) for n in steps for c in ("v_z1", "v_z2", "v_vz1"))
    ck.check(len(steps) == 177 and worst < 1e-12,
             "a restart written after a landing step continues the run's trajectory",
             "%d steps, %.3g off" % (len(steps), worst))


def plastic_pour(args, ck):
    """The material deck's pour at E = 1e8 without restitution (restitution 0): 15 substeps,
    and no bounce anywhere, so detection must still reach as far as the impacts kick the
    spheres. Before it did, a sphere that a plastic impact at 12.5 m/s kicked in the step's
    first substep ran into a neighbour without a contact, and from step 385 on the overlaps grew
    to 90% of a radius and spheres left the box. Its first 1.8 s (406 steps, 310 spheres)."""
    source = os.path.join(args.source, "examples", "material")
    for name in ("scene.material", "run.material"):
        shutil.copy(os.path.join(source, name), args.workdir)
    with open(os.path.join(source, "in.material")) as f:
        deck = f.read()
    run = e2e.run_lmp(args, deck, "plastic_pour", variables={
        "N": 1400, "E": E, "tend": 1.8, "fc_extra": "restitution 0"})
    if not ck.ran(run):
        return
    rows = [r for b in run.thermo for r in b]
    deepest = max(r["f_fc[7]"] for r in rows)
    ck.check(deepest < 0.0025, "a plastic stiff pour: the deepest overlap stays below 1% of the "
             "smallest radius", "%.3g" % deepest)
    ck.check(rows[-1]["Atoms"] == 310, "a plastic stiff pour: no sphere leaves the box",
             "%d atoms" % rows[-1]["Atoms"])


if __name__ == "__main__":
    main()
