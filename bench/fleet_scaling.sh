#!/usr/bin/env bash
# How lmcal fleet scales: a generated fleet of 40 sets (40 units, each a friction log of 640
# samples and 3 thermal runs of 2 h) calibrated from scratch with --jobs 1 and 2 and, when
# lmcal was built with MPI, mpirun -np 1, 2 and 3 (mpirun binds each rank to a core); wall
# time, sets per second, the speed-up over one worker on one core, and the largest resident
# memory of one process (GNU time when present: the launcher's own for mpirun).
# Usage: bench/fleet_scaling.sh [LMCAL] [UNITS]   (defaults: build/lmcal, 40)
set -euo pipefail
LMCAL=${1:-build/lmcal}
UNITS=${2:-40}
LMCAL=$(cd "$(dirname "$LMCAL")" && pwd)/$(basename "$LMCAL")
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cd "$work"
"$LMCAL" generate fleet -o fleet --units "$UNITS" --dated-units 0 >/dev/null

mpi_flags=(--oversubscribe)
[[ $(id -u) -eq 0 ]] && mpi_flags+=(--allow-run-as-root)
base=""
measure() {  # measure LABEL COMMAND...
  local label=$1; shift
  rm -rf out
  local start end rss=""
  start=$(date +%s.%N)
  if [[ -x /usr/bin/time ]]; then
    /usr/bin/time -f "%M" -o rss.txt "$@" -o out >/dev/null 2>&1
    rss=$(tail -1 rss.txt)
  else
    "$@" -o out >/dev/null 2>&1
  fi
  end=$(date +%s.%N)
  local seconds
  seconds=$(awk -v a="$start" -v b="$end" 'BEGIN { print b - a }')
  [[ -z "$base" ]] && base=$seconds
  awk -v l="$label" -v s="$seconds" -v n="$UNITS" -v b="$base" -v r="${rss:+max RSS $rss kB (one process)}" \
    'BEGIN { printf "%-22s %7.2f s  %6.2f sets/s  speed-up %4.2f  %s\n", l, s, n / s, b / s, r }'
}
echo "lmcal fleet, $UNITS sets, $(nproc) cores"
# The baseline is one worker on one core: a set's own OpenMP loops on one thread, as every
# worker runs them when there are several.
measure "--jobs 1, 1 thread" env OMP_NUM_THREADS=1 "$LMCAL" fleet fleet --jobs 1
measure "--jobs 1" "$LMCAL" fleet fleet --jobs 1
measure "--jobs 2" "$LMCAL" fleet fleet --jobs 2
if command -v mpirun >/dev/null && ldd "$LMCAL" | grep -q libmpi; then
  for np in 1 2 3; do measure "mpirun -np $np" mpirun "${mpi_flags[@]}" -np $np "$LMCAL" fleet fleet; done
fi
