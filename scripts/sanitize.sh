#!/usr/bin/env bash
# Builds lmcal, its tests and the fuzz harnesses with AddressSanitizer and UndefinedBehaviorSanitizer
# (clang) into build-asan/ and runs the test suite there. Fails on a failing test or on any
# sanitizer report (the runtimes abort the process, and ctest counts the test as failed).
# The fuzz harnesses share the build (scripts/fuzz.sh with LMCAL_FUZZ_BUILD=build-asan): the
# library carries libFuzzer's coverage instrumentation too, which the tests do not notice.
# Usage: scripts/sanitize.sh [JOBS]   (default: all cores)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${1:-$(nproc)}
bash scripts/install-deps.sh
# Off here: the Python module would have to load the ASan runtime into an uninstrumented
# python3 (it refuses: "ASan runtime does not come first"); the benchmarks test nothing.
# Clang, as for the fuzzers: g++ 12 with ASan and UBSan spends over 25 minutes (-O3) on one file
# (src/fit/friction_model.cc, the Jet-heavy friction residuals), and over 13 at -O1.
CC=clang-16 CXX=clang++-16 cmake -S . -B build-asan -DCMAKE_BUILD_TYPE=Release -DLMCAL_SANITIZE=address,undefined \
      -DLMCAL_FUZZ=ON -DLMCAL_PYTHON=OFF -DLMCAL_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build build-asan -j"$jobs"
source scripts/sanitizer-env.sh
# The suite without the tests scripts/sanitize-skip.txt lists (each with its reason). The cli
# test's 1-thread-against-2 comparisons repeat two whole calibrations, the slowest part of the
# slowest test here, and compare results, not memory: LMCAL_TEST_SERIAL_BUILD skips them (the
# release suite runs them).
skip=$(grep -v -e '^#' -e '^$' scripts/sanitize-skip.txt | paste -sd '|')
LMCAL_TEST_SERIAL_BUILD=1 ctest --test-dir build-asan --output-on-failure -j"$jobs" -E "^($skip)\$"
