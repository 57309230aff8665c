#!/usr/bin/env python3
"""The trapped air's pressure deficit while a wet cloth is pulled off the
table, plotted live: the deficit over time, and the cloth's height with the
part in contact (the air pocket's seal) outlined.

    python3 examples/python/pressure_live.py
    python3 examples/python/pressure_live.py --out pressure.png   # also saved
"""
import argparse

import matplotlib.pyplot as plt

import wetcloth

ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
ap.add_argument("--scene", default="pull-straight")
ap.add_argument("--humidity", type=float, default=0.7)
ap.add_argument("--grid", type=int, default=31)
ap.add_argument("--duration", type=float, default=1.5)
ap.add_argument("--every", type=float, default=0.02, help="seconds between updates")
ap.add_argument("--out", help="save the last picture here")
args = ap.parse_args()

sim = wetcloth.Simulation(args.scene, humidity=args.humidity, grid=args.grid)
p_atm = sim.get("air.p_atm")
nu, nv = sim.grid

plt.ion()
fig, (curve, field) = plt.subplots(1, 2, figsize=(10, 4))
line, = curve.plot([], [])
curve.set(xlabel="time, s", ylabel="p_atm - p_in, Pa", title="pressure deficit", xlim=(0, args.duration))
height = lambda: 100 * sim.positions[:, 2].reshape(nv, nu)  # cm; particle i + nu j is (i, j)
image = field.imshow(height(), origin="lower", cmap="viridis")
fig.colorbar(image, ax=field, label="height, cm")
field.set(title="height; in contact outlined", xlabel="i", ylabel="j")
outline = None
times, deficits = [], []
steps = max(1, round(args.duration / args.every))
for k in range(1, steps + 1):
    sim.advance_to(k * args.duration / steps)
    m = sim.metrics()
    times.append(m["time_s"])
    deficits.append(p_atm - m["inner_pressure_pa"])
    line.set_data(times, deficits)
    curve.set_ylim(0, max(1.0, 1.1 * max(deficits)))
    z = height()
    image.set_data(z)
    image.set_clim(0, max(1.0, z.max()))
    if outline is not None:
        try:
            outline.remove()
        except AttributeError:  # matplotlib before 3.8: piece by piece
            for piece in outline.collections:
                piece.remove()
    contact = sim.in_contact.reshape(nv, nu)
    outline = field.contour(contact, levels=[0.5], colors="white") if 0 < contact.sum() < contact.size else None
    fig.canvas.draw_idle()
    fig.canvas.flush_events()
print(f"peak deficit over the updates {max(deficits):.1f} Pa, at any step {sim.peak_deficit:.1f} Pa; "
      f"handle at {sim.metrics()['handle_height_m']:.4f} m")
if args.out:
    fig.savefig(args.out)
    print(f"wrote {args.out}")
else:
    plt.ioff()
    plt.show()
