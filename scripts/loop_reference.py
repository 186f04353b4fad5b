#!/usr/bin/env python3
"""Reference data for wavemill's Loop subdivision agreement test.

Writes closed input meshes and trimesh's Loop subdivision of them (2 iterations) as OBJ
files into tests/data/loop_reference/ (relative to the crate root):

    <name>_input.obj    the input mesh (v/f lines only, 1-based faces)
    <name>_loop2.obj    trimesh.remesh.subdivide_loop(vertices, faces, iterations=2)

Run from the crate root (the output is deterministic, byte for byte):

    pip install trimesh          # used: trimesh 5.2.0, numpy 2.4.6, Python 3.11.7
    python3 scripts/loop_reference.py

Meshes (all closed, consistently oriented, counter-clockwise seen from outside):
* octahedron  : 6 vertices of valence 4, positions perturbed (deterministic seed);
* irregular   : icosphere(subdivisions=1) (80 triangles), then deterministic edge flips
                so that vertex valences span 3..8, then radial perturbation;
* torus       : genus-1 torus, 8 x 6 sections (96 triangles, all valence 6), perturbed.

trimesh's subdivide_loop uses Loop's original weights, the same as wavemill's rules
(docs/multires-conventions.md): odd = 3/8 (a + b) + 1/8 (c + d); even = (1 - n beta) v +
beta sum(neighbours), beta = (40 - (3 + 2 cos(2 pi / n))^2) / (64 n). trimesh has no creases,
and its boundary vertex rule 3/4 v + 1/8 sum(...) sums every neighbour that is a boundary
vertex, also across interior edges (weights then exceed 1, e.g. on a quad split in two), where
wavemill uses only the two neighbours along boundary edges. So only closed meshes are compared.
"""

import os

import numpy as np
import trimesh
from trimesh import remesh

OUT = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "tests", "data", "loop_reference")
SEED = 4  # seed 004


def write_obj(path, vertices, faces, comment):
    with open(path, "w", newline="\n") as f:
        f.write(f"# {comment}\n")
        for v in vertices:
            # repr() of a Python float is the shortest string that round-trips exactly
            f.write("v {} {} {}\n".format(*(repr(float(x)) for x in v)))
        for t in faces:
            f.write("f {} {} {}\n".format(*(int(i) + 1 for i in t)))


def octahedron(rng):
    v = np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]], dtype=float)
    f = np.array([[0, 2, 4], [2, 1, 4], [1, 3, 4], [3, 0, 4], [2, 0, 5], [1, 2, 5], [3, 1, 5], [0, 3, 5]])
    v = v * (1.0 + 0.2 * rng.random((len(v), 1)))
    return v, f


def flip(faces, a, b):
    """Flip edge {a, b}: faces (a, b, c), (b, a, d) -> (c, a, d), (d, b, c). Returns success."""
    i = j = None
    for k, t in enumerate(faces):
        for s in range(3):
            if t[s] == a and t[(s + 1) % 3] == b:
                i, c = k, t[(s + 2) % 3]
            if t[s] == b and t[(s + 1) % 3] == a:
                j, d = k, t[(s + 2) % 3]
    if i is None or j is None or c == d:
        return False
    # the new edge must not exist already
    for t in faces:
        if c in t and d in t:
            return False
    faces[i] = [c, a, d]
    faces[j] = [d, b, c]
    return True


def valences(faces, n):
    nb = [set() for _ in range(n)]
    for t in faces:
        for s in range(3):
            nb[t[s]].add(t[(s + 1) % 3])
            nb[t[s]].add(t[(s + 2) % 3])
    return [len(x) for x in nb], nb


def irregular(rng):
    ico = trimesh.creation.icosphere(subdivisions=1)
    v = np.array(ico.vertices, dtype=float)
    faces = [list(map(int, t)) for t in ico.faces]
    n = len(v)
    # Raise vertex `hi` to valence 8 by flipping edges of its link, lower `lo` to valence 3 by
    # flipping its spokes, then some seeded random flips that keep valences in 3..8.
    hi, lo = 0, n - 1
    for _ in range(20):
        val, nb = valences(faces, n)
        if val[hi] >= 8:
            break
        for t in faces:
            if hi in t:
                s = t.index(hi)
                a, b = t[(s + 1) % 3], t[(s + 2) % 3]
                if val[a] > 4 and val[b] > 4 and flip(faces, a, b):
                    break
    for _ in range(20):
        val, nb = valences(faces, n)
        if val[lo] <= 3:
            break
        for w in sorted(nb[lo]):
            if val[w] > 4 and flip(faces, lo, w):
                break
    for _ in range(40):
        val, nb = valences(faces, n)
        t = faces[int(rng.integers(len(faces)))]
        s = int(rng.integers(3))
        a, b = t[s], t[(s + 1) % 3]
        c = t[(s + 2) % 3]
        d = next((u[(u.index(b) + 2) % 3] for u in faces if b in u and a in u and u != t), None)
        if d is None or {a, b, c, d} & {hi, lo}:
            continue
        if min(val[a], val[b]) > 4 and max(val[c], val[d]) < 7:
            flip(faces, a, b)
    val, _ = valences(faces, n)
    assert min(val) == 3 and max(val) == 8, (min(val), max(val))
    v = v * (1.0 + 0.15 * (rng.random((n, 1)) - 0.5))
    return v, np.array(faces)


def torus(rng):
    t = trimesh.creation.torus(major_radius=2.0, minor_radius=0.7, major_sections=8, minor_sections=6)
    v = np.array(t.vertices, dtype=float)
    v = v + 0.05 * (rng.random(v.shape) - 0.5)
    return v, np.array(t.faces)


def main():
    os.makedirs(OUT, exist_ok=True)
    rng = np.random.default_rng(SEED)
    for name, make in [("octahedron", octahedron), ("irregular", irregular), ("torus", torus)]:
        v, f = make(rng)
        m = trimesh.Trimesh(vertices=v, faces=f, process=False)
        assert m.is_watertight and m.is_winding_consistent and m.volume > 0, name
        val, _ = valences(f.tolist(), len(v))
        write_obj(os.path.join(OUT, f"{name}_input.obj"), v, f,
                  f"{name}: input ({len(v)} vertices, valences {min(val)}..{max(val)})")
        sv, sf = remesh.subdivide_loop(v, f, iterations=2)
        write_obj(os.path.join(OUT, f"{name}_loop2.obj"), sv, sf,
                  f"{name}: trimesh {trimesh.__version__} remesh.subdivide_loop(iterations=2)")
        print(name, len(v), len(f), "->", len(sv), len(sf), "valences", min(val), max(val))


if __name__ == "__main__":
    main()
