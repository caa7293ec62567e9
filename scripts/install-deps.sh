#!/usr/bin/env bash
# Installs the Debian 12 packages vibro needs, skipping the apt step when all are present.
set -euo pipefail
packages=(
  build-essential cmake pkg-config
  libsundials-dev libeigen3-dev libhdf5-dev hdf5-tools
  libgtest-dev libgmock-dev libbenchmark-dev libcli11-dev libtomlplusplus-dev
  libfmt-dev libtbb-dev nlohmann-json3-dev python3-h5py python3-matplotlib
  libopenmpi-dev openmpi-bin
  libboost-dev
  pybind11-dev python3-dev python3-numpy python3-pytest
  jupyter-nbconvert python3-ipykernel python3-nbformat python3-nbclient
  clang libclang-rt-14-dev
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present" >&2
  exit 0
fi
echo "install-deps: installing ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
