#!/usr/bin/env python3
"""Writes the built-in scenes' obstacle meshes, scenes/meshes/*.obj.

Every mesh is closed (each edge between two triangles, counter-clockwise
seen from outside), in metres, z up, made here from simple shapes; nothing is
downloaded. Run from the repository's root:

    /usr/bin/python3 tools/make_meshes.py

and commit the .obj files with any change to this script (the build embeds
them in the program, tools/embed_scenes.cmake).

  bowl.obj   a bowl, a solid of revolution with a rounded rim (bowl-drape)
  rail.obj   a towel rail: a capsule along x (towel-rail)
  arm.obj    an arm for a sleeve: a cylinder along x with flat ends rounded
             at their edge (sleeve-pull)
  torso.obj  a mannequin's torso: the union of ellipsoids and capsules, cut
             flat at the hips and the neck (mannequin-drape)
"""
import math
import os
import sys


def revolve(profile, segments):
    """A closed solid of revolution about z from a profile of (r, z) points
    that starts and ends on the axis (r = 0), ordered so that the outside is
    on the right going along it seen with r to the right and z up."""
    pts, tris = [], []
    first_axis = len(pts)
    pts.append((0.0, 0.0, profile[0][1]))
    rings = []
    for r, z in profile[1:-1]:
        ring = []
        for s in range(segments):
            a = 2 * math.pi * s / segments
            ring.append(len(pts))
            pts.append((r * math.cos(a), r * math.sin(a), z))
        rings.append(ring)
    last_axis = len(pts)
    pts.append((0.0, 0.0, profile[-1][1]))
    n = segments
    for s in range(n):  # the first pole's fan
        tris.append((first_axis, rings[0][(s + 1) % n], rings[0][s]))
    for k in range(len(rings) - 1):
        a, b = rings[k], rings[k + 1]
        for s in range(n):
            t = (s + 1) % n
            tris.append((a[s], a[t], b[t]))
            tris.append((a[s], b[t], b[s]))
    for s in range(n):  # the last pole's fan
        tris.append((last_axis, rings[-1][s], rings[-1][(s + 1) % n]))
    return pts, tris


def signed_volume(pts, tris):
    v = 0.0
    for a, b, c in tris:
        (ax, ay, az), (bx, by, bz), (cx, cy, cz) = pts[a], pts[b], pts[c]
        v += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)) / 6
    return v


def outward(pts, tris):
    """The triangles turned so that the volume is positive (outward normals)."""
    return tris if signed_volume(pts, tris) > 0 else [(a, c, b) for a, b, c in tris]


def bowl():
    # Outer wall from the foot's centre out and up to the rim, a rounded rim
    # 8 mm thick, the inner wall down to the inner bottom's centre.
    r_foot, r_rim, height, wall = 0.05, 0.11, 0.07, 0.008
    profile = [(0.0, 0.0)]
    for k in range(1, 5):  # the foot
        profile.append((r_foot * k / 4, 0.0))
    for k in range(1, 17):  # the outer wall: a quarter ellipse out and up
        a = math.pi / 2 * k / 16
        profile.append((r_foot + (r_rim - r_foot) * math.sin(a), height * (1 - math.cos(a))))
    for k in range(1, 8):  # the rim: a half circle over the top
        a = math.pi * k / 8
        c = r_rim - wall / 2
        profile.append((c + wall / 2 * math.cos(a), height + wall / 2 * math.sin(a)))
    r_in, h_in = r_rim - wall, height
    for k in range(0, 17):  # the inner wall down to the inner bottom
        a = math.pi / 2 * k / 16
        profile.append(((r_foot - wall) + (r_in - r_foot + wall) * math.cos(a),
                        wall + (h_in - wall) * (1 - math.sin(a))))
    for k in range(3, 0, -1):
        profile.append(((r_foot - wall) * k / 4, wall))
    profile.append((0.0, wall))
    pts, tris = revolve(profile, 48)
    return pts, outward(pts, tris)


def capsule_x(length, radius, rings=24, segments=32):
    """A capsule along x through the origin: hemispheres on a cylinder."""
    profile = [(-(length / 2 + radius), 0.0)]  # (x, r): revolved about x
    for k in range(1, rings // 2 + 1):
        a = math.pi / 2 * k / (rings // 2)
        profile.append((-length / 2 - radius * math.cos(a), radius * math.sin(a)))
    for k in range(1, 12):
        profile.append((-length / 2 + length * k / 12, radius))
    for k in range(0, rings // 2):
        a = math.pi / 2 * k / (rings // 2)
        profile.append((length / 2 + radius * math.sin(a), radius * math.cos(a)))
    profile.append((length / 2 + radius, 0.0))
    pts, tris = revolve([(r, x) for x, r in profile], segments)
    # revolve() turned about z; swap z for x: (x, y, z) -> (z, y, -x) keeps handedness
    pts = [(z, y, -x) for x, y, z in pts]
    return pts, outward(pts, tris)


def cylinder_x(length, radius, fillet, segments=48):
    """A cylinder along x through the origin, its flat ends' edges rounded
    by `fillet` (a sleeve pulled over the end slides round it)."""
    profile = [(-length / 2, 0.0)]  # (x, r): revolved about x
    for k in range(1, 4):  # the end's disc
        profile.append((-length / 2, (radius - fillet) * k / 4))
    for k in range(0, 7):  # the rounded edge
        a = math.pi / 2 * k / 6
        profile.append((-length / 2 + fillet * (1 - math.cos(a)), radius - fillet * (1 - math.sin(a))))
    for k in range(1, 40):  # the wall, in rings 1 cm apart (on a 40 cm arm)
        profile.append((-length / 2 + fillet + (length - 2 * fillet) * k / 40, radius))
    for k in range(0, 7):
        a = math.pi / 2 * k / 6
        profile.append((length / 2 - fillet * (1 - math.sin(a)), radius - fillet * (1 - math.cos(a))))
    for k in range(3, 0, -1):
        profile.append((length / 2, (radius - fillet) * k / 4))
    profile.append((length / 2, 0.0))
    pts, tris = revolve([(r, x) for x, r in profile], segments)
    pts = [(z, y, -x) for x, y, z in pts]  # as capsule_x: z becomes x
    return pts, outward(pts, tris)


def torso():
    """The union of ellipsoids and capsules, sliced at each height: every
    slice holds the z axis, so a ray from it leaves the body once (a star
    about the axis), and the surface is a stack of rings."""
    def capsule(p, a, b, r):
        ab = [b[i] - a[i] for i in range(3)]
        ap = [p[i] - a[i] for i in range(3)]
        t = max(0.0, min(1.0, sum(ab[i] * ap[i] for i in range(3)) / sum(x * x for x in ab)))
        return math.dist(p, [a[i] + t * ab[i] for i in range(3)]) - r

    def ellipsoid(p, c, r):
        return math.sqrt(sum(((p[i] - c[i]) / r[i]) ** 2 for i in range(3))) - 1

    def inside(p):
        return (ellipsoid(p, (0, 0, 0.15), (0.15, 0.10, 0.22)) < 0 or  # hips and belly
                ellipsoid(p, (0, 0.005, 0.36), (0.16, 0.105, 0.17)) < 0 or  # chest
                capsule(p, (-0.15, 0, 0.47), (0.15, 0, 0.47), 0.055) < 0 or  # shoulders
                capsule(p, (0, 0, 0.40), (0, 0, 0.70), 0.048) < 0)  # neck

    z_bottom, z_top, heights, segments = 0.0, 0.6, 64, 64
    pts, tris = [], []
    pts.append((0.0, 0.0, z_bottom))
    rings = []
    for h in range(heights + 1):
        z = z_bottom + (z_top - z_bottom) * h / heights
        ring = []
        for s in range(segments):
            a = 2 * math.pi * s / segments
            lo, hi = 0.0, 0.5
            for _ in range(40):  # the ray's exit, by bisection
                mid = (lo + hi) / 2
                if inside((mid * math.cos(a), mid * math.sin(a), z)):
                    lo = mid
                else:
                    hi = mid
            ring.append(len(pts))
            pts.append((lo * math.cos(a), lo * math.sin(a), z))
        rings.append(ring)
    top = len(pts)
    pts.append((0.0, 0.0, z_top))
    n = segments
    for s in range(n):
        tris.append((0, rings[0][(s + 1) % n], rings[0][s]))
    for k in range(len(rings) - 1):
        a, b = rings[k], rings[k + 1]
        for s in range(n):
            t = (s + 1) % n
            tris.append((a[s], a[t], b[t]))
            tris.append((a[s], b[t], b[s]))
    for s in range(n):
        tris.append((top, rings[-1][s], rings[-1][(s + 1) % n]))
    return pts, outward(pts, tris)


def write_obj(path, title, pts, tris):
    with open(path, "w", newline="\n") as f:
        f.write(f"# {title}\n# written by tools/make_meshes.py: closed, metres, z up\n")
        for x, y, z in pts:
            f.write(f"v {x:.6f} {y:.6f} {z:.6f}\n")
        for a, b, c in tris:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")
    print(f"{path}: {len(pts)} vertices, {len(tris)} triangles")


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = os.path.join(root, "scenes", "meshes")
    if len(sys.argv) > 1:
        out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    write_obj(os.path.join(out, "bowl.obj"), "a bowl, 22 cm across, 7.4 cm high", *bowl())
    write_obj(os.path.join(out, "rail.obj"), "a towel rail, 50 cm long, 2.4 cm thick",
              *capsule_x(0.5, 0.012))
    write_obj(os.path.join(out, "arm.obj"), "an arm, 40 cm long, 4 cm in radius",
              *cylinder_x(0.4, 0.04, 0.008))
    write_obj(os.path.join(out, "torso.obj"), "a mannequin's torso, 60 cm high", *torso())


if __name__ == "__main__":
    main()
