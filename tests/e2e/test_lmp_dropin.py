"""lmp_fibre is a drop-in replacement for Debian's lmp (issue 2 acceptance):
- a shortened official pour deck gives the same thermo output as lmp;
- the startup banner names the add-on;
- an unknown fix style, and a bad fibre_contact argument, exit non-zero with a LAMMPS error;
- it runs under mpirun -np 2, the stock deck and a deck with fix fibre_contact.
"""
import os
import re
import shutil
import subprocess

import fibre_e2e as e2e

args = e2e.parse_args()
ck = e2e.Checks("lmp_fibre as a drop-in lmp")

# The official pour deck, shortened to 2 x 1000 steps with thermo every 200.
deck = open("/usr/share/lammps/examples/pour/in.pour").read()
deck = re.sub(r"thermo\s+1000", "thermo 200", deck)
deck = re.sub(r"run\s+25000", "run 1000", deck)
assert deck.count("run 1000") == 2, "pour deck layout changed"

fibre = e2e.run_lmp(args, deck, "pour")
ck.ran(fibre, "pour runs with lmp_fibre")
lmp = shutil.which("lmp") or "/usr/bin/lmp"
native = subprocess.run([lmp, "-in", os.path.join(args.workdir, "in.pour"), "-log", "none"],
                        cwd=args.workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                        text=True, timeout=600)
ck.check(native.returncode == 0, "pour runs with lmp", "rc %d" % native.returncode)
reference = e2e.parse_thermo(native.stdout)
ck.check(len(fibre.thermo) == 2 and fibre.thermo == reference, "same thermo tables",
         "%d blocks, last rows %s vs %s" % (len(fibre.thermo),
                                            fibre.thermo[-1][-1] if fibre.thermo else None,
                                            reference[-1][-1] if reference else None))
ck.check("fibre_contact add-on" in fibre.output, "banner names the add-on")

# Unknown style, and a bad fibre_contact argument: a LAMMPS error and a non-zero exit.
box = "units lj\natom_style sphere\nregion b block 0 1 0 1 0 1\ncreate_box 1 b\n"
bad = e2e.run_lmp(args, box + "fix 1 all no_such_fix\n", "unknown_fix")
ck.check(bad.rc != 0 and "no_such_fix" in bad.error_line(), "unknown fix: error, non-zero exit",
         "rc %d, %s" % (bad.rc, bad.error_line()))
bad = e2e.run_lmp(args, box + "pair_style granular\n"
                  "pair_coeff * * hertz/material 1e5 0.2 0.3 tangential linear_nohistory 1.0 0\n"
                  "fix 1 all fibre_contact tol -1\n", "bad_tol")
ck.check(bad.rc != 0 and "tol" in bad.error_line(), "bad fibre_contact argument names 'tol'",
         "rc %d, %s" % (bad.rc, bad.error_line()))

# mpirun -np 2 on the stock deck: the same atoms are inserted.
mpi = e2e.run_lmp(args, deck, "pour_np2", np=2)
if ck.ran(mpi, "pour runs under mpirun -np 2") and len(fibre.thermo) == 2:
    ck.check([r["Atoms"] for r in mpi.thermo[0]] == [r["Atoms"] for r in fibre.thermo[0]],
             "mpirun -np 2 inserts the same atoms")

# A deck with fix fibre_contact, serial and mpirun -np 2: 80 spheres dropped onto a floor.
FIBRE_DECK = """
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
    run = e2e.run_lmp(args, FIBRE_DECK, "fibre_np%d" % np, np=np)
    if ck.ran(run, "fix fibre_contact runs with %d rank(s)" % np) and run.thermo:
        last = run.thermo[-1][-1]
        ck.check(last["Atoms"] == 80 and all(abs(v) < 1e30 for v in last.values()) and
                 last["f_fc[3]"] > 0, "np %d: all 80 atoms kept, finite, contacts found" % np,
                 str(last))
ck.close()
