#!/usr/bin/env python3
"""Prints the include graph of the fibre library and its front end, and checks the layering.

Every header of solver/include/fibre has a layer (doc/design.md section 6); a header, or the
source file of the same name, may include only headers of its own or a lower layer, and the
front end (fix/) sits above them all. Exits 1 and names the offending line when an include
runs upward, or when a header has no layer.

    python3 tools/include_graph.py [--quiet]
"""

import os
import re
import sys

LAYERS = {
    0: ["system", "exchange", "names", "text"],
    1: ["material", "contact_model", "kernels", "contact_rows", "detection", "mesh",
        "contact_history"],
    2: ["spook", "operators", "fibres", "cones", "assembly", "system_io", "stress"],
    3: ["solver_control", "preconditioner", "preconditioner_family", "krylov", "direct", "pgs", "sweep_groups",
        "fibre_blocks", "apgd", "spectra", "analysis", "combined_preconditioner",
        "nonsmooth_reference"],
    4: ["step_solver", "accuracy_study", "substeps"],
    5: ["settings"],
}
FRONT_END = 6
INCLUDE = re.compile(r'^\s*#\s*include\s+"fibre/([a-z_]+)\.hpp"')


def layer_of(name):
    for layer, names in LAYERS.items():
        if name in names:
            return layer
    return None


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    quiet = "--quiet" in sys.argv
    files = []
    for folder, front in (("solver/include/fibre", False), ("solver/src", False), ("fix", True)):
        path = os.path.join(root, folder)
        for f in sorted(os.listdir(path)):
            if f.endswith((".hpp", ".cpp", ".h")):
                files.append((os.path.join(folder, f), front))
    errors = []
    for rel, front in files:
        stem = os.path.splitext(os.path.basename(rel))[0]
        own = FRONT_END if front else layer_of(stem)
        if own is None:
            errors.append(f"{rel}: no layer for '{stem}' (add it to LAYERS and doc/design.md)")
            continue
        deps = []
        with open(os.path.join(root, rel)) as f:
            for number, line in enumerate(f, 1):
                m = INCLUDE.match(line)
                if not m:
                    continue
                dep = m.group(1)
                deps.append(dep)
                dep_layer = layer_of(dep)
                if dep_layer is None:
                    errors.append(f"{rel}:{number}: includes fibre/{dep}.hpp, which has no layer")
                elif dep_layer > own:
                    errors.append(f"{rel}:{number}: layer {own} includes fibre/{dep}.hpp of "
                                  f"layer {dep_layer}")
        if not quiet and rel.endswith((".hpp", ".h")) or (not quiet and front):
            print(f"[{own}] {rel} -> {', '.join(deps) if deps else '-'}")
    for e in errors:
        print("include_graph: " + e)
    print(f"include_graph: {len(files)} files, {len(errors)} layering errors")
    sys.exit(1 if errors else 0)


if __name__ == "__main__":
    main()
