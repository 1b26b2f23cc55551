#!/usr/bin/env bash
# Renders the top of the bundled report (fits/cheng2017/report.html) to docs/report.png with
# headless Chromium, for the README.
set -euo pipefail
cd "$(dirname "$0")/.."
profile=$(mktemp -d)
trap 'rm -rf "$profile"' EXIT
chromium --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run --user-data-dir="$profile" \
  --hide-scrollbars --window-size=1300,1500 --virtual-time-budget=10000 \
  --screenshot="$PWD/docs/report.png" "file://$PWD/fits/cheng2017/report.html" 2>/dev/null
echo "wrote docs/report.png"
