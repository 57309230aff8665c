#!/usr/bin/env python3
"""Writes the built-in scenes' cloth meshes, scenes/meshes/cloth_*.obj.

    tools/make_cloth_meshes.py [--out scenes/meshes]

cloth_disc.obj: a round cloth 0.3 m across (metres, in the xy plane, z up),
triangles in concentric rings about 6 mm apart (ring r has 6 r vertices,
so the triangles stay close to equilateral), with texture coordinates
u = 0.5 + x / 0.3, v = 0.5 + y / 0.3. A mesh of no grid: every vertex of
the kinds a mesh cloth meets (valence 5, 6 and 7, a curved border).

The output is the same bytes on every run (no randomness, fixed formatting),
so that the committed files are what this script writes.
"""
import argparse
import math
import os


def disc(radius=0.15, rings=25):
    """Vertices (x, y) and counter-clockwise triangles of a disc."""
    points = [(0.0, 0.0)]
    first = [0]  # index of each ring's first vertex
    for r in range(1, rings + 1):
        first.append(len(points))
        count = 6 * r
        for k in range(count):
            a = 2 * math.pi * k / count
            points.append((radius * r / rings * math.cos(a), radius * r / rings * math.sin(a)))
    triangles = []
    for k in range(6):  # the first ring's fan
        triangles.append((0, first[1] + k, first[1] + (k + 1) % 6))
    for r in range(1, rings):
        inner, outer = first[r], first[r + 1]
        n_in, n_out = 6 * r, 6 * (r + 1)
        i = j = 0
        # Walk both rings by angle, each step adding the triangle whose new
        # vertex comes first.
        while i < n_in or j < n_out:
            a_in = (i + 1) / n_in
            a_out = (j + 1) / n_out
            if j < n_out and (i >= n_in or a_out <= a_in):
                triangles.append((inner + i % n_in, outer + j, outer + (j + 1) % n_out))
                j += 1
            else:
                triangles.append((inner + i % n_in, outer + j % n_out, inner + (i + 1) % n_in))
                i += 1
    return points, triangles


def write_obj(path, points, triangles, radius, comment):
    lines = ["# " + comment, "# written by tools/make_cloth_meshes.py; metres, z up"]
    for x, y in points:
        lines.append("v %.9f %.9f 0" % (x, y))
    for x, y in points:
        lines.append("vt %.9f %.9f" % (0.5 + x / (2 * radius), 0.5 + y / (2 * radius)))
    for a, b, c in triangles:
        lines.append("f %d/%d %d/%d %d/%d" % (a + 1, a + 1, b + 1, b + 1, c + 1, c + 1))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--out", default=os.path.join(here, "..", "scenes", "meshes"))
    args = parser.parse_args()
    os.makedirs(args.out, exist_ok=True)
    points, triangles = disc()
    path = os.path.join(args.out, "cloth_disc.obj")
    write_obj(path, points, triangles, 0.15,
              "a round cloth 0.3 m across, %d vertices, %d triangles" % (len(points), len(triangles)))
    print("wrote", os.path.relpath(path), len(points), "vertices,", len(triangles), "triangles")


if __name__ == "__main__":
    main()
