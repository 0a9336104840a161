"""LAMMPS runs from Python: the launch command and environment, the example scenes' files,
and the reading of the output (thermo blocks of a log, frames of a text dump, log lines).

One piece of code for tests/e2e/fibre_e2e.py (the end-to-end tests) and
examples/compare/compare.py (fix fibre_contact against its native twin); both put this
folder on sys.path. Python 3 standard library only: compare.py turns the plain lists into
numpy arrays itself.
"""

import os
import re
import shutil

# The files of an example scene (examples/SCENE/): the fibre_contact deck, its native twin,
# and what both include.
SCENE_FILES = {
    "silo": ["in.silo", "in.silo.native", "scene.silo", "run.silo"],
    "material": ["in.material", "in.material.native", "scene.material", "run.material"],
    "drum": ["in.drum", "in.drum.native", "scene.drum", "run.drum"],
    "shear": ["in.shear", "in.shear.native", "scene.shear", "run.shear"],
    "mixer": ["in.mixer", "in.mixer.native", "scene.mixer", "run.mixer"],
    "janssen": ["in.janssen", "in.janssen.native", "scene.janssen", "run.janssen", "janssen.py"],
}


def copy_scene(repo, scene, dest):
    """Copies the files of examples/SCENE (SCENE_FILES) from the repository root into dest."""
    for name in SCENE_FILES[scene]:
        shutil.copy(os.path.join(repo, "examples", scene, name), dest)


# ----------------------------------------------------------------------------- running

def mpi_prefix(mpirun, np):
    """The launcher words in front of the executable: none for one process, else mpirun
    (as root, and with more ranks than cores)."""
    if np > 1:
        return [mpirun, "--allow-run-as-root", "--oversubscribe", "-np", str(np)]
    return []


def lmp_env(base=None):
    """The environment of a run: base (default os.environ) with, where not set already,
    Open MPI allowed to run as root and to oversubscribe, ranks that yield when idle (more
    ranks than cores), and one OpenMP thread."""
    env = dict(os.environ if base is None else base)
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT", "1")
    env.setdefault("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1")
    env.setdefault("OMPI_MCA_rmaps_base_oversubscribe", "1")
    env.setdefault("OMP_NUM_THREADS", "1")
    env.setdefault("OMPI_MCA_mpi_yield_when_idle", "1")
    return env


# GNU time in front of the executable (after mpi_prefix: one line a process), and the largest
# resident set of any process in the run's output, in KiB
MAX_RSS_PREFIX = ["/usr/bin/time", "-f", "MAXRSS %M"]


def max_rss_kib(output):
    """The largest MAXRSS that MAX_RSS_PREFIX printed in output (KiB)."""
    return max(int(k) for k in re.findall(r"MAXRSS (\d+)", output))


# ----------------------------------------------------------------------------- reading

def read_text(path):
    """A log file's text (undecodable bytes replaced)."""
    with open(path, errors="replace") as f:
        return f.read()


def thermo_blocks(text):
    """Thermo blocks of a LAMMPS log's text: a list (one per run command) of (header, rows),
    header the column names of the 'Step ...' line, rows lists of floats. A block ends at
    'Loop time' or at an ERROR line (then it may have no rows); the last one may be cut off
    (a run that died). Lines of another length or with non-numbers (warnings) are skipped."""
    blocks, header, rows = [], None, None
    for line in text.splitlines():
        words = line.split()
        if words and words[0] == "Step":
            header, rows = words, []
            continue
        if header is None:
            continue
        if line.startswith("Loop time") or line.startswith("ERROR"):
            blocks.append((header, rows))
            header = None
            continue
        if len(words) != len(header):
            continue
        try:
            rows.append([float(w) for w in words])
        except ValueError:
            continue
    if header is not None and rows:
        blocks.append((header, rows))
    return blocks


def parse_thermo(text):
    """Thermo blocks of a LAMMPS log's text: a list (one per run) of lists of {column: value}."""
    return [[dict(zip(header, r)) for r in rows] for header, rows in thermo_blocks(text)]


def least_squares_slope(xs, ys):
    """The slope of the least-squares line through the points (xs, ys)."""
    xm, ym = sum(xs) / len(xs), sum(ys) / len(ys)
    return sum((x - xm) * (y - ym) for x, y in zip(xs, ys)) / sum((x - xm) ** 2 for x in xs)


def last_line_words(text, prefix):
    """Words of the last line of text that starts with prefix (None if there is none)."""
    found = None
    for line in text.splitlines():
        if line.startswith(prefix):
            found = line.split()
    return found


def parse_dump(path):
    """A LAMMPS text dump (atom or local): list of (timestep, columns, rows), rows lists of
    floats in the order of columns."""
    frames = []
    with open(path) as f:
        lines = f.read().splitlines()
    i, step, count = 0, 0, 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("ITEM: TIMESTEP"):
            step = int(lines[i + 1])
            i += 2
        elif line.startswith("ITEM: NUMBER OF"):
            count = int(lines[i + 1])
            i += 2
        elif line.startswith("ITEM: ATOMS") or line.startswith("ITEM: ENTRIES"):
            columns = line.split()[2:]
            rows = [[float(w) for w in lines[i + 1 + k].split()] for k in range(count)]
            frames.append((step, columns, rows))
            i += 1 + count
        else:
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
