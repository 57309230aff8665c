#!/usr/bin/env bash
# Installs the Debian packages wetcloth needs, only those that are missing.
set -euo pipefail
pkgs=(
  cmake g++ make pkg-config clang-format
  libeigen3-dev libtomlplusplus-dev libcli11-dev nlohmann-json3-dev libstb-dev
  libtinyobjloader-dev libcgal-dev zlib1g-dev
  libgtest-dev libgmock-dev libbenchmark-dev libbullet-dev
  python3 python3-matplotlib
  pybind11-dev python3-dev python3-numpy python3-pytest python3-distributed python3-venv python3-wheel
  libglfw3-dev libimgui-dev libepoxy-dev libegl-dev libgl1-mesa-dri xvfb xauth ffmpeg
)
# `install-deps.sh clients`: also the tools that read the caches (make test-clients).
if [ "${1:-}" = clients ]; then
  pkgs+=(blender python3-vtk9)
fi
# `install-deps.sh fuzz`: what `make fuzz` needs besides (clang's libFuzzer
# and sanitizer runtimes, and its OpenMP).
if [ "${1:-}" = fuzz ]; then
  pkgs=(clang libclang-rt-14-dev libomp-dev)
fi
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0
echo "installing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "error: need root (or sudo) to install: ${missing[*]}" >&2; exit 1; }
  SUDO=sudo
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get -o DPkg::Lock::Timeout=600 install -y -qq --no-install-recommends "${missing[@]}"
