#!/usr/bin/env python3
"""The blog's flag: a cloth hanging from its top corners, a gust on its lower
right, animated with matplotlib.

    python3 examples/python/flag.py                  # a window
    python3 examples/python/flag.py --out flag.gif   # a file (Pillow)
"""
import argparse

import matplotlib.pyplot as plt
from matplotlib.animation import FuncAnimation

import wetcloth

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--grid", type=int, default=31, help="particles along each side")
ap.add_argument("--duration", type=float, default=4.0, help="simulated seconds")
ap.add_argument("--fps", type=float, default=30)
ap.add_argument("--out", help="write the animation here (.gif) instead of showing it")
args = ap.parse_args()

sim = wetcloth.Simulation("flag", grid=args.grid)
frames = int(args.duration * args.fps)

fig = plt.figure(figsize=(5, 5))
ax = fig.add_subplot(projection="3d")


def draw(f):
    sim.advance_to(f / args.fps)
    x = sim.positions  # (n, 3), C-contiguous: a copy at each read
    ax.clear()
    ax.plot_trisurf(x[:, 0], x[:, 1], x[:, 2], triangles=sim.triangles, color="tab:blue", alpha=0.8)
    ax.set(xlim=(-0.2, 0.2), ylim=(-0.2, 0.2), zlim=(0.25, 0.8), title=f"t = {sim.time:.2f} s")


anim = FuncAnimation(fig, draw, frames=frames + 1, interval=1000 / args.fps)
if args.out:
    anim.save(args.out, writer="pillow", fps=args.fps)
    print(f"wrote {args.out}: {frames + 1} frames, tip at z = {sim.positions[:, 2].min():.3f} m")
else:
    plt.show()
