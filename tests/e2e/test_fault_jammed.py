"""Faults: a jammed pack. 125 spheres on a simple cubic lattice of spacing 1 in a walled box
5 x 5 x 5 (hertz/material E = 1e6, Mindlin, tsuji, walls of the same material, density 1000,
no gravity), grown by fix adapt from d = 0.6 to 1.15 in 2 s, then held for 1 s: a solid
fraction of 0.80, more than any packing holds, so every contact ends 0.15 deep (13% of a
diameter). The fix at 1e-3 s, native LAMMPS at 1e-4 s.

- grown (the neighbour skin 0.6 covers the growth): nothing lost or NaN, the fastest sphere
  within twice native's and the pack at rest at the end, as native's; serial and np 2.
- over-compressed from the start (the spheres created at d = 1.15, as a packing read from
  another code): nothing lost or NaN; no sphere faster than the recovery speed (0.01 r / dt,
  5.75 m/s); the overlaps stay (no room to remove them, and the displacement that would only
  move them from contact to contact is not taken); serial and np 2. (The displacement did move
  them: the deepest overlap grew from 0.15 to 0.8 in 1000 steps, the spheres reached 3 m/s
  and 4 of 125 left the box.) The log says the pack is jammed. Native pushes the pack apart with its springs and comes to rest,
  for the record.
"""

import fibre_e2e as e2e

LAW = "hertz/material 1e6 0.3 0.3 tangential mindlin NULL 1.0 0.5 damping tsuji"
WALLS = " ".join("wall granular %s %splane 0 5" % (LAW, p) for p in "xyz")
NATIVE = "\n".join(["fix n all nve/sphere"] + ["fix w%s all wall/gran granular %s %splane 0 5"
                                               % (p, LAW, p) for p in "xyz"])

DECK = """units si
atom_style sphere 1
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
processors {procs}
region box block 0 5 0 5 0 5 units box
create_box 1 box
lattice sc 1.0
region bed block 0 5 0 5 0 5 units box
create_atoms 1 region bed
displace_atoms all move 0.5 0.5 0.5 units box
set type 1 diameter {d0}
set type 1 density 1000
pair_style granular
pair_coeff * * """ + LAW + """
neighbor 0.6 bin
neigh_modify every 1 delay 0
timestep {dt}
variable grow equal {d0}+(1.15-{d0})*elapsed/{grow}
{adapt}
{integrate}
variable speed atom sqrt(vx*vx+vy*vy+vz*vz)
compute fastest all reduce max v_speed
thermo_style custom step atoms ke c_fastest {extra}
thermo_modify lost warn format float %.10g
thermo {every}
run {grow}
{unadapt}
run {hold}
"""


def deck(case, method, np):
    dt = 1e-3 if method == "fibre" else 1e-4
    grown = case == "grown"
    return DECK.format(
        procs="2 1 1" if np == 2 else "1 1 1", d0=0.6 if grown else 1.15, dt=dt,
        grow=int(round(2.0 / dt)), hold=int(round(1.0 / dt)), every=int(round(0.1 / dt)),
        adapt="fix a all adapt 1 atom diameter v_grow" if grown else "",
        unadapt="unfix a" if grown else "",
        integrate=("fix f all fibre_contact " + WALLS) if method == "fibre" else NATIVE,
        extra="f_f[7]" if method == "fibre" else "")


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("faults: a jammed pack, grown or over-compressed from the start")
    for case in ("grown", "overcompressed"):
        native = e2e.run_lmp(args, deck(case, "native", 1), "%s_native" % case)
        n_fast = max(native.column("c_fastest")) if native.rc == 0 else float("nan")
        if native.rc == 0:
            print("native %s: %d atoms at the end, fastest %.4g m/s, last %.4g m/s"
                  % (case, native.last("Atoms"), n_fast, native.last("c_fastest")))
        for np in (1, 2):
            run = e2e.run_lmp(args, deck(case, "fibre", np), "%s_fibre_np%d" % (case, np), np=np)
            what = "%s np %d: " % (case, np)
            if not ck.ran(run):
                continue
            speeds, deepest = run.column("c_fastest"), run.column("f_f[7]")
            ck.check(run.last("Atoms") == 125 and e2e.finite(speeds) and e2e.finite(deepest),
                     what + "nothing lost, nothing NaN", "%d atoms" % run.last("Atoms"))
            print("%sfastest %.4g m/s, last %.4g, deepest overlap %.4g at the end"
                  % (what, max(speeds), run.last("c_fastest"), run.last("f_f[7]")))
            if case == "grown":
                ck.check(max(speeds) <= 2.0 * n_fast, what + "fastest within twice native's",
                         "%.4g against %.4g m/s" % (max(speeds), n_fast))
                ck.check(run.last("c_fastest") < 1e-3, what + "the pack at rest at the end",
                         "%.4g m/s (native %.4g)" % (run.last("c_fastest"),
                                                     native.last("c_fastest")))
            else:
                ck.check(max(speeds) <= 5.75, what + "no sphere faster than the recovery speed",
                         "%.4g m/s" % max(speeds))
                ck.check(max(deepest) <= 0.151, what + "the overlaps stay as they were",
                         "deepest %.4g" % max(deepest))
                ck.check("penetrations have no room to open" in run.output,
                         what + "the log says the pack is jammed")
    ck.close()


if __name__ == "__main__":
    main()
