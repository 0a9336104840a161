"""Acceptance 6: write_restart then read_restart continues the same trajectory.

Run A: 64 spheres with random velocities fall into a walled box (friction, rolling
resistance): 200 steps, write_restart, 200 more steps. Run B: read_restart of A's file, the
same fix commands again (same IDs), 200 steps. The fix stores the last step's contact
impulses per atom (the warm start) in the restart file, so B repeats A's last 200 steps:
positions and velocities agree to 1e-12 at step 400 (serial and with 2 processes), and the
solver's iteration counts agree step by step. Without the warm-start data (run C: the fix
with a new ID) the trajectory differs at the solver tolerance, which shows the data is used.
"""

import os

import fibre_e2e as e2e

SETUP = """atom_style sphere
atom_modify map array
boundary f f f
newton off
comm_modify vel yes
lattice sc 0.75
region box block -1 5 -1 5 -1 12
create_box 1 box
region fill block 0 3.9 0 3.9 2 5.9
create_atoms 1 region fill
set group all diameter 1.0 density 1.0
velocity all create 0.1 87287 loop geom
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
neighbor 0.2 bin
timestep 0.01
"""

FIXES = """fix g all gravity 1.0 vector 0 0 -1
fix {fid} all fibre_contact mu 0.5 mu_roll 0.05 wall xplane -0.55 4.95 &
    wall yplane -0.55 4.95 wall zplane -0.55 13.0
compute ke all ke
thermo_style custom step c_ke f_{fid}[1] f_{fid}[3] f_{fid}[6] f_{fid}[7]
thermo_modify format float %.17g
thermo 1
"""

DUMP = """dump d all custom 400 {name}.*.atoms id x y z vx vy vz
dump_modify d sort id format float %.17g first no
"""


def deck_a(name):
    return (SETUP + FIXES.format(fid="fc") + "run 200\nwrite_restart %s.restart\n" % name +
            DUMP.format(name=name) + "run 200\n")


def deck_b(name, restart, fid="fc"):
    return ("read_restart %s\nneighbor 0.2 bin\n" % restart + FIXES.format(fid=fid) +
            DUMP.format(name=name) + "run 200\n")


def compare(ck, args, tag, name_a, name_b):
    fa = e2e.parse_dump(os.path.join(args.workdir, "%s.400.atoms" % name_a))
    fb = e2e.parse_dump(os.path.join(args.workdir, "%s.400.atoms" % name_b))
    a, b = e2e.dump_by_id(fa[-1]), e2e.dump_by_id(fb[-1])
    ck.check(sorted(a) == sorted(b) and len(a) == 64, "%s: same atoms at step 400" % tag,
             "%d and %d atoms" % (len(a), len(b)))
    dx = max(abs(a[i][c] - b[i][c]) for i in a if i in b for c in ("x", "y", "z"))
    dv = max(abs(a[i][c] - b[i][c]) for i in a if i in b for c in ("vx", "vy", "vz"))
    ck.check(dx <= 1e-12 and dv <= 1e-12, "%s: read_restart continues the same trajectory" % tag,
             "max |dx| = %.3g, max |dv| = %.3g at step 400" % (dx, dv))


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("restart")
    for np in (1, 2):
        tag = "np%d" % np
        name_a, name_b = "restart_a_" + tag, "restart_b_" + tag
        run_a = e2e.run_lmp(args, deck_a(name_a), name_a, np=np)
        if not ck.ran(run_a, "%s: run A (400 steps, write_restart at 200)" % tag):
            continue
        run_b = e2e.run_lmp(args, deck_b(name_b, name_a + ".restart"), name_b, np=np)
        if not ck.ran(run_b, "%s: run B (read_restart, 200 steps)" % tag):
            continue
        compare(ck, args, tag, name_a, name_b)
        it_a = run_a.column("f_fc[1]", block=1)
        it_b = run_b.column("f_fc[1]", block=0)
        ck.check(it_a == it_b, "%s: Krylov iterations agree step by step" % tag,
                 "first steps A %s, B %s" % (it_a[1:5], it_b[1:5]))
        ck.check(run_b.thermo[0][0]["f_fc[3]"] == run_a.thermo[0][-1]["f_fc[3]"],
                 "%s: global vector restored (f_fc[3] at the restart step)" % tag,
                 "%g vs %g" % (run_b.thermo[0][0]["f_fc[3]"], run_a.thermo[0][-1]["f_fc[3]"]))
        if np == 1:
            name_c = "restart_c_" + tag
            run_c = e2e.run_lmp(args, deck_b(name_c, name_a + ".restart", fid="other"), name_c)
            if ck.ran(run_c, "%s: run C (read_restart, fix with a new ID)" % tag):
                # Without the stored impulses the first solves start from zero: the iterates,
                # hence the trajectory, differ from B's at the solver tolerance.
                ke_b, ke_c = run_b.column("c_ke", block=0), run_c.column("c_ke", block=0)
                it_c = run_c.column("f_other[1]", block=0)
                diff = max(abs(x - y) / max(abs(y), 1e-300) for x, y in zip(ke_c, ke_b))
                ck.check(diff > 1e-13, "%s: the restarted warm start is used" % tag,
                         "max rel diff of KE, cold (new fix ID) vs restarted: %.3g; iterations "
                         "of the first steps %s with it, %s cold" % (diff, it_b[1:4], it_c[1:4]))
    ck.close()


if __name__ == "__main__":
    main()
