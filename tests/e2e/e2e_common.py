"""Shared helpers for the end-to-end tests: run lmp_fibre (or lmp) on a deck and read thermo."""
import argparse
import os
import subprocess
import sys


def parse_args():
    ap = argparse.ArgumentParser()
    ap.add_argument("--lmp", required=True, help="path to lmp_fibre")
    ap.add_argument("--mpirun", default="mpirun")
    ap.add_argument("--workdir", required=True)
    ap.add_argument("--source", required=True, help="repository root")
    args = ap.parse_args()
    os.makedirs(args.workdir, exist_ok=True)
    return args


MPI_FLAGS = ["--allow-run-as-root", "--oversubscribe"]


def run(cmd, workdir, deck_text=None, deck_name="in.deck", timeout=600):
    """Runs cmd (a list) in workdir, writing deck_text to deck_name first if given.
    Returns (exit code, combined stdout+stderr)."""
    if deck_text is not None:
        with open(os.path.join(workdir, deck_name), "w") as f:
            f.write(deck_text)
    p = subprocess.run(cmd, cwd=workdir, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                       text=True, timeout=timeout)
    return p.returncode, p.stdout


def lmp_cmd(args, deck_name="in.deck", np=1, extra=()):
    base = [args.lmp, "-in", deck_name, "-log", "log." + deck_name, *extra]
    if np > 1:
        return [args.mpirun, *MPI_FLAGS, "-np", str(np), *base]
    return base


def thermo_blocks(text):
    """Thermo tables of a LAMMPS log: a list of (header list, rows of floats)."""
    blocks, header, rows = [], None, []
    for line in text.splitlines():
        words = line.split()
        if words and words[0] == "Step":
            header, rows = words, []
            continue
        if header is not None:
            if line.startswith("Loop time"):
                blocks.append((header, rows))
                header = None
                continue
            try:
                vals = [float(w) for w in words]
            except ValueError:
                continue
            if len(vals) == len(header):
                rows.append(vals)
    return blocks


class Checks:
    """Counts named checks and prints the closing 'N passed, N failed' line."""

    def __init__(self):
        self.passed = 0
        self.failed = 0

    def check(self, name, ok, detail=""):
        status = "PASS" if ok else "FAIL"
        print(f"{status} {name} {detail}".rstrip())
        if ok:
            self.passed += 1
        else:
            self.failed += 1

    def finish(self):
        print(f"{self.passed} passed, {self.failed} failed")
        sys.exit(1 if self.failed or not self.passed else 0)
