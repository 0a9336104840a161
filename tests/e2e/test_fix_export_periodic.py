"""An exported step of a serial periodic run replays exactly (issue #13).

Two layers of 3 x 3 touching spheres in a box periodic in x and y (each row touches the image
of its first sphere across the boundary) fall on a floor with random velocities, mu 0.5 and
rolling resistance; fix fibre_contact exports step 20. In a serial periodic run LAMMPS's ghost
images of owned atoms are extra bodies of the system; the export's PREFIX.images maps each to
its body. Checks, with tools/fibre_accuracy:
- the export has the images file, and the reference (sweeps and Newton) is confirmed;
- replaying the step with the defaults from the exported warm start gives the run's own
  impulses: the "(defaults)" row's errors against the reference equal those of "(the run's
  own impulses)" (printed to 3 digits);
- without the images file the replay is another problem (images relaxed as separate bodies):
  its errors differ from the run's.
"""

import os
import shutil
import subprocess

import fibre_e2e as e2e

DECK = "\n".join(e2e.sphere_box("0 3 0 3 0 6", boundary="p p f")) + """
lattice sc 1.0 origin 0.5 0.5 0.5
region pile block 0 3 0 3 0 2 units box
create_atoms 1 region pile
set type 1 diameter 1.0 density 1.0
pair_style gran/hooke 1.0 NULL 0.0 NULL 0.0 0
pair_coeff * *
velocity all create 0.3 4928 loop geom
neighbor 0.2 bin
timestep 0.005
fix g all gravity 9.81 vector 0 0 -1
fix fc all fibre_contact mu 0.5 mu_roll 0.05 wall zplane 0.0 NULL export 20 snap
thermo_style custom step ke f_fc[3] f_fc[13]
run 20
"""


def rows_of(output):
    """The printed error columns of the run's row and of the defaults' row."""
    found = {}
    for line in output.splitlines():
        for name in ("(the run's own impulses)", "(defaults)"):
            if line.startswith(name):
                found[name] = line.split()[-6:]
    return found


def main():
    args = e2e.parse_args()
    ck = e2e.Checks("export: a serial periodic step replays exactly")
    run = e2e.run_lmp(args, DECK, "periodic")
    if not ck.ran(run):
        ck.close()
        return
    prefix = os.path.join(args.workdir, "snap.20.0")
    ck.check(os.path.exists(prefix + ".images"), "the export maps the periodic images",
             "no %s.images" % prefix)
    tool = os.path.join(os.path.dirname(os.path.dirname(args.lmp)), "tools", "fibre_accuracy")

    def replay():
        proc = subprocess.run([tool, prefix, "--setting", "", "--repeat", "1"],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=600)
        return proc.returncode, proc.stdout

    rc, out = replay()
    ck.check(rc == 0 and "confirmed" in out, "with the images: the reference is confirmed",
             out[-400:])
    rows = rows_of(out)
    ck.check(len(rows) == 2 and rows["(defaults)"] == rows["(the run's own impulses)"],
             "with the images: replaying the defaults gives the run's impulses", str(rows))
    if os.path.exists(prefix + ".images"):
        shutil.move(prefix + ".images", prefix + ".images.off")
        rc, out = replay()
        rows = rows_of(out)
        ck.check(len(rows) == 2 and rows["(defaults)"] != rows["(the run's own impulses)"],
                 "without the images the replay is another problem", str(rows))
    ck.close()


if __name__ == "__main__":
    main()
