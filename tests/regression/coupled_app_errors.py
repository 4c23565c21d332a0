#!/usr/bin/env python3
"""Bad input to a coupled app (the scene loader of coupling/scene_loader.h), run end to end:
each case rewrites one value in a copy of the default submerged_collapse scene and must exit 2
with exactly one stderr line naming the scene file and the line of that key, the key path,
the value and the accepted range, and must leave no --out folder.

  coupled_app_errors.py --app EXE --scene data/scenes/submerged_collapse.yaml --work DIR
"""
import argparse
import re
import sys

from bad_input import run_cases

# (key path in the message, regex of the text to rewrite, its replacement (re.sub syntax),
#  substrings the message must hold besides file:line and the key path). The line is that of
#  the match plus the newlines of the replacement.
CASES = [
    ("drag.grain_diameter", r"(grain_diameter:)\s*[^\s#]+", r"\1 0", ["0", "> 0"]),
    ("drag.law", r"(\blaw:)\s*[^\s#]+", r"\1 magic", ["magic", "'stokes'", "'gidaspow'"]),
    ("sediment.packing_fraction", r"(packing_fraction:)\s*[^\s#]+", r"\1 1.2", ["1.2", "(0, 0.65]"]),
    ("sediment.plasticity.dilatancy", r"(dilatancy:)\s*[^\s#]+", r"\1 -1", ["-1", ">= 0"]),
    ("sediment.plasticity.critical_packing", r"(critical_packing:)\s*[^\s#]+", r"\1 1.5", ["1.5", "(0, 1)"]),
    ("sediment.min_fluid_fraction", r"(\nsediment:)", r"\1\n  min_fluid_fraction: 1", ["1", "(0, 1)"]),
    ("sediment.switching.dense_above", r"(dense_above:)\s*[^\s#}]+", r"\1 0.1", ["0.1", "(0.2, 1)"]),
    ("sediment.switching.rouse_number", r"(dense_above:\s*[^\s#}]+)", r"\1, rouse_number: 2",
     ["2", "only with a bed-load closure"]),
    ("fluid.density", r"(density:)\s*1010", r"\1 -1", ["-1", "> 0"]),
    ("bodies[0].phase", r"(phase:)\s*sediment", r"\1 mud", ["mud", "'fluid'", "'sediment'"]),
    ("periodic", r"(gravity:[^\n]*\nwalls:\n  contact: sticky[^\n]*(?:\n  thickness:[^\n]*)?)", r"\1\n  x_min: open\n  x_max: open\nperiodic: [true, false]",
     ["coupled scenes have no periodic axes"]),
    ("colliders[0].sediment.friction", r"\Z",
     r"\ncolliders:\n  - {type: box, lo: [0.5, 0.5], hi: [0.6, 0.6], contact: sticky, sediment: {contact: slip, friction: 0.4}}",
     ["0.4", "Coulomb friction applies to 'contact: separate' only"]),
    ("emitters[0].hi", r"\Z", r"\nemitters:\n  - {phase: fluid, lo: [0.1, 0.12], hi: [0.2, 0.2], velocity: [0, -1]}",
     ["0.2", "must lie inside the domain"]),
]


def substitute(pattern, value):
    """A rewrite for run_cases: the first match of `pattern` becomes `value` (re.sub syntax);
    the key's line is that of the match plus the newlines of the replacement."""
    def rewrite(text):
        match = re.search(pattern, text)
        if not match:
            raise KeyError(pattern)
        replaced = match.expand(value)
        line = text.count("\n", 0, match.start()) + 1 + replaced.count("\n")
        return text[:match.start()] + replaced + text[match.end():], line
    return rewrite


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--app", required=True)
    parser.add_argument("--scene", required=True)
    parser.add_argument("--work", required=True)
    args = parser.parse_args()
    cases = [(path, path, substitute(pattern, value), expected) for path, pattern, value, expected in CASES]
    return run_cases(args.app, args.scene, args.work, cases)


if __name__ == "__main__":
    sys.exit(main())
