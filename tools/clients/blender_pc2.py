# Blender (headless): import a run's rest OBJ, put its PC2 cache on a Mesh Cache
# modifier, and check the evaluated mesh at each frame against the run's own
# frames/frame_NNNNN.obj. The docs' three steps, done by a script:
#   blender -b --factory-startup --python blender_pc2.py -- RUN_DIR
# Exit 0 when every frame's vertices match within float precision.
import os
import sys

import bpy

run = sys.argv[sys.argv.index("--") + 1]


def obj_points(path):
    pts, up = [], "z"
    with open(path) as f:
        for line in f:
            if line.startswith("#") and ", y up" in line:
                up = "y"
            if line.startswith("v "):
                pts.append(tuple(float(t) for t in line.split()[1:4]))
    return pts, up


rest, up = obj_points(os.path.join(run, "cloth_rest.obj"))
bpy.ops.wm.read_factory_settings(use_empty=True)
# Blender is z up: a z-up file comes in as it is; a y-up file with the
# importer's defaults (forward -Z, up Y), which turn it to z up.
if up == "z":
    bpy.ops.wm.obj_import(filepath=os.path.join(run, "cloth_rest.obj"), forward_axis="Y", up_axis="Z")
else:
    bpy.ops.wm.obj_import(filepath=os.path.join(run, "cloth_rest.obj"))
obj = bpy.context.selected_objects[0]
mod = obj.modifiers.new("wetcloth", "MESH_CACHE")
mod.cache_format = "PC2"
mod.filepath = os.path.join(run, "cloth.pc2")
# The importer turns a y-up file by the object's transform, not its vertices, so
# the cache's points (the file's own axes) need no turning of their own.
frames = sorted(f for f in os.listdir(os.path.join(run, "frames")) if f.endswith(".obj"))
scene = bpy.context.scene
worst, checked = 0.0, 0
for k, name in enumerate(frames):
    want, _ = obj_points(os.path.join(run, "frames", name))
    scene.frame_set(k)
    deps = bpy.context.evaluated_depsgraph_get()
    ev = obj.evaluated_get(deps)
    mesh = ev.to_mesh()
    world = ev.matrix_world
    got = [tuple(world @ v.co) for v in mesh.vertices]
    ev.to_mesh_clear()
    if len(got) != len(want):
        print(f"FAIL frame {k}: {len(got)} vertices, the run has {len(want)}")
        sys.exit(1)
    for g, w in zip(got, want):
        # the run's point in Blender's z-up world
        w = w if up == "z" else (w[0], -w[2], w[1])
        worst = max(worst, max(abs(a - b) for a, b in zip(g, w)))
    checked += 1
print(f"blender: {checked} frames, {len(rest)} vertices, largest difference {worst:.3g} m")
sys.exit(0 if checked > 1 and worst < 1e-5 else 1)
