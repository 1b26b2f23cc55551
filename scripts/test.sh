#!/usr/bin/env bash
# Installs what is missing, builds lmcal with its tests and runs them all.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j"$(nproc)"
