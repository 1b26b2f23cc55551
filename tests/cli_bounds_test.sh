#!/usr/bin/env bash
# End-to-end checks of the lmcal command line at the edges of what it accepts: every number that
# leaves is finite, or the command exits 1 with a message, at the extremes of each accepted range
# (docs/formats.md#limits); a model or a fit JSON of another guide, layout or major version is
# refused. Split from cli_test.sh so that ctest runs the two side by side (under the sanitizers,
# where each command is about 15 times slower, each half takes minutes). $LMCAL is the binary.
set -uo pipefail
SOURCE=$(cd "$(dirname "$0")/.." && pwd)
source "$SOURCE/tests/support/checks.sh"
unset COLUMNS

# --- finite or refused: every number that leaves is finite, or the command exits 1 ---------------
# Every number in every file given is finite: JSON without null, NaN or Infinity (lmcal writes a
# non-finite double as null; "options" records the command line as given, null for an option
# left out), CSV without a nan or inf cell.
all_finite() {  # all_finite FILE...
  python3 - "$@" <<'EOF_FINITE'
import csv, json, math, sys
def walk(x, where):
    if x is None: sys.exit(f"{where}: null")
    if isinstance(x, float) and not math.isfinite(x): sys.exit(f"{where}: {x}")
    if isinstance(x, dict): [walk(v, f"{where}.{k}") for k, v in x.items() if k != "options"]
    if isinstance(x, list): [walk(v, f"{where}[{i}]") for i, v in enumerate(x)]
for name in sys.argv[1:]:
    if name.endswith(".json"):
        walk(json.load(open(name), parse_constant=lambda c: float(c)), name)
        continue
    for r, row in enumerate(csv.reader(open(name))):
        for cell in row:
            try: v = float(cell)
            except ValueError: continue
            if not math.isfinite(v): sys.exit(f"{name}:{r + 1}: {cell}")
EOF_FINITE
}
# finite_or_refused NAME OUTPUTS -- ARGS...: exit 0 with every number of OUTPUTS finite, or exit 1
# with a message (never a silent NaN, never another exit status).
finite_or_refused() {
  local name=$1; shift
  local outputs=()
  while [[ $1 != -- ]]; do outputs+=("$1"); shift; done
  shift
  rm -rf bound; mkdir bound
  "$LMCAL" "$@" >bound/stdout.txt 2>bound/stderr.txt
  local rc=$?
  if [[ $rc -eq 1 ]]; then grep -q 'lmcal: error:' bound/stderr.txt || { echo "  $name: exit 1 without a message"; return 1; }; return 0; fi
  [[ $rc -eq 0 ]] || { echo "  $name: exit $rc: $(cat bound/stderr.txt)"; return 1; }
  grep -qi 'nan\b' bound/stdout.txt && { echo "  $name: NaN on stdout: $(cat bound/stdout.txt)"; return 1; }
  all_finite "${outputs[@]}" || { echo "  $name: not finite"; return 1; }
}
MODEL="$SOURCE/fits/cheng2017/model.toml"
# The extremes of each accepted range (docs/formats.md#limits): speed 0 and 20 m/s, load 0 and
# 1e7 N, the temperatures -273.15 and 1000 °C, the viscosity 1e-3 and 1e6 mm²/s, a stroke of
# 5e-324 m and the longest the rail takes.
for args in "--velocity 0" "--velocity 20" "--load 0" "--load 1e7" "--temperature -273.15" "--temperature 1000" \
            "--viscosity40 1e-3" "--viscosity40 1e6" "--preload 0" "--preload 1000" "--block-length 1e5"; do
  check "simulate friction $args: finite or refused" \
    finite_or_refused "friction $args" bound/f.csv bound/f.csv.json -- simulate friction -o bound/f.csv $args
  check "simulate friction --model $args: finite or refused" \
    finite_or_refused "friction --model $args" bound/f.csv bound/f.csv.json -- simulate friction --model "$MODEL" -o bound/f.csv $args
done
for args in "--velocity 0" "--velocity 20" "--velocity 3" "--load 0" "--load 1e7" "--stroke 5e-324" "--stroke 0.5" "--source moving --stroke 1e-9" \
            "--heat-rate 0" "--heat-rate 1e6" "--h 1e5" "--ambient -273.15" "--ambient 1000" "--alpha 0" "--alpha 1"; do
  for model in "" "--model $MODEL"; do
    [[ -n $model && ( $args == --h* || $args == --alpha* ) ]] && continue  # the model's own
    check "simulate thermal $model $args: finite or refused" \
      finite_or_refused "thermal $args" bound/t_time.csv bound/t_profile.csv bound/t.json -- \
      simulate thermal $model -o bound/t --duration 3600 --output-every 600 $args
  done
done
for segment in "velocity_m_s = 0" "velocity_m_s = 20" "velocity_m_s = 3" "load_N = 0" "load_N = 1e7" "stroke_m = 5e-324" \
               "viscosity40_mm2_s = 1e-3" "viscosity40_mm2_s = 1e6" "preload_um = 0" "block_length_mm = 1e5"; do
  printf 'guide = "SRN 35C"\nrail_length_m = 0.6\nambient_C = 24\nload_N = 3000\npreload_um = 4\nstroke_m = 0.2\n' >bound.toml
  printf '[[segment]]\nduration_h = 1\n%s\n' "$segment" >>bound.toml
  [[ $segment == velocity* ]] || echo 'velocity_m_s = 0.11' >>bound.toml
  check "predict with $segment: finite or refused" \
    finite_or_refused "predict $segment" bound/p/prediction.json bound/p/prediction_time.csv -- \
    predict "$MODEL" bound.toml -o bound/p --samples 20
done
check "simulate friction refuses a speed beyond a rig's" \
  refused "velocity_m_s = 1e+308 is invalid: expected a value in [0, 20]" simulate friction -o out/f.csv --velocity 1e308
check "simulate thermal refuses a speed beyond a rig's" \
  refused "--velocity = 1e+308 is invalid: expected a value in [0, 20]" simulate thermal -o out/t --velocity 1e308
printf 'guide = "SRN 35C"\nrail_length_m = 0.6\nambient_C = 24\nload_N = 3000\npreload_um = 4\nstroke_m = 0.2\n[[segment]]\nduration_h = 1\nvelocity_m_s = 3\n' >fast.toml
check "a duty whose heat runs away is refused at its segment" \
  refused "fast.toml:7:1: segment 1 (velocity_m_s = 3, load_N = 3000" predict "$MODEL" fast.toml -o out/p --samples 20
sed 's/velocity_m_s = 3/velocity_m_s = 0.11\nviscosity40_mm2_s = 1e-3/' fast.toml >thin.toml
check "a duty whose oil thins the heat into a runaway is refused" \
  refused "drives the rail to" predict "$MODEL" thin.toml -o out/p --samples 20
sed 's/stroke_m = 0.2/stroke_m = 5e-324/; s/velocity_m_s = 3/velocity_m_s = 0.11/' fast.toml >still.toml
"$LMCAL" predict "$MODEL" still.toml -o still --samples 20 >still.txt
check "a stroke of 5e-324 m predicts the block standing on one spot, finite" all_finite still/prediction.json still/prediction_time.csv
# A model of another guide, and a fit JSON of another layout or major version.
sed 's/^guide = "SRN 35C"/guide = "SRG 25C"/' "$MODEL" >srg.toml
check "a duty on another guide than the model's is refused" \
  refused 'guide: the duty runs on "SRN 35C" but the model was calibrated on "SRG 25C"' \
  predict srg.toml "$SOURCE/examples/duty/two_shifts.toml" -o out/p --samples 20
"$LMCAL" predict srg.toml "$SOURCE/examples/duty/two_shifts.toml" -o srg --samples 20 --any-guide >/dev/null
check "--any-guide predicts it, noted in the outputs" \
  grep -q 'calibrated on \\"SRG 25C\\", the duty runs on \\"SRN 35C\\" (--any-guide)' srg/prediction.json
python3 -c 'import json,sys; d = json.load(open(sys.argv[1])); d["schema_version"] = 99; json.dump(d, open("schema99.json", "w"))' \
  "$SOURCE/fits/cheng2017/friction.json"
check "a fit JSON of another layout is refused by --friction, naming the field" \
  refused "schema99.json: field schema_version: 99: written in another layout" \
  fit thermal "$SOURCE/measurements/cheng2017/thermal.toml" --friction schema99.json -o out
python3 -c 'import json,sys; d = json.load(open(sys.argv[1])); d["lmcal_version"] = "1.0.0"; json.dump(d, open("v1.json", "w"))' \
  "$SOURCE/fits/cheng2017/friction.json"
check "a fit JSON of another major version is refused by --friction" \
  refused 'v1.json: field lmcal_version: "1.0.0": written by another major version' \
  fit thermal "$SOURCE/measurements/cheng2017/thermal.toml" --friction v1.json -o out

finish cli_bounds_test.sh
