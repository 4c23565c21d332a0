#!/usr/bin/env python3
"""Checks the layering of the libraries by their #include lines.

  layering.py ROOT

Every source and header under ROOT/libmpm, ROOT/libfluid, ROOT/libcoupling and ROOT/apps
belongs to a target, and may include only the headers of the targets it links:

  mpm::core           mpm/{core,adaptive,domains,io,geometry,math}
  mpm::solid          + mpm/{solid,constitutive,plasticity}
  mpm::cuda           mpm::solid + mpm/cuda/    (the solid step on a GPU; only apps include it)
  fluid::fluid        mpm::core + fluid/        (never solid code, never coupling)
  coupling::coupling  everything above + coupling/
  apps                everything

A header under a `detail/` folder is internal to the library that holds it: no other library
and no app includes it. Prints one line per violation (file:line, the include, the rule) and
exits 1 when there is any.
"""
import pathlib
import re
import sys

CORE = ("mpm/core/", "mpm/adaptive/", "mpm/domains/", "mpm/io/", "mpm/geometry/", "mpm/math/")
SOLID = CORE + ("mpm/solid/", "mpm/constitutive/", "mpm/plasticity/")
CUDA = SOLID + ("mpm/cuda/",)
FLUID = CORE + ("fluid/",)
COUPLING = SOLID + ("fluid/", "coupling/")
APPS = COUPLING + ("mpm/cuda/",)
PROJECT = ("mpm/", "fluid/", "coupling/")

# (path prefix relative to ROOT, target name, allowed project include prefixes)
TARGETS = [
    ("libmpm/include/mpm/solid/", "mpm::solid", SOLID),
    ("libmpm/include/mpm/constitutive/", "mpm::solid", SOLID),
    ("libmpm/include/mpm/plasticity/", "mpm::solid", SOLID),
    ("libmpm/src/solid/", "mpm::solid", SOLID),
    ("libmpm/include/mpm/cuda/", "mpm::cuda", CUDA),
    ("libmpm/src/cuda/", "mpm::cuda", CUDA),
    ("libmpm/", "mpm::core", CORE),
    ("libfluid/", "fluid::fluid", FLUID),
    ("libcoupling/", "coupling::coupling", COUPLING),
    ("apps/", "apps", APPS),
]
# The library that owns a header, by its include prefix.
OWNER = [("mpm/", "libmpm/"), ("fluid/", "libfluid/"), ("coupling/", "libcoupling/")]

INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([^>"]+)[>"]')


def check(root):
    problems = []
    for path in sorted(root.rglob("*")):
        if path.suffix not in (".h", ".cpp") or not path.is_file():
            continue
        rel = path.relative_to(root).as_posix()
        target = next(((name, allowed) for prefix, name, allowed in TARGETS if rel.startswith(prefix)), None)
        if target is None:
            continue
        name, allowed = target
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            m = INCLUDE.match(line)
            if not m or not m.group(1).startswith(PROJECT):
                continue
            header = m.group(1)
            if not header.startswith(allowed):
                problems.append(f"{rel}:{number}: #include <{header}>: {name} does not link the target of that header")
            owner = next(lib for prefix, lib in OWNER if header.startswith(prefix))
            if "/detail/" in header and not rel.startswith(owner):
                problems.append(f"{rel}:{number}: #include <{header}>: a detail/ header is internal to {owner}")
    return problems


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    problems = check(pathlib.Path(sys.argv[1]))
    for p in problems:
        print(p)
    print(f"layering: {len(problems)} violation(s)")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
