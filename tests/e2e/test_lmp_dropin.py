"""lmp_fibre is a drop-in replacement for Debian's lmp (issue 2 acceptance):
- a shortened official pour deck gives the same thermo output as lmp;
- the startup banner names the add-on;
- an unknown fix style exits non-zero with a LAMMPS error;
- it runs under mpirun -np 2.
"""
import os
import re
import shutil

from e2e_common import Checks, lmp_cmd, parse_args, run, thermo_blocks

args = parse_args()
checks = Checks()
wd = args.workdir

# The official pour deck, shortened to 2000 steps with thermo every 200.
official = "/usr/share/lammps/examples/pour/in.pour"
deck = open(official).read()
deck = re.sub(r"thermo\s+1000", "thermo 200", deck)
deck = deck.replace("run\t\t25000\n\nunfix", "run 1000\n\nunfix").replace("run\t\t25000", "run 1000")
assert deck.count("run 1000") == 2, "pour deck layout changed"
with open(os.path.join(wd, "in.pour"), "w") as f:
    f.write(deck)

rc_f, out_f = run(lmp_cmd(args, "in.pour"), wd)
lmp = shutil.which("lmp") or "/usr/bin/lmp"
rc_l, out_l = run([lmp, "-in", "in.pour", "-log", "log.lmp"], wd)
checks.check("pour runs with lmp_fibre", rc_f == 0, f"exit {rc_f}")
checks.check("pour runs with lmp", rc_l == 0, f"exit {rc_l}")
tf, tl = thermo_blocks(out_f), thermo_blocks(out_l)
checks.check("same thermo tables", len(tf) == 2 and tf == tl,
             f"{len(tf)} blocks, last rows {tf[-1][1][-1] if tf else None} vs "
             f"{tl[-1][1][-1] if tl else None}")
checks.check("banner names the add-on", "fibre_contact add-on" in out_f)

# Unknown style: a LAMMPS error and a non-zero exit.
bad = "units lj\natom_style sphere\nregion b block 0 1 0 1 0 1\ncreate_box 1 b\nfix 1 all no_such_fix\n"
rc, out = run(lmp_cmd(args, "in.bad"), wd, bad, "in.bad")
checks.check("unknown fix exits non-zero", rc != 0, f"exit {rc}")
checks.check("unknown fix message", "ERROR" in out and "no_such_fix" in out)

# Bad argument for fibre_contact.
bad2 = bad.replace("fix 1 all no_such_fix", "pair_style granular\npair_coeff * * hertz/material 1e5 0.2 0.3 tangential linear_nohistory 1.0 0.0\nfix 1 all fibre_contact tol -1")
rc, out = run(lmp_cmd(args, "in.bad2"), wd, bad2, "in.bad2")
checks.check("bad fibre_contact argument exits non-zero", rc != 0, f"exit {rc}")
checks.check("bad argument message names the keyword", "ERROR" in out and "tol" in out,
             out.strip().splitlines()[-1] if out.strip() else "")

# mpirun -np 2 on the stock deck: same atom counts as serial.
rc, out = run(lmp_cmd(args, "in.pour", np=2), wd)
t2 = thermo_blocks(out)
checks.check("mpirun -np 2 runs", rc == 0 and len(t2) == 2, f"exit {rc}")
if len(t2) == 2 and len(tf) == 2:
    checks.check("mpirun -np 2 inserts the same atoms",
                 [r[1] for r in t2[0][1]] == [r[1] for r in tf[0][1]])
# mpirun -np 2 on a deck that uses fix fibre_contact: 80 spheres dropped onto a floor.
fibre_deck = """
units si
atom_style sphere
boundary p p fm
newton off
comm_modify vel yes
lattice sc 1.0
region box block 0 4 0 4 0 12 units box
create_box 1 box
region drop block 0 4 0 4 2 6 units box
create_atoms 1 region drop
set group all diameter 0.9
set group all density 1.0
velocity all create 1.0 4928 loop geom
pair_style granular
pair_coeff * * hertz/material 1e5 0.2 0.3 tangential linear_nohistory 1.0 0.5
neighbor 0.3 bin
fix g all gravity 9.81 vector 0 0 -1
fix fc all fibre_contact mu 0.5 wall zplane 0.0 NULL
timestep 0.005
compute ke all ke
thermo_style custom step atoms c_ke f_fc[1] f_fc[3]
thermo 50
run 300
"""
for np in (1, 2):
    rc, out = run(lmp_cmd(args, "in.fibre_np%d" % np, np=np), wd, fibre_deck, "in.fibre_np%d" % np)
    t = thermo_blocks(out)
    ok = rc == 0 and len(t) == 1 and len(t[0][1]) == 7
    checks.check("fix fibre_contact runs with %d rank(s)" % np, ok, f"exit {rc}")
    if ok:
        last = t[0][1][-1]
        checks.check("np %d: all 80 atoms kept, finite, contacts found" % np,
                     last[1] == 80 and all(abs(v) < 1e30 for v in last) and last[4] > 0,
                     str(last))
checks.finish()
