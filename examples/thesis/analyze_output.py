"""Reading fibre_analyze's output: the history CSV (--csv), the spectrum files (--spectra)
and the method names. Shared by make_results.py and plot_convergence.py (same folder).

fibre_analyze names the preconditioned conjugate gradient method `cg`; files written before
that say `uzawa` (the thesis's name, still an alias of the tool's --methods). Every reader
here turns `uzawa` into `cg`, so old and new files read the same. Python 3 standard library.
"""
import csv

METHODS = ["cg", "cr", "minres"]
METHOD_ALIASES = {"uzawa": "cg"}
METHOD_STYLES = {"cg": "-", "cr": "--", "minres": "-."}  # dotted: the 100-iteration mark
PRECOND_COLOURS = {"none": "black", "jacobi": "tab:orange", "block": "tab:blue",
                   "fibre": "tab:green", "tree": "tab:red"}


def method_name(name):
    """The method's name as fibre_analyze writes it now (`uzawa` -> `cg`)."""
    return METHOD_ALIASES.get(name, name)


def read_history(path, columns=("iteration", "rr", "rb", "ve", "ve_rel")):
    """Runs {(form, method, precond): {column: [float]}} and sizes {form: N} ('# size' lines)
    of a history CSV of fibre_analyze --csv; method names normalised (method_name)."""
    runs, sizes, lines = {}, {}, []
    with open(path, newline="") as f:
        for line in f:
            if line.startswith("# size "):
                words = line.split()
                sizes[words[2]] = int(words[3])
            elif line.strip() and not line.startswith("#"):
                lines.append(line)
    reader = csv.DictReader(lines)
    wanted = ["form", "method", "precond"] + list(columns)
    if reader.fieldnames is None or any(c not in reader.fieldnames for c in wanted):
        raise ValueError(f"{path}: not a fibre_analyze history (columns {', '.join(wanted)})")
    for row in reader:
        key = (row["form"], method_name(row["method"]), row["precond"])
        run = runs.setdefault(key, {c: [] for c in columns})
        for c in columns:
            run[c].append(float(row[c]))
    return runs, sizes


def read_spectrum(path):
    """One spectrum file of fibre_analyze --spectra: {"eigenvalues": [float], "method": how
    they were computed, the '# kappa_e ...' pairs (kappa_e, lambda_r, ...), and "form" and
    "precond" from the '# fibre_analyze spectrum:' line}."""
    info, values = {"path": path}, []
    with open(path) as f:
        for line in f:
            if line.startswith("# fibre_analyze spectrum:"):
                # "# fibre_analyze spectrum: form contact, precond block (P^-1 A), n 6180"
                words = line.replace(",", " ").split()
                info["form"] = words[words.index("form") + 1]
                info["precond"] = words[words.index("precond") + 1]
            elif line.startswith("# method "):
                info["method"] = line[len("# method "):].strip()
            elif line.startswith("# kappa_e "):
                words = line[2:].split()
                for name, value in zip(words[0::2], words[1::2]):
                    info[name] = float(value)
            elif line.strip() and not line.startswith("#"):
                values.append(float(line))
    info["eigenvalues"] = values
    return info
