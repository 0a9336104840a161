"""Helpers for the end-to-end tests of fix fibre_contact (tests/e2e/test_fix_*.py).

Every test is a script run by ctest as

    python3 test_x.py --lmp PATH_TO_lmp_fibre --mpirun PATH --workdir DIR --source REPO_ROOT

It writes its input decks into the work directory, runs lmp_fibre on them, parses the log,
thermo and dump output (tools/lammps_runs.py, shared with examples/compare/compare.py) and
checks numbers. `Checks` collects the results, prints one line per check and a closing
"N passed, M failed" line, and gives the exit status.

Python 3 standard library only.
"""

import argparse
import math
import os
import subprocess
import sys
import time

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools"))
# the tests call e2e.parse_thermo, e2e.parse_dump, e2e.dump_by_id, e2e.last_line_words and
# e2e.copy_scene: one code with examples/compare/compare.py
from lammps_runs import (copy_scene, dump_by_id, last_line_words, lmp_env,  # noqa: E402,F401
                         mpi_prefix, parse_dump, parse_thermo, read_text)


def parse_args():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--lmp", required=True, help="the lmp_fibre executable")
    p.add_argument("--mpirun", default="mpirun", help="the mpirun executable")
    p.add_argument("--workdir", required=True, help="directory for decks and output")
    p.add_argument("--source", required=True, help="the repository root")
    args = p.parse_args()
    for name in ("lmp", "workdir", "source"):
        setattr(args, name, os.path.abspath(getattr(args, name)))
    os.makedirs(args.workdir, exist_ok=True)
    return args


class Run:
    """One finished lmp_fibre run: exit status, output and parsed thermo blocks."""

    def __init__(self, name, rc, output, log_text, seconds):
        self.name = name
        self.rc = rc
        self.output = output
        self.log = log_text
        self.seconds = seconds
        self.thermo = parse_thermo(log_text if log_text else output)

    def last(self, column, block=-1):
        """Value of a thermo column on the last line of a run block."""
        return self.thermo[block][-1][column]

    def column(self, column, block=None):
        """All values of a thermo column (all blocks, or one)."""
        blocks = self.thermo if block is None else [self.thermo[block]]
        return [row[column] for b in blocks for row in b]

    def error_line(self):
        for line in self.output.splitlines():
            if "ERROR" in line:
                return line.strip()
        return ""


def sphere_box(box, types=1, boundary="f f f", processors=None):
    """The deck lines up to create_box for spheres: atom_style sphere with an atom map, newton
    off, ghost velocities, a block box (the six bounds as a string) with `types` atom types,
    and optionally a processor grid ("2 1 1")."""
    lines = ["atom_style sphere", "atom_modify map array", "boundary " + boundary,
             "newton off", "comm_modify vel yes"]
    if processors:
        lines.append("processors " + processors)
    return lines + ["region box block %s units box" % box, "create_box %d box" % types]


def cubic_bed(width, height):
    """The deck lines of a simple cubic bed of unit spacing filling 0..width x 0..width x
    0..height (region `bed`), the centres at half-integers: spheres of d = 1 touch each other
    and the walls at 0 and width."""
    return "\n".join(["lattice sc 1.0", "region bed block 0 %g 0 %g 0 %g units box"
                      % (width, width, height), "create_atoms 1 region bed",
                      "displace_atoms all move 0.5 0.5 0.5 units box"])


def bed_under_gravity(box, width, height, law, density, timestep, processors, created=None):
    """The opening of a deck whose unit spheres (a `cubic_bed` width x width x height in a box of
    `sphere_box`, and optionally the `created` lines after it) have `density` and the
    `pair_style granular` law `law`, with a bin neighbour list rebuilt at every step, the step
    `timestep` and gravity along -z. The numbers are strings: a template's fields stay as
    they are."""
    lines = ["units si"] + sphere_box(box, processors=processors) + [cubic_bed(width, height)]
    lines += [created] if created else []
    return "\n".join(lines + [
        "set type 1 diameter 1.0", "set type 1 density " + density, "pair_style granular",
        "pair_coeff * * " + law, "neighbor 0.3 bin", "neigh_modify every 1 delay 0",
        "timestep " + timestep, "fix g all gravity 9.81 vector 0 0 -1"])


def stacked_column(diameters):
    """Spheres of these diameters stacked on z = 0 along the z axis, each touching the next:
    their centres' heights and the create_atoms and set lines (density 1) that make them."""
    centres, lines, z = [], [], 0.0
    for i, d in enumerate(diameters):
        centres.append(z + d / 2)
        lines.append("create_atoms 1 single 0 0 %.17g units box" % centres[-1])
        lines.append("set atom %d diameter %.17g density 1.0" % (i + 1, d))
        z += d
    return centres, lines


def run_lmp(args, deck, name, np=1, variables=None, timeout=600):
    """Writes `deck` to WORKDIR/in.NAME and runs it with np processes (mpirun if np > 1)."""
    deck_path = os.path.join(args.workdir, "in." + name)
    log_path = os.path.join(args.workdir, "log." + name)
    with open(deck_path, "w") as f:
        f.write(deck)
    cmd = mpi_prefix(args.mpirun, np)
    cmd += [args.lmp, "-in", deck_path, "-log", log_path, "-echo", "none"]
    for key, value in (variables or {}).items():
        cmd += ["-var", key, str(value)]
    env = lmp_env()
    if os.path.exists(log_path):
        os.remove(log_path)
    t0 = time.time()
    try:
        proc = subprocess.run(cmd, cwd=args.workdir, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, timeout=timeout, env=env)
        rc, out = proc.returncode, proc.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired as e:
        rc, out = -9, (e.stdout or b"").decode("utf-8", "replace") + "\nTIMEOUT"
    seconds = time.time() - t0
    log_text = read_text(log_path) if os.path.exists(log_path) else ""
    # errors of other ranks than 0 reach only the screen: keep both for messages
    return Run(name, rc, out + "\n" + log_text, log_text, seconds)


class Checks:
    def __init__(self, title):
        self.title = title
        self.passed = 0
        self.failed = 0
        print("== " + title, flush=True)

    def check(self, ok, what, detail=""):
        status = "PASS" if ok else "FAIL"
        line = "%s: %s" % (status, what)
        if detail:
            line += " (" + detail + ")"
        print(line, flush=True)
        if ok:
            self.passed += 1
        else:
            self.failed += 1
        return ok

    def agree(self, a, b, tol, what, fmt="%.6g"):
        """a and b agree within the relative tolerance tol (rel_err)."""
        return self.check(rel_err(a, b) < tol, what, (fmt + " vs " + fmt) % (a, b))

    def ran(self, run, what=None):
        """The run finished with status 0."""
        detail = "rc %d, %.1f s" % (run.rc, run.seconds)
        if run.rc != 0:
            err = run.error_line()
            detail += ", " + (err if err else run.output.strip()[-400:])
        return self.check(run.rc == 0, what or ("run " + run.name + " completes"), detail)

    def close(self):
        print("%d passed, %d failed" % (self.passed, self.failed), flush=True)
        sys.exit(1 if self.failed else 0)


def rel_err(a, b):
    scale = max(abs(a), abs(b))
    return abs(a - b) / scale if scale > 0 else 0.0


def finite(values):
    return all(math.isfinite(v) for v in values)


def deepest_overlap(frames, floor_z=None):
    """The deepest sphere-sphere overlap r_i + r_j - |x_i - x_j| over dump frames with x, y,
    z and radius columns, and with floor_z the deepest r - (z - floor_z): how the tests bound
    the fix's overlaps by the native twin's."""
    worst = 0.0
    for frame in frames:
        atoms = list(dump_by_id(frame).values())
        xs = [(a["x"], a["y"], a["z"], a["radius"]) for a in atoms]
        for i, (xi, yi, zi, ri) in enumerate(xs):
            if floor_z is not None:
                worst = max(worst, ri - (zi - floor_z))
            for xj, yj, zj, rj in xs[i + 1:]:
                reach = ri + rj
                dx, dy, dz = xi - xj, yi - yj, zi - zj
                if abs(dx) < reach and abs(dy) < reach and abs(dz) < reach:
                    worst = max(worst, reach - math.sqrt(dx * dx + dy * dy + dz * dz))
    return worst
