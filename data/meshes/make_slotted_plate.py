#!/usr/bin/env python3
"""Writes slotted_plate.obj: a closed, consistently oriented quad mesh (see README.md).

The plate is the extrusion along y of a rectangle in the (x, z) plane with three rectangular
holes. Its vertices lie on the tensor grid xs x ys x zs, so neighbouring faces share vertices
and the surface is watertight; the script checks that every edge is used once in each direction
and that the enclosed volume is the expected one.
"""
import itertools
import pathlib

SLIT_WIDTH = 0.02
SLIT_CENTRES = (0.275, 0.525, 0.775)  # cell centres of a 0.05 m grid: no node of it lies in a slit
xs = [0.0] + [c + s * SLIT_WIDTH / 2 for c in SLIT_CENTRES for s in (-1, 1)] + [1.0]
ys = [0.40, 0.46]
zs = [0.0, 0.1, 0.5, 0.6]
SLIT_COLUMNS = {1, 3, 5}  # x intervals that are slits for z in [zs[1], zs[2]]


def solid(i, j):
    inside = 0 <= i < len(xs) - 1 and 0 <= j < len(zs) - 1
    return inside and not (i in SLIT_COLUMNS and j == 1)


vertices, index = [], {}


def vertex(i, k, j):
    key = (i, k, j)
    if key not in index:
        index[key] = len(vertices) + 1
        vertices.append((xs[i], ys[k], zs[j]))
    return index[key]


def quad(corners, outward):
    """A face through four (i, k, j) grid corners, ordered so its normal points along outward."""
    p = [vertices[vertex(*c) - 1] for c in corners]
    a = [p[1][d] - p[0][d] for d in range(3)]
    b = [p[2][d] - p[0][d] for d in range(3)]
    n = (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
    face = [vertex(*c) for c in corners]
    return face if sum(n[d] * outward[d] for d in range(3)) > 0 else face[::-1]


faces = []
for i, j in itertools.product(range(len(xs) - 1), range(len(zs) - 1)):
    if not solid(i, j):
        continue
    for k, sign in ((1, 1), (0, -1)):  # top and bottom
        faces.append(quad([(i, k, j), (i + 1, k, j), (i + 1, k, j + 1), (i, k, j + 1)], (0, sign, 0)))
    if not solid(i - 1, j):
        faces.append(quad([(i, 0, j), (i, 1, j), (i, 1, j + 1), (i, 0, j + 1)], (-1, 0, 0)))
    if not solid(i + 1, j):
        faces.append(quad([(i + 1, 0, j), (i + 1, 1, j), (i + 1, 1, j + 1), (i + 1, 0, j + 1)], (1, 0, 0)))
    if not solid(i, j - 1):
        faces.append(quad([(i, 0, j), (i + 1, 0, j), (i + 1, 1, j), (i, 1, j)], (0, 0, -1)))
    if not solid(i, j + 1):
        faces.append(quad([(i, 0, j + 1), (i + 1, 0, j + 1), (i + 1, 1, j + 1), (i, 1, j + 1)], (0, 0, 1)))

directed = [(f[m], f[(m + 1) % 4]) for f in faces for m in range(4)]
assert len(set(directed)) == len(directed), "an edge is used twice in one direction"
assert all((b, a) in set(directed) for a, b in directed), "an edge has no opposite: the mesh is open"


def signed_volume(face):
    # Divergence theorem over the fan triangles of a planar face.
    p = [vertices[v - 1] for v in face]
    total = 0.0
    for m in range(1, len(p) - 1):
        a, b, c = p[0], p[m], p[m + 1]
        total += (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                  + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
    return total


volume = sum(signed_volume(f) for f in faces)
expected = 1.0 * 0.06 * 0.6 - len(SLIT_CENTRES) * SLIT_WIDTH * 0.06 * (zs[2] - zs[1])
assert abs(volume - expected) < 1e-12, (volume, expected)

out = pathlib.Path(__file__).with_name("slotted_plate.obj")
with out.open("w") as f:
    f.write("# slotted plate 1.0 x 0.06 x 0.6 m with 3 slits 0.02 m wide; written by make_slotted_plate.py\n")
    for x, y, z in vertices:
        f.write(f"v {x:.6g} {y:.6g} {z:.6g}\n")
    for face in faces:
        f.write("f " + " ".join(map(str, face)) + "\n")
print(f"{out.name}: {len(vertices)} vertices, {len(faces)} quads, volume {volume:.6g} m^3")
