"""Helpers for the end-to-end tests of fix fibre_contact (tests/e2e/test_fix_*.py).

Every test is a script run by ctest as

    python3 test_x.py --lmp PATH_TO_lmp_fibre --mpirun PATH --workdir DIR --source REPO_ROOT

It writes its input decks into the work directory, runs lmp_fibre on them, parses the log,
thermo and dump output and checks numbers. `Checks` collects the results, prints one line per
check and a closing "N passed, M failed" line, and gives the exit status.

Python 3 standard library only.
"""

import argparse
import math
import os
import subprocess
import sys
import time


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


def run_lmp(args, deck, name, np=1, variables=None, timeout=600):
    """Writes `deck` to WORKDIR/in.NAME and runs it with np processes (mpirun if np > 1)."""
    deck_path = os.path.join(args.workdir, "in." + name)
    log_path = os.path.join(args.workdir, "log." + name)
    with open(deck_path, "w") as f:
        f.write(deck)
    cmd = []
    if np > 1:
        cmd = [args.mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(np)]
    cmd += [args.lmp, "-in", deck_path, "-log", log_path, "-echo", "none"]
    for key, value in (variables or {}).items():
        cmd += ["-var", key, str(value)]
    env = dict(os.environ)
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")  # more ranks than cores
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
    log_text = ""
    if os.path.exists(log_path):
        with open(log_path, errors="replace") as f:
            log_text = f.read()
    # errors of other ranks than 0 reach only the screen: keep both for messages
    return Run(name, rc, out + "\n" + log_text, log_text, seconds)


def parse_thermo(text):
    """Thermo blocks of a LAMMPS log: a list (one per run) of lists of {column: value}."""
    blocks, header, rows = [], None, None
    for line in text.splitlines():
        words = line.split()
        if words and words[0] == "Step":
            header, rows = words, []
            continue
        if header is None:
            continue
        if line.startswith("Loop time") or line.startswith("ERROR"):
            blocks.append(rows)
            header = None
            continue
        if len(words) != len(header):
            continue  # warnings between thermo lines
        try:
            values = [float(w) for w in words]
        except ValueError:
            continue
        rows.append(dict(zip(header, values)))
    if header is not None and rows:
        blocks.append(rows)
    return blocks


def parse_dump(path):
    """A LAMMPS text dump (atom or local): list of (timestep, columns, rows)."""
    frames = []
    with open(path) as f:
        lines = f.read().splitlines()
    i = 0
    while i < len(lines):
        if lines[i].startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            i += 2
            continue
        if lines[i].startswith("ITEM: NUMBER OF"):
            count = int(lines[i + 1])
            i += 2
            continue
        if lines[i].startswith("ITEM: ATOMS") or lines[i].startswith("ITEM: ENTRIES"):
            columns = lines[i].split()[2:]
            rows = [[float(w) for w in lines[i + 1 + k].split()] for k in range(count)]
            frames.append((step, columns, rows))
            i += 1 + count
            continue
        i += 1
    return frames


def dump_by_id(frame):
    """{atom id: {column: value}} of one dump frame with an 'id' column."""
    step, columns, rows = frame
    out = {}
    for r in rows:
        d = dict(zip(columns, r))
        out[int(d["id"])] = d
    return out


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
