#!/usr/bin/env bash
# Installs the Debian 12 packages vibro needs, skipping the apt step when all are present.
#   install-deps.sh run     what building and running vibro needs: the compiler, the libraries,
#                           MPI, the Python package's build and the plots' and CSV tools' Python
#                           modules (scripts/quickstart.sh, the README's first command)
#   install-deps.sh test    run's, and what the test suite adds: GoogleTest, Google Benchmark,
#                           pytest, the notebook runner (Jupyter), clang for the fuzz harnesses,
#                           hdf5-tools (scripts/test.sh; the default)
#   install-deps.sh bench   test's, and the peers of benchmarks/peers/run_all.py (SciPy, Siconos)
set -euo pipefail
mode=${1:-test}
run=(
  build-essential cmake pkg-config
  libsundials-dev libeigen3-dev libhdf5-dev
  libcli11-dev libtomlplusplus-dev libfmt-dev libtbb-dev nlohmann-json3-dev libboost-dev
  libopenmpi-dev openmpi-bin
  pybind11-dev python3-dev python3-numpy python3-h5py python3-matplotlib
  libflint-arb-dev python3-mpmath python3-tqdm
)
test=(
  hdf5-tools libgtest-dev libgmock-dev libbenchmark-dev python3-pytest
  jupyter-nbconvert python3-ipykernel python3-nbformat python3-nbclient
  clang libclang-rt-14-dev
)
bench=(python3-scipy python3-siconos)
case $mode in
  run) packages=("${run[@]}") ;;
  test) packages=("${run[@]}" "${test[@]}") ;;
  bench) packages=("${run[@]}" "${test[@]}" "${bench[@]}") ;;
  *) echo "usage: install-deps.sh [run|test|bench] (not '$mode')" >&2; exit 2 ;;
esac
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps ($mode): all ${#packages[@]} packages present" >&2
  exit 0
fi
echo "install-deps ($mode): installing ${missing[*]}" >&2
sudo=""
[ "$(id -u)" -eq 0 ] || sudo="sudo"
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -qq
$sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
