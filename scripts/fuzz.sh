#!/usr/bin/env bash
# Coverage-guided fuzzing of lmcal's readers (fuzz/, libFuzzer with ASan and UBSan). Builds the
# harnesses with clang into build-fuzz/ when needed, replays every saved reproducer of
# fuzz/regressions/<harness>/, then runs each harness SECONDS seconds on a fresh working copy of
# its seeds (fuzz/corpus/<harness>, committed small; the grown corpus stays in the build folder) with
# its format's dictionary. Prints executions and coverage per harness; fails on any crash,
# sanitizer report, timeout or broken property ("lmcal fuzz finding: ..."), leaving the input
# that did it in <build folder>/artifacts/<harness>/. A finding that is known and not fixed yet is
# listed in fuzz/regressions/OPEN: its reproducer's failure, and a fuzzing failure of its
# harness that prints the same text, are reported but do not fail the run.
# Usage: scripts/fuzz.sh SECONDS [HARNESS...]   (default: every harness; FUZZ_JOBS at once, default one per core)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:?usage: scripts/fuzz.sh SECONDS [HARNESS...]}
shift
all=(friction_csv thermal_csv friction_manifest thermal_manifest catalog fit_json model_file duty fleet_toml)
harnesses=("${@:-${all[@]}}")

# The build folder: build-fuzz/ by default; LMCAL_FUZZ_BUILD=build-asan reuses the sanitizer
# suite's build (scripts/sanitize.sh configures it with the fuzzers: one library build for both).
build=${LMCAL_FUZZ_BUILD:-build-fuzz}
bash scripts/install-deps.sh
if [[ ! -f $build/CMakeCache.txt ]]; then
  CC=clang-16 CXX=clang++-16 cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Release -DLMCAL_FUZZ=ON -DLMCAL_BUILD_TESTS=OFF \
    -DLMCAL_BUILD_BENCHMARKS=OFF -DLMCAL_PYTHON=OFF -DLMCAL_MPI=OFF >/dev/null
fi
if ! cmake --build "$build" -j"${FUZZ_BUILD_JOBS:-$(nproc)}" --target "${harnesses[@]/#/fuzz_}" >"$build"/fuzz-build.log 2>&1; then
  tail -30 "$build"/fuzz-build.log >&2
  exit 1
fi

# Per format: the dictionary and the largest input (the biggest seed fits; more only slows).
declare -A dict=([friction_csv]=csv [thermal_csv]=csv [friction_manifest]=toml [thermal_manifest]=toml
                 [catalog]=toml [fit_json]=json [model_file]=toml [duty]=toml [fleet_toml]=toml)
declare -A max_len=([friction_csv]=8192 [thermal_csv]=8192 [friction_manifest]=4096 [thermal_manifest]=4096
                    [catalog]=4096 [fit_json]=8192 [model_file]=8192 [duty]=4096 [fleet_toml]=2048)
source scripts/sanitizer-env.sh

# fuzz/regressions/OPEN: "<harness>/<file> | <text its failure prints>" per line.
open_entry() { awk -F' [|] ' -v want="$1" '$1 == want { print $2 }' fuzz/regressions/OPEN; }
open_texts() { awk -F' [|] ' -v h="$1/" 'index($1, h) == 1 { print $2 }' fuzz/regressions/OPEN; }
finding_lines() { grep -m3 -E 'lmcal fuzz finding|ERROR: |runtime error|SUMMARY' "$1" || tail -20 "$1"; }

failed=()
for h in "${harnesses[@]}"; do
  for input in fuzz/regressions/"$h"/*; do
    [[ -f "$input" ]] || continue
    known=$(open_entry "${input#fuzz/regressions/}")
    if "$build"/fuzz/fuzz_"$h" "$input" >"$build"/replay.log 2>&1; then
      [[ -z "$known" ]] || echo "fuzz $h: $input passes now: remove its line from fuzz/regressions/OPEN"
    elif [[ -n "$known" ]] && grep -qF -- "$known" "$build"/replay.log; then
      echo "fuzz $h: open finding, not fixed yet: $input ($known)"
    else
      echo "fuzz $h: regression $input fails:" >&2
      finding_lines "$build"/replay.log >&2
      failed+=("$h: $input")
    fi
  done
done

# Fuzz each harness for SECONDS, FUZZ_JOBS at once (default: one per core); then report them in
# order. A harness's exit status is kept in its folder.
fuzz_one() {  # fuzz_one HARNESS
  local h=$1 work=$build/corpus/$1 artifacts=$build/artifacts/$1/ status=0
  rm -rf "$work" "$artifacts"
  mkdir -p "$work" "$artifacts"
  cp fuzz/corpus/"$h"/* "$work"/
  "$build"/fuzz/fuzz_"$h" "$work" -dict=fuzz/dict/"${dict[$h]}".dict -max_len="${max_len[$h]}" \
    -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -artifact_prefix="$artifacts" -print_final_stats=1 \
    >"$build"/fuzz_"$h".log 2>&1 || status=$?
  echo "$status" >"$build"/fuzz_"$h".status
}
parallel=${FUZZ_JOBS:-$(nproc)}
for h in "${harnesses[@]}"; do
  rm -f "$build"/fuzz_"$h".status
  while (($(jobs -rp | wc -l) >= parallel)); do wait -n || true; done
  fuzz_one "$h" &
done
wait

for h in "${harnesses[@]}"; do
  artifacts=$build/artifacts/$h/
  log=$build/fuzz_$h.log
  status=$(cat "$build"/fuzz_"$h".status 2>/dev/null || echo "no status (the harness's setup failed)")
  # libFuzzer's last status line: "#<executions> DONE cov: <edges> ft: <features> corp: <inputs>/<bytes> ...".
  last=$(grep -E '^#[0-9]+' "$log" | tail -1 || true)
  execs=$(grep -oE 'stat::number_of_executed_units: *[0-9]+' "$log" | grep -oE '[0-9]+$' || echo "${last%%[[:space:]]*}")
  cov=$(grep -oE 'cov: [0-9]+ ft: [0-9]+ corp: [0-9]+' <<<"$last" || echo "cov: ? ft: ? corp: ?")
  echo "fuzz $h: ${execs#\#} executions in ${seconds} s, $cov"
  if [[ $status != 0 ]]; then
    known=$(open_texts "$h" | grep -F -f - "$log" | head -1 || true)
    if [[ -n "$known" ]]; then
      echo "fuzz $h: stopped on an open finding (fuzz/regressions/OPEN), not counted: $known"
    else
      echo "fuzz $h: FAILED (exit $status); input in $artifacts, log $log:" >&2
      finding_lines "$log" >&2
      failed+=("$h")
    fi
  fi
done

if ((${#failed[@]})); then
  echo "fuzz: ${#failed[@]} failed: ${failed[*]}" >&2
  exit 1
fi
echo "fuzz: ${#harnesses[@]} harnesses ran clean for ${seconds} s each"
