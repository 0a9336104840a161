#!/usr/bin/env python3
"""Prints the include graph of the fibre library and its front ends, and checks the layering.

The library's layers are its folders (solver/include/fibre/LAYER/ and solver/src/LAYER/,
doc/design.md, "Layers"), in the order of FOLDERS, lowest first; folders of one rank may
include each other. A file may include only headers of its own or a lower rank; the front
ends (fix/, liggghts/) sit above them all. Exits 1 and names the offending line when an
include runs upward, names a header that does not exist, or when a library file lies outside
a known folder.

    python3 tools/include_graph.py [--quiet]
"""

import os
import re
import sys

# lowest first; a tuple holds folders of one rank
FOLDERS = ["core", ("model", "geometry"), "algebra", ("io", "precond"), "solvers", "step",
           "study", "frontend"]
RANK = {name: rank for rank, entry in enumerate(FOLDERS)
        for name in (entry if isinstance(entry, tuple) else (entry,))}
FRONT_END = len(FOLDERS)
INCLUDE = re.compile(r'^\s*#\s*include\s+"fibre/([a-z_]+)/([a-z_]+)\.hpp"')
FLAT = re.compile(r'^\s*#\s*include\s+"fibre/([a-z_]+)\.hpp"')


def library_files(root):
    """(path relative to root, folder) of every header and source of the library."""
    out = []
    for base in ("solver/include/fibre", "solver/src"):
        for folder in sorted(os.listdir(os.path.join(root, base))):
            path = os.path.join(root, base, folder)
            if not os.path.isdir(path):
                out.append((os.path.join(base, folder), None))
                continue
            for f in sorted(os.listdir(path)):
                if f.endswith((".hpp", ".cpp")):
                    out.append((os.path.join(base, folder, f), folder))
    return out


def front_end_files(root):
    out = []
    for base in ("fix", "liggghts"):
        for f in sorted(os.listdir(os.path.join(root, base))):
            if f.endswith((".hpp", ".cpp", ".h")):
                out.append((os.path.join(base, f), None))
    return out


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    quiet = "--quiet" in sys.argv
    headers = {os.path.relpath(p, "solver/include") for p, _ in library_files(root)
               if p.startswith("solver/include/")}
    errors = []
    files = [(p, f, False) for p, f in library_files(root)]
    files += [(p, f, True) for p, f in front_end_files(root)]
    for rel, folder, front in files:
        own = FRONT_END if front else RANK.get(folder)
        if own is None:
            errors.append(f"{rel}: not in a layer's folder ({', '.join(RANK)})")
            continue
        deps = []
        with open(os.path.join(root, rel)) as f:
            for number, line in enumerate(f, 1):
                if FLAT.match(line):
                    errors.append(f"{rel}:{number}: includes a header outside the layers' folders")
                    continue
                m = INCLUDE.match(line)
                if not m:
                    continue
                dep_folder, dep = m.groups()
                deps.append(f"{dep_folder}/{dep}")
                dep_rank = RANK.get(dep_folder)
                if f"fibre/{dep_folder}/{dep}.hpp" not in headers or dep_rank is None:
                    errors.append(f"{rel}:{number}: includes fibre/{dep_folder}/{dep}.hpp, "
                                  "which is no header of the library")
                elif dep_rank > own:
                    errors.append(f"{rel}:{number}: {folder or 'front end'} (rank {own}) "
                                  f"includes fibre/{dep_folder}/{dep}.hpp (rank {dep_rank})")
        if not quiet and (rel.endswith((".hpp", ".h")) or front):
            print(f"[{own}] {rel} -> {', '.join(deps) if deps else '-'}")
    for e in errors:
        print("include_graph: " + e)
    print(f"include_graph: {len(files)} files, {len(errors)} layering errors")
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    main()
