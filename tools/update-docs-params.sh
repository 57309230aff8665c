#!/usr/bin/env bash
# Replaces the parameter table in docs/guide.md (between the params:begin and
# params:end markers) with `wetcloth params --markdown`.
# Usage: tools/update-docs-params.sh path/to/wetcloth
set -euo pipefail
W=$(realpath "$1"); cd "$(dirname "$0")/.."
DOC=docs/guide.md
table=$("$W" params --markdown)
grep -q '<!-- params:begin -->' "$DOC" && grep -q '<!-- params:end -->' "$DOC" ||
  { echo "update-docs-params: $DOC has no params:begin/params:end markers" >&2; exit 1; }
awk -v t="$table" '/<!-- params:begin -->/{print; print t; skip=1; next}
                   /<!-- params:end -->/{skip=0} !skip' "$DOC" > "$DOC.tmp"
mv "$DOC.tmp" "$DOC"
