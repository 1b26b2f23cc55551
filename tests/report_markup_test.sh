#!/usr/bin/env bash
# Run names that are markup (issue 23 #1: a name reached the report's tables as raw HTML):
# the bundled friction log with three runs renamed to an image with an error handler, a closing
# title and a script, and an attribute break-out, calibrated; the names must reach the CSV
# outputs as written and the report (in headless Chromium, its hover tooltips too) only as text.
set -euo pipefail
lmcal="$1"
root="$(cd "$(dirname "$0")/.." && pwd)"
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
mkdir "$out/set"
sed -e 's|^run01,|"<img src=x onerror=alert(1)>",|' \
    -e 's|^run02,|"</title><script>alert(2)</script>",|' \
    -e 's|^run03,|"x"" onmouseover=""alert(3)",|' \
    "$root/measurements/cheng2017/friction.csv" >"$out/set/friction.csv"
"$lmcal" calibrate "$out/set" -o "$out/fit" >/dev/null
grep -q '<img src=x onerror=alert(1)>' "$out/fit/friction_samples.csv" || { echo "FAIL: the name did not reach the samples CSV"; exit 1; }
bash "$root/tests/report_render_test.sh" "$out/fit/report.html" 20
# The names escaped in the SVG (it parses; every plot titled, with its ticks, inside its box) and
# shown as text in the hover tooltips.
python3 "$root/tests/report_svg_test.py" "$out/fit/report.html"
python3 "$root/tests/report_hover_test.py" "$out/fit/report.html"
