#!/usr/bin/env bash
# The bundled set's report (fits/cheng2017/report.html; calibration_test checks a fresh run
# reproduces it) in a real browser, headless Chromium: it loads without script errors and
# every plot the page lists draws with a size, no text is drawn outside its plot, every
# axis that should name runs or units shows the names, no tick labels overlap, every plot has a
# title and two tick labels on each axis (the page's own check, read from the DOM); no markup
# from the data (run names) became elements.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
report="${1:-$root/fits/cheng2017/report.html}"  # or the report given
min_plots="${2:-30}"  # the whole story of a calibration; a fleet's page has fewer
browser=$(command -v chromium || command -v chromium-browser || true)
fail() { echo "FAIL: $*"; exit 1; }
[[ -n "$browser" ]] || fail "chromium is not installed (scripts/install-deps.sh installs it)"
[[ -f "$report" ]] || fail "$report is missing (scripts/run.sh writes it)"
report=$(realpath "$report")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

"$browser" --headless --no-sandbox --disable-gpu --disable-dev-shm-usage --no-first-run --user-data-dir="$tmp/profile" \
  --enable-logging=stderr --v=0 --virtual-time-budget=10000 --dump-dom "file://$report" >"$tmp/dom.html" 2>"$tmp/browser.log" ||
  fail "chromium could not load the report: $(tail -3 "$tmp/browser.log")"

listed=$(grep -o 'data-plots="[^"]*"' "$tmp/dom.html" | head -1 | sed 's/data-plots="//; s/"$//')
count=$(wc -w <<<"$listed")
[[ "$count" -ge "$min_plots" ]] || fail "the page lists $count plots; expected $min_plots or more"
rendered=$(grep -o 'data-rendered="[^"]*"' "$tmp/dom.html" | head -1 || true)
[[ "$rendered" == "data-rendered=\"all $count\"" ]] || fail "not every plot drew: ${rendered:-the check in the page did not run}"
for id in $listed; do
  grep -q "data-plot=\"$id\"" "$tmp/dom.html" || fail "plot $id is not in the rendered page"
done
if grep -q 'data-errors=' "$tmp/dom.html"; then fail "script errors: $(grep -o 'data-errors="[^"]*"' "$tmp/dom.html")"; fi
# What only the browser's fonts can tell (the page's own check): no text outside its plot, every
# axis that should name its runs or units names them, no x or y tick labels running into each
# other, every plot with data titled and with two tick labels on each axis.
grep -q 'data-rendered=' "$tmp/dom.html" || fail "the page's check did not run"
for what in clipped unnamed overlap lacking; do
  if grep -q "data-$what=" "$tmp/dom.html"; then fail "$what: $(grep -o "data-$what=\"[^\"]*\"" "$tmp/dom.html" | head -c 600)"; fi
done
if grep -E 'CONSOLE|Uncaught|Failed to load resource' "$tmp/browser.log"; then fail "the browser reported errors (above)"; fi
# Nothing from the data became markup (the page's check, from the DOM): its one script, no
# element with an event handler, no image or frame (names such as <img src=x onerror=...> show
# as text).
if grep -q 'data-injected=' "$tmp/dom.html"; then fail "markup from the data: $(grep -o 'data-injected="[^"]*"' "$tmp/dom.html")"; fi
echo "ok: the report loads, all $count plots draw titled with their ticks, no text is clipped and every named axis shows its names"
