#!/usr/bin/env python3
"""Paper Fig. 7: a force pulls the middle of a cloth lying on the table; the
wetter the cloth, the lower it is lifted and the wider its base stays.

    python3 examples/python/fig7.py --out fig7.png
"""
import argparse

import matplotlib.pyplot as plt

import wetcloth


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--humidity", default="0,0.3,0.5,0.7,1", help="humidities ω, comma-separated")
    ap.add_argument("--grid", type=int, default=51)
    ap.add_argument("--duration", type=float, default=3.0)
    ap.add_argument("--processes", type=int, help="cases run at once (default: all cores)")
    ap.add_argument("--out", default="fig7.png")
    args = ap.parse_args()

    omegas = [float(w) for w in args.humidity.split(",")]
    table = wetcloth.sweep("pull-straight", vary={"cloth.humidity": omegas},
                           overrides={"run.duration": args.duration}, grid=args.grid, processes=args.processes)

    fig, (a, b) = plt.subplots(1, 2, figsize=(9, 3.5))
    a.plot(table["humidity"], 100 * table["handle_height_m"], "o-")
    a.set(xlabel="humidity ω", ylabel="pulled height, cm", title="(a) pulled height")
    b.plot(table["humidity"], 100 * table["base_diagonal_m"], "s-")
    b.set(xlabel="humidity ω", ylabel="base diagonal, cm", title="(b) base diagonal")
    fig.tight_layout()
    fig.savefig(args.out)
    for row in table:
        print(f"ω = {row['humidity']:.2f}: height {row['handle_height_m']:.4f} m, "
              f"base diagonal {row['base_diagonal_m']:.4f} m ({row['status']})")
    print(f"wrote {args.out}")


if __name__ == "__main__":  # the sweep's processes import this file: nothing runs then
    main()
