#!/usr/bin/env python3
"""Bad input to a fluid app, run end to end: each case changes the value of one key in a copy
of the default dam_break scene and must exit 2 with exactly one stderr line naming the scene
file and the line of that key, the key path, the value and the accepted range, and must leave
no --out folder.

  fluid_app_errors.py --dam-break EXE --scene data/scenes/dam_break.yaml --work DIR
"""
import argparse
import re
import sys

from bad_input import run_cases

# (key path, new value, substrings the message must hold besides file:line and the key path)
CASES = [
    ("fluid.viscosity", "-1", ["-1", ">= 0"]),
    ("fluid.density", "0", ["> 0"]),
    ("time.cfl", "1.5", ["1.5", "(0, 1]"]),
    ("pressure.solver", "magic", ["magic", "'cg'"]),
    ("pressure.on_failure", "ignore", ["ignore", "'stop'", "'warn'"]),
    ("pressure.setup_reuse", "0", ["0", "[1, 1000]"]),
]


def with_value(text, path, value):
    """The scene text with the value of `section.key` replaced (or the key added first in its
    section where the scene leaves it out), and the 1-based line of it."""
    section, key = path.split(".")
    lines = text.splitlines()
    in_section = False
    header = None
    for i, line in enumerate(lines):
        if re.match(r"^\w", line):
            in_section = line.startswith(section + ":")
            if in_section:
                header = i
        elif in_section and re.match(rf"^\s+{key}:", line):
            lines[i] = re.sub(rf"^(\s+{key}:)\s*[^#]*", rf"\g<1> {value}  ", line)
            return "\n".join(lines) + "\n", i + 1
    if header is None:
        raise KeyError(path)
    lines.insert(header + 1, f"  {key}: {value}")
    return "\n".join(lines) + "\n", header + 2


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--dam-break", required=True)
    parser.add_argument("--scene", required=True)
    parser.add_argument("--work", required=True)
    args = parser.parse_args()
    cases = [(f"{path} = {value}", path, lambda text, p=path, v=value: with_value(text, p, v), expected)
             for path, value, expected in CASES]
    return run_cases(args.dam_break, args.scene, args.work, cases)


if __name__ == "__main__":
    sys.exit(main())
