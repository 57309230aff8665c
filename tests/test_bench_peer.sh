#!/usr/bin/env bash
# `wetcloth bench --peer bullet`: it runs briefly (a small grid, a few steps),
# prints the ratio line and writes its JSON; in a build without Bullet it says
# so and exits 1. No timing checks.
# Usage: test_bench_peer.sh WETCLOTH with|without
set -u
W="$1"; BUILD="$2"
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
fails=0; passes=0
ok()  { passes=$((passes+1)); echo "ok: $1"; }
bad() { fails=$((fails+1)); echo "FAIL: $1"; }

if [ "$BUILD" = without ]; then
  "$W" bench --peer bullet --grids 9 --duration 0.01 --out "$T/peer.json" >"$T/out" 2>"$T/err"; code=$?
  [ $code -eq 1 ] && grep -qF -- "--peer bullet: this wetcloth was built without Bullet" "$T/err" &&
    [ ! -e "$T/peer.json" ] && ok "built without Bullet: exit 1, said, nothing written" ||
    bad "built without Bullet: exit $code, $(cat "$T/err")"
  echo "skip: Bullet's runs (this build has no Bullet)"
else
  "$W" bench --peer bullet --grids 9,11 --duration 0.01 --repetitions 2 --out "$T/peer.json" \
    >"$T/out" 2>"$T/err"; code=$?
  [ $code -eq 0 ] && ok "bench --peer bullet exits 0" || bad "bench --peer bullet: exit $code, $(cat "$T/err")"
  grep -Eq '^grid 9: ours/Bullet real-time factor [0-9.]+' "$T/out" &&
    grep -Eq '^grid 11: ours/Bullet real-time factor [0-9.]+' "$T/out" &&
    ok "a ratio line per grid" || bad "no ratio line: $(cat "$T/out")"
  python3 -c '
import json, math, sys
d = json.load(open(sys.argv[1]))
assert d["peer"]["name"] == "bullet" and d["threads"] == 1 and len(d["grids"]) == 2, d
for g, n in zip(d["grids"], (9, 11)):
    o, b = g["ours"], g["bullet"]
    assert o["particles"] == b["nodes"] == n * n, g
    assert len(o["wall_s"]) == len(b["wall_s"]) == len(g["ratio_per_round"]) == 2, g
    assert b["steps"] == 6 and abs(b["dt_s"] - 1 / 600) < 1e-15, b   # 0.01 s at 1/600
    # Both the same dry cloth: 0.12 kg/m^2 over 0.3 m x 0.3 m.
    assert abs(o["dry_mass_kg"] - 0.0108) < 1e-9 and abs(b["mass_kg"] - 0.0108) < 1e-9, g
    assert g["ratio_median"] > 0 and math.isfinite(g["ratio_median"]), g
' "$T/peer.json" && ok "peer JSON: two grids, two rounds each, the same mass" || bad "peer JSON"
  # Both clothes of a hanging scene fall: the same scene in both, pins held.
  "$W" bench --peer bullet --scene hang --grids 11 --duration 0.05 --repetitions 1 \
    --out "$T/hang.json" >/dev/null 2>"$T/err" || bad "hang: $(cat "$T/err")"
  python3 -c '
import json, sys
g = json.load(open(sys.argv[1]))["grids"][0]
o, b = g["ours"]["end"], g["bullet"]["end"]
# t = 0.05 s: a free fall of 1.2 cm; the pinned edge stays at 0.6 m.
assert 0.58 < o["mean_z_m"] < 0.6 and 0.58 < b["mean_z_m"] < 0.6, g
assert abs(o["max_z_m"] - 0.6) < 1e-6 and abs(b["max_z_m"] - 0.6) < 1e-6, g
' "$T/hang.json" && ok "hang: both clothes fall from their pins" || bad "hang: $(cat "$T/hang.json")"
  # A duration shorter than one of Bullet's steps is bad input; nothing written.
  "$W" bench --peer bullet --grids 9 --duration 0.0005 --out "$T/short.json" >/dev/null 2>"$T/err"; code=$?
  [ $code -eq 2 ] && grep -qF "shorter than one of Bullet's steps" "$T/err" && [ ! -e "$T/short.json" ] &&
    ok "--duration under 1/600 s: exit 2" || bad "short duration: exit $code, $(cat "$T/err")"
fi
# An unknown peer is bad input in any build.
"$W" bench --peer havok --grids 9 --out "$T/havok.json" >/dev/null 2>"$T/err"; code=$?
[ $code -eq 2 ] && [ ! -e "$T/havok.json" ] && ok "--peer havok: exit 2" || bad "--peer havok: exit $code, $(cat "$T/err")"

echo "$passes passed, $fails failed"
[ $fails -eq 0 ]
