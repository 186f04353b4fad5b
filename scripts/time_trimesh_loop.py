#!/usr/bin/env python3
"""Times trimesh's Loop subdivision on the bundled sample blade, for the ratio against
wavemill's criterion bench `loop_subdivision/blade_2_levels_output_triangles`.

    pip install trimesh
    python3 scripts/time_trimesh_loop.py
"""
import time

import trimesh

mesh = trimesh.load("data/blade.obj", process=False)
best = float("inf")
for _ in range(3):
    start = time.perf_counter()
    out = mesh.subdivide_loop(iterations=2)
    best = min(best, time.perf_counter() - start)
print(f"trimesh {trimesh.__version__}: {len(mesh.faces)} -> {len(out.faces)} triangles in {best:.3f} s "
      f"= {len(out.faces) / best / 1e6:.2f} M output triangles/s (best of 3)")
