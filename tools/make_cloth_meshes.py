#!/usr/bin/env python3
"""Writes the built-in scenes' cloth meshes, scenes/meshes/cloth_*.obj.

    tools/make_cloth_meshes.py [--out scenes/meshes]

cloth_sleeve.obj: a sleeve, an open tube along x, 4.05 cm in radius (half a
millimetre over sleeve-pull's 4 cm arm, tools/make_meshes.py) and 24 cm
long, of quads about 8 mm a side (32 around, 31 along), texture coordinates
u around (from the top, seam there) and v along x (v = 1: the end ring at
+x, which sleeve-pull's handle pulls). The grid rolled up: quads give it the
grid's springs (docs/guide.md, "A cloth from a mesh").

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


def sleeve(radius=0.0405, length=0.24, around=32, along=31):
    """Vertices (x, y, z), texture coordinates and quads (as vertex/uv index
    pairs, counter-clockwise seen from outside) of an open tube along x."""
    points, uvs, quads = [], [], []
    for i in range(along):
        x = -length / 2 + length * i / (along - 1)
        for j in range(around):
            a = 2 * math.pi * j / around  # from the top (+z) towards +y
            points.append((x, radius * math.sin(a), radius * math.cos(a)))
    for i in range(along):  # a column more than vertices: u = 1 at the seam
        for j in range(around + 1):
            uvs.append((j / around, i / (along - 1)))
    for i in range(along - 1):
        for j in range(around):
            v = [i * around + j, i * around + (j + 1) % around,
                 (i + 1) * around + (j + 1) % around, (i + 1) * around + j]
            t = [i * (around + 1) + j, i * (around + 1) + j + 1,
                 (i + 1) * (around + 1) + j + 1, (i + 1) * (around + 1) + j]
            quads.append(list(zip(v, t)))
    return points, uvs, quads


def write_sleeve(path):
    points, uvs, quads = sleeve()
    lines = ["# a sleeve: an open tube along x, 4.05 cm in radius, 24 cm long, %d vertices, "
             "%d quads" % (len(points), len(quads)),
             "# written by tools/make_cloth_meshes.py; metres, z up"]
    for x, y, z in points:
        lines.append("v %.9f %.9f %.9f" % (x, y, z))
    for u, v in uvs:
        lines.append("vt %.9f %.9f" % (u, v))
    for q in quads:
        # Outward normals: the quad's corners counter-clockwise seen from outside.
        lines.append("f " + " ".join("%d/%d" % (a + 1, t + 1) for a, t in reversed(q)))
    with open(path, "w", newline="\n") as f:
        f.write("\n".join(lines) + "\n")
    return len(points), len(quads)


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
    path = os.path.join(args.out, "cloth_sleeve.obj")
    vertices, quads = write_sleeve(path)
    print("wrote", os.path.relpath(path), vertices, "vertices,", quads, "quads")


if __name__ == "__main__":
    main()
