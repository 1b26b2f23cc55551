#!/usr/bin/env bash
# lmcal as a package, as another project uses it: the build installed into a temporary
# prefix, examples/cpp configured against it with find_package (no hand-written paths),
# built and run on the bundled friction log; the installed lmcal command runs too.
# With PYTHON and PYTHON_DIR (the package's folder relative to the prefix), the Python package
# is imported from the prefix and fits the bundled log.
# Usage: package_test.sh BUILD_DIR SOURCE_DIR [PYTHON PYTHON_DIR]
set -euo pipefail
build=$1
source=$2
python=${3:-}
python_dir=${4:-}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/lmcal/fit/friction_fit.hpp"
test -f "$work/prefix/share/lmcal/guides.toml"
test -s "$work/prefix/share/man/man1/lmcal.1"                          # the man page
test -s "$work/prefix/share/bash-completion/completions/lmcal"         # the bash completion
cmake -S "$source/examples/cpp" -B "$work/example" -DCMAKE_PREFIX_PATH="$work/prefix" -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$work/example" >/dev/null
"$work/example/fit_log" "$source/measurements/cheng2017/friction.csv" >"$work/fit.txt"
# Seven constants, each inside its own finite interval, and the RMSE.
awk 'NR <= 7 { v = $2; lo = substr($3, 2) + 0; hi = $4 + 0; if (!(lo <= v && v <= hi)) { print "bad interval: " $0; exit 1 } }
     END { if (NR != 8) { print "expected 8 lines, got " NR; exit 1 } }' "$work/fit.txt"
grep -q '^rmse_N ' "$work/fit.txt"
# A version the package does not claim is refused.
mkdir -p "$work/wrong"
cat >"$work/wrong/CMakeLists.txt" <<'CMAKE'
cmake_minimum_required(VERSION 3.25)
project(wrong LANGUAGES CXX)
find_package(lmcal 9.0 REQUIRED)
CMAKE
if cmake -S "$work/wrong" -B "$work/wrong/build" -DCMAKE_PREFIX_PATH="$work/prefix" >/dev/null 2>&1; then
  echo "find_package(lmcal 9.0) was accepted by a 0.2 package"
  exit 1
fi
"$work/prefix/bin/lmcal" --help >/dev/null
if [[ -n "$python" ]]; then
  test -f "$work/prefix/$python_dir/lmcal/__init__.py"
  (cd "$work" && PYTHONPATH="$work/prefix/$python_dir" "$python" - "$source/measurements/cheng2017/friction.csv" "$work/prefix" <<'PY'
import sys, lmcal
assert lmcal.__file__.startswith(sys.argv[2]), lmcal.__file__
fit = lmcal.fit_friction(sys.argv[1], bootstrap=0)
k1 = fit.params["k1"]
assert k1.ci[0] < k1.value < k1.ci[1], k1
PY
  )
fi
echo "package: installed, found, built against and run"
