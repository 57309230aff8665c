#!/usr/bin/env bash
# The install line of docs/guide.md, without the network: a venv (Debian's NumPy
# through --system-site-packages), `pip install --no-build-isolation` of a copy
# of the checkout's setup.py and python/ (this build's module: WETCLOTH_BUILD_DIR),
# then the one-liner from another folder. The venv is made without
# its own copy of pip (10 s): Debian's pip, the same version, installs into it.
# Usage: test_python_install.sh SOURCE_DIR BUILD_DIR PYTHON
set -eu
SRC=$1; BUILD=$2; PY=$3
T=$(mktemp -d); trap 'rm -rf "$T"' EXIT
mkdir "$T/src"
cp "$SRC/setup.py" "$T/src/"
cp -r "$SRC/python" "$T/src/python"
rm -rf "$T/src/python/tests"
"$PY" -m venv --system-site-packages --without-pip "$T/venv"
unset MAKEFLAGS MFLAGS MAKELEVEL  # the build's check runs outside make test's own make
(cd "$T/src" && WETCLOTH_BUILD_DIR="$BUILD" PIP_NO_INDEX=1 "$T/venv/bin/python3" -m pip install -q --no-build-isolation .)
cd "$T"
out=$("$T/venv/bin/python3" -c "import wetcloth; s = wetcloth.Simulation('drop-table', grid=11); s.advance_to(0.5); print(s.positions.shape, s.metrics()['contact_area_m2'])")
echo "$out"
where=$("$T/venv/bin/python3" -c "import wetcloth; print(wetcloth.__file__)")
case "$where" in
  "$T/venv/"*) ;;
  *) echo "FAIL: wetcloth imported from $where, not the venv"; exit 1 ;;
esac
[[ "$out" =~ ^\(121,\ 3\)\ 0\.[0-9]+ ]] || { echo "FAIL: unexpected output: $out"; exit 1; }
echo "ok: pip installed wetcloth into a venv; the one-liner runs"
