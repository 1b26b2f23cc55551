#!/usr/bin/env bash
# Installs the Debian 12 packages lmcal builds with, if any are missing.
# As root it runs apt-get; otherwise it prints the exact command to run and fails.
set -euo pipefail

packages=(
  g++ cmake make                 # toolchain
  ccache                         # compiler cache: rebuilds on this machine reuse earlier objects
  libceres-dev libeigen3-dev     # least squares, autodiff, covariance; linear algebra
  libnlopt-dev libnlopt-cxx-dev  # global and derivative-free search
  libcli11-dev libfmt-dev nlohmann-json3-dev libtomlplusplus-dev libfast-float-dev
  libboost-dev libssl-dev        # Student-t and F quantiles (Boost.Math); SHA-256 of inputs (OpenSSL)
  pybind11-dev python3-dev python3-numpy  # the Python package lmcal
  openmpi-bin libopenmpi-dev     # lmcal fleet on a cluster: mpirun -np N (optional at build time)
  libgtest-dev libbenchmark-dev  # tests and benchmarks
  python3-pytest python3-pandas python3-jsonschema  # the Python package's tests (a DataFrame goes in; the outputs' schema)
  python3-matplotlib             # the Python package's plot() (optional for the package; its tests draw)
  python3-nbclient python3-nbformat python3-ipykernel  # the notebook example, executed by the tests
  chromium chromium-driver       # the report's test in a headless browser
  clang-16 libclang-rt-16-dev libomp-16-dev llvm  # sanitize.sh, fuzz.sh: clang 16 (14 cannot build lmcal), libFuzzer, llvm-symbolizer
)

missing=()
for p in "${packages[@]}"; do
  [[ "$p" == \#* ]] && continue
  status=$(dpkg-query -W -f='${Status}' "$p" 2>/dev/null || true)
  [[ "$status" == "install ok installed" ]] || missing+=("$p")
done

if ((${#missing[@]} == 0)); then
  exit 0
fi

echo "lmcal: installing missing packages: ${missing[*]}" >&2
if [[ $(id -u) -eq 0 ]]; then
  export DEBIAN_FRONTEND=noninteractive
  apt-get update -qq
  apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  sudo DEBIAN_FRONTEND=noninteractive apt-get update -qq
  sudo DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
else
  echo "lmcal: these packages are missing and installing them needs root. Run:" >&2
  echo "  sudo apt-get update && sudo apt-get install -y ${missing[*]}" >&2
  exit 1
fi
