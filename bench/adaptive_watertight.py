#!/usr/bin/env python3
"""Crack-free adaptive decodes (issue #48, item 4) on .isw files, counted independently of the library's mesh code.

usage: PYTHONPATH=build/python python3 bench/adaptive_watertight.py FILE.isw [FILE.isw ...]

For each file: the whole decode, a region decode (a box of 5% of the surface's box around its centre) and two
view decodes at 1 pixel on 1920 x 1080 (a camera at that centre looking along +x, fov 60; one outside the box
looking at it, fov 40), all triangulated. Per output: boundary edges (a directed edge without its reverse),
non-manifold edges (an undirected edge of more than two triangles) and directed edges used twice. A view's
boundary edges whose ends project into its image must end on the whole decode's boundary (matched by position:
in view, a view decode's points are the whole decode's; outside it, a 2.2 file read for the frustum leaves them
at the base's precision); a region's points outside the box are the base surface's, so only its counts are
checked. FAIL marks an output
with a non-manifold or repeated edge, or with a boundary where the whole decode has none.
"""
import sys

import numpy as np

import isowave


def edge_stats(vertices, faces):
    n = np.int64(vertices.shape[0] + 1)
    a = faces.reshape(-1).astype(np.int64)
    b = np.roll(faces, -1, axis=1).reshape(-1).astype(np.int64)
    directed, counts = np.unique(a * n + b, return_counts=True)
    undirected, uses = np.unique(np.minimum(a, b) * n + np.maximum(a, b), return_counts=True)
    boundary = directed[~np.isin(directed, b * n + a)]
    return int((counts > 1).sum()), int((uses > 2).sum()), boundary // n, boundary % n


def in_image(camera, points):
    """Which points project into the camera's image (a look-at pinhole camera)."""
    position, target, up = (np.asarray(camera[k], float) for k in ("position", "target", "up"))
    d = (target - position) / np.linalg.norm(target - position)
    r = np.cross(d, up)
    r /= np.linalg.norm(r)
    u = np.cross(r, d)
    v = points - position
    z = v @ d
    f = 0.5 * camera["viewport"][1] / np.tan(np.radians(camera["fov"]) / 2)
    with np.errstate(divide="ignore", invalid="ignore"):
        x, y = f * (v @ r) / z, f * (v @ u) / z
    return (z > 0) & (np.abs(x) <= camera["viewport"][0] / 2) & (np.abs(y) <= camera["viewport"][1] / 2)


def check(path):
    vertices, faces = isowave.decode(path, triangulate=True)
    repeated, nonmanifold, a, b = edge_stats(vertices, faces)
    ends = set(map(tuple, np.round(vertices[np.unique(np.concatenate([a, b]))], 9)))
    low, high = vertices.min(axis=0), vertices.max(axis=0)
    centre, extent = 0.5 * (low + high), high - low
    half = 0.5 * 0.368 * extent  # 0.368^3: 5% of the box
    inside = {"position": centre.tolist(), "target": (centre + [extent[0], 0, 0]).tolist(), "up": [0, 0, 1],
              "fov": 60, "viewport": [1920, 1080]}
    outside = {"position": (centre - [0, 0, 2 * extent[2] + extent.max()]).tolist(), "target": centre.tolist(),
               "up": [0, 1, 0], "fov": 40, "viewport": [1920, 1080]}
    line = [path.split("/")[-1], f"whole: {len(a)} boundary, {nonmanifold} non-manifold, {repeated} repeated"]
    cases = (("region", {"roi": tuple(np.concatenate([centre - half, centre + half]).tolist())}),
             ("view inside", {"view": inside}), ("view outside", {"view": outside}))
    for name, options in cases:
        v, f = isowave.decode(path, triangulate=True, **options)
        rep, nm, a2, b2 = edge_stats(v, f)
        note = ""
        if name != "region":
            points = v[np.concatenate([a2, b2])]
            seen = points[in_image(options["view"], points)]
            off = sum(1 for p in map(tuple, np.round(seen, 9)) if p not in ends)
            note = f", {off} of {len(seen)} ends in view off the whole boundary"
        ok = rep == 0 and nm == 0 and (len(a) > 0 or len(a2) == 0) and (name == "region" or off == 0)
        line.append(f"{name}: {len(a2)} boundary, {nm} non-manifold, {rep} repeated{note}{'' if ok else ' FAIL'}")
    print(" | ".join(line), flush=True)


if __name__ == "__main__":
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    for path in sys.argv[1:]:
        check(path)
