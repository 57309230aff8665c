#!/usr/bin/env bash
# Replaces the README's parameter table with `wetcloth params --markdown`.
set -euo pipefail
W=$(realpath "$1"); cd "$(dirname "$0")/.."
table=$("$W" params --markdown)
awk -v t="$table" '/<!-- params:begin -->/{print; print t; skip=1; next}
                   /<!-- params:end -->/{skip=0} !skip' README.md > README.md.tmp
mv README.md.tmp README.md
