#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Checks a DXF file the way a strict CAD reader would, with ezdxf.

Usage: check_dxf.py FILE

Loads FILE with ezdxf.readfile, runs the auditor and fails (exit status 1, the
reasons on stderr) if the auditor finds errors or had to fix anything, or if an
entity or layer refers to a layer or linetype missing from the tables. On
success prints one line of JSON on stdout, flat so a test can read it without a
JSON library:

  {"version": "AC1009", "total": 7, "POINT": 3, "POINT@Points": 3, ...}

"TYPE" counts the model space entities of that type, "TYPE@LAYER" those on a
layer. Exit status 2: the file could not be read, or ezdxf is missing.
"""

import json
import os
import sys

try:
    import ezdxf
except ImportError:
    # Debian's python3-ezdxf is installed for the system interpreter; a python3
    # from pyenv or a virtual environment earlier in PATH does not see it.
    system_python = "/usr/bin/python3"
    if (os.path.exists(system_python)
            and os.path.realpath(sys.executable) != os.path.realpath(system_python)
            and not os.environ.get("CHECK_DXF_REEXECUTED")):
        os.environ["CHECK_DXF_REEXECUTED"] = "1"
        os.execv(system_python, [system_python] + sys.argv)
    print("check_dxf: the Python module ezdxf is missing (Debian: apt-get install python3-ezdxf)",
          file=sys.stderr)
    sys.exit(2)


def main(argv):
    if len(argv) != 2:
        print("usage: check_dxf.py FILE", file=sys.stderr)
        return 2
    path = argv[1]
    try:
        doc = ezdxf.readfile(path)
    except IOError as error:
        print(f"check_dxf: {path}: cannot read: {error}", file=sys.stderr)
        return 2
    except ezdxf.DXFStructureError as error:
        print(f"check_dxf: {path}: invalid DXF structure: {error}", file=sys.stderr)
        return 1

    problems = []
    # ezdxf accepts a file cut just before its end marker; a DXF must end with EOF.
    with open(path, "rb") as raw:
        lines = raw.read().split(b"\n")
    while lines and not lines[-1].strip():
        lines.pop()
    if not lines or lines[-1].strip() != b"EOF":
        problems.append("the file does not end with the EOF marker")
    auditor = doc.audit()
    problems += [f"audit error: {entry.message}" for entry in auditor.errors]
    problems += [f"audit had to fix: {entry.message}" for entry in auditor.fixes]
    # ezdxf tolerates references to undeclared table entries, as AutoCAD does;
    # stricter importers do not, so check them here.
    for layer in doc.layers:
        if layer.dxf.linetype not in doc.linetypes:
            problems.append(f"layer '{layer.dxf.name}' uses undeclared linetype '{layer.dxf.linetype}'")
    for entity in doc.modelspace():
        if entity.dxf.layer not in doc.layers:
            problems.append(f"{entity.dxftype()} on undeclared layer '{entity.dxf.layer}'")
    if problems:
        for problem in problems:
            print(f"check_dxf: {path}: {problem}", file=sys.stderr)
        return 1

    counts = {"version": doc.dxfversion, "total": 0}
    for entity in doc.modelspace():
        kind = entity.dxftype()
        layer = entity.dxf.layer
        counts["total"] += 1
        counts[kind] = counts.get(kind, 0) + 1
        counts[f"{kind}@{layer}"] = counts.get(f"{kind}@{layer}", 0) + 1
    print(json.dumps(counts, sort_keys=True))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
