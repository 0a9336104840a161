#!/usr/bin/env python3
"""Runs the same LAMMPS decks with two lmp_fibre binaries and compares their trajectories.

For a refactoring that must not change behaviour: every deck that uses fix fibre_contact gets
a full-precision dump (id, x, v, omega every N steps, sorted by id) before its first run;
both binaries run it in their own copy of the deck's folder, and the dumps are compared
value by value. Prints one line per deck (bitwise identical, or the largest relative
difference) and exits 1 when any deck differs by more than --tol. --chain runs the decks in
order in one folder per binary (a restart written by one deck, read by the next).

    python3 tools/compare_trajectories.py --old OLD/lmp_fibre --new NEW/lmp_fibre \
        --np 1 [--var tag x] [--chain] DECK [DECK ...]
"""

import argparse
import os
import re
import shutil
import subprocess
import sys

DUMP = ("dump trajcmp all custom {every} traj.dump id x y z vx vy vz omegax omegay omegaz\n"
        "dump_modify trajcmp sort id format float %.17g\n")
# LIGGGHTS's dump_modify takes the whole line's format
DUMP_LIGGGHTS = ("dump trajcmp all custom {every} traj.dump id x y z vx vy vz omegax omegay "
                 "omegaz\ndump_modify trajcmp sort id format \"%d" + " %.17g" * 9 + "\"\n")


def instrument(text, every, dump=DUMP):
    """The deck with the dump before its first run, or None without fix fibre_contact."""
    if not re.search(r"^\s*fix\s+\S+\s+\S+\s+fibre_contact\b", text, re.M):
        return None
    lines = text.splitlines(keepends=True)
    for i, line in enumerate(lines):
        if re.match(r"\s*run\s", line) and not (i > 0 and lines[i - 1].rstrip().endswith("&")):
            return "".join(lines[:i]) + dump.format(every=every) + "".join(lines[i:])
    return None


def run(lmp, deck_text, workdir, np, mpirun, variables):
    os.makedirs(workdir, exist_ok=True)
    with open(os.path.join(workdir, "in.deck"), "w") as f:
        f.write(deck_text)
    cmd = [mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(np)] if np > 1 else []
    cmd += [lmp, "-in", "in.deck", "-log", "log.deck", "-echo", "none"]
    for name, value in variables:
        cmd += ["-var", name, value]
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMP_NUM_THREADS="1")
    done = subprocess.run(cmd, cwd=workdir, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, timeout=1200)
    path = os.path.join(workdir, "traj.dump")
    return done.returncode, open(path).read() if os.path.exists(path) else ""


def numbers(dump):
    out = []
    for line in dump.splitlines():
        for word in line.split():
            try:
                out.append(float(word))
            except ValueError:
                pass
    return out


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--old", required=True)
    p.add_argument("--new", required=True)
    p.add_argument("--np", type=int, default=1)
    p.add_argument("--every", type=int, default=10)
    p.add_argument("--tol", type=float, default=0.0, help="largest relative difference allowed")
    p.add_argument("--mpirun", default="mpirun")
    p.add_argument("--workdir", default="/tmp/compare_trajectories")
    p.add_argument("--var", nargs=2, action="append", default=[], metavar=("NAME", "VALUE"))
    p.add_argument("--chain", action="store_true", help="run the decks in one folder, in order")
    p.add_argument("--liggghts", action="store_true", help="LIGGGHTS binaries (its dump_modify)")
    p.add_argument("decks", nargs="+")
    args = p.parse_args()
    worst = 0.0
    for deck in args.decks:
        text = instrument(open(deck).read(), args.every,
                          DUMP_LIGGGHTS if args.liggghts else DUMP)
        name = os.path.basename(os.path.dirname(deck)) + "/" + os.path.basename(deck)
        if text is None:
            print(f"{name}: no fix fibre_contact, skipped")
            continue
        base = os.path.join(args.workdir, "chain" if args.chain else name.replace("/", "_"))
        if not (args.chain and os.path.isdir(base)):
            shutil.rmtree(base, ignore_errors=True)
            # decks may read files next to them (scenes, restart files): copy the folder
            for side in ("old", "new"):
                shutil.copytree(os.path.dirname(os.path.abspath(deck)), os.path.join(base, side),
                                ignore=shutil.ignore_patterns("log.*", "*.dump", "dump.*",
                                                              "*.restart*" if args.chain else "-"))
        rc_old, old = run(args.old, text, os.path.join(base, "old"), args.np, args.mpirun,
                          args.var)
        rc_new, new = run(args.new, text, os.path.join(base, "new"), args.np, args.mpirun,
                          args.var)
        if rc_old != rc_new:
            print(f"{name}: exit status {rc_old} (old) != {rc_new} (new)")
            worst = float("inf")
            continue
        if old == new:
            print(f"{name}: bitwise identical ({len(old.splitlines())} dump lines, rc {rc_old})")
            continue
        a, b = numbers(old), numbers(new)
        if len(a) != len(b):
            print(f"{name}: dumps differ in length ({len(a)} vs {len(b)} numbers)")
            worst = float("inf")
            continue
        diff = max(abs(x - y) / max(abs(x), abs(y), 1e-300) for x, y in zip(a, b) if x != y)
        worst = max(worst, diff)
        print(f"{name}: differs, largest relative difference {diff:.3g}")
    sys.exit(0 if worst <= args.tol else 1)


if __name__ == "__main__":
    main()
