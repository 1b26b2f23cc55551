#!/usr/bin/env bash
# End-to-end checks of the lmcal command line: outputs that pandas-style readers
# can parse, numbers that match the physics, and bad input refused with a clear
# message, a non-zero exit and no output written. $LMCAL is the binary.
set -uo pipefail
SOURCE=$(cd "$(dirname "$0")/.." && pwd)
DATA="$SOURCE/tests/data"
source "$SOURCE/tests/support/checks.sh"
unset COLUMNS  # stdout as a pipe gets it: unwrapped (the checks that wrap set it themselves)

# The value of column NAME (found by its header) in the rows where column KEY equals VALUE.
column_where() {  # column_where FILE NAME KEY VALUE
  awk -F, -v name="$2" -v key="$3" -v value="$4" \
    'NR == 1 { for (i = 1; i <= NF; ++i) col[$i] = i; next } $col[key] == value { print $col[name] }' "$1"
}

# --- friction sweep: the sanity figure of PHYSICS.md at V = 0.11 m/s -------------------------
"$LMCAL" simulate friction -o f.csv --velocity 0.066,0.083,0.11 >/dev/null
check "friction csv written" test -s f.csv -a -s f.csv.json
check "friction csv has a header and 3 rows" test "$(wc -l < f.csv)" -eq 4
f110=$(column_where f.csv friction_N velocity_m_s 0.11)
check "F(0.11 m/s) = 44.2 N" awk -v f="$f110" 'BEGIN { exit !(f > 44.15 && f < 44.25) }'
check "the published law has no effects" test "$(column_where f.csv effects_N velocity_m_s 0.11)" = 0
check "inputs recorded" grep -q '"k1": 0.315' f.csv.json

# --- thermal run: CSVs with the declared columns, and the steady state above the run's end ----
"$LMCAL" simulate thermal -o t --velocity 0.11 --duration 7200 --output-every 600 >/dev/null
check "thermal outputs written" test -s t_time.csv -a -s t_profile.csv -a -s t.json
check "time csv rows: 13 times x 3 sensors" test "$(wc -l < t_time.csv)" -eq 40
check "time csv header" grep -q '^case,guide,velocity_m_s,load_N,preload_um,block_length_mm,contact_length_mm,stroke_m,heat_rate_W,time_s,sensor_x_m,temperature_C$' t_time.csv
check "rail warms at the centre" awk -F, 'NR > 1 && $11 == 0 {if (first == "") first = $12; last = $12} END { exit !(last > first + 1) }' t_time.csv
check "steady state hotter than after 2 h" awk -F, '$10 == "end_of_run" && $11 == 0 {e = $12} $10 == "steady_state" && $11 == 0 {s = $12} END { exit !(s > e) }' t_profile.csv

"$LMCAL" simulate thermal -o stop --velocity 0.11 --duration 21600 --stop 14400 --output-every 3600 >/dev/null
check "a block that stops: the rail warms, then cools" awk -F, 'NR > 1 && $11 == 0 { T[$10] = $12 }
  END { exit !(T[14400] > T[10800] && T[18000] < T[14400] - 3 && T[21600] < T[18000]) }' stop_time.csv
check "and no heat after the stop" awk -F, 'NR > 1 && $10 > 14400 && $9 != 0 { bad = 1 } END { exit bad }' stop_time.csv

# --- refusals ----------------------------------------------------------------------------------
check "alpha outside [0, 1]" refused "--alpha = 1.5" simulate thermal -o out/t --alpha 1.5
check "NaN alpha" refused "--alpha = nan" simulate thermal -o out/t --alpha nan
check "zero segments" refused "--segments = 0" simulate thermal -o out/t --segments 0
check "negative step" refused "--dt = -1" simulate thermal -o out/t --dt -1
check "a stop after the run's end" refused "--stop = 99999" simulate thermal -o out/t --stop 99999
check "negative rail length" refused "--rail-length = -0.5" simulate thermal -o out/t --rail-length -0.5
check "rail shorter than stroke + block" refused "rail_length_m = 0.25" simulate thermal -o out/t --rail-length 0.25
check "negative load" refused "load_N = -10" simulate friction -o out/f.csv --load -10
check "not a number in a list" refused "'fast' is not a number" simulate friction -o out/f.csv --velocity 0.1,fast
check "unknown guide" refused "unknown model 'SRN 99'" simulate friction -o out/f.csv --guide "SRN 99"
check "material missing in the catalog" refused "conductivity_W_mK: the catalog (<built-in>) has no value for guide SRG 25C; add conductivity_W_mK" \
  simulate thermal -o out/t --guide "SRG 25C"
check "unknown source model" refused "unknown source model 'uniform'" simulate thermal -o out/t --source uniform
check "unknown catalog field" refused "unknown guide field" simulate thermal -o out/t --set colour_mm=3

# --- virtual rig, loaders and the bundled data set ---------------------------------------------
"$LMCAL" generate friction -o rig --runs 2 --guides "SRN 35C" --effect seal_drag=100 >/dev/null
check "generated friction log and truth" test -s rig/friction.csv -a -s rig/friction_truth.json
check "generated log says it is synthetic" grep -q '^# SYNTHETIC' rig/friction.csv
check "truth names the effect" grep -q '"seal_drag"' rig/friction_truth.json
"$LMCAL" check friction rig/friction.csv > check.txt
check "check reads the generated log" grep -q 'friction log: .* samples, 2 runs, 1 guide$' check.txt
"$LMCAL" generate thermal -o rig --velocity 0.11 --duration 1200 --record-every 10 >/dev/null
"$LMCAL" check thermal rig/thermal.toml > check.txt
check "check reads the generated manifest" grep -q "thermal data set 'synthetic': 1 run$" check.txt
"$LMCAL" resample rig/thermal/v110.csv -o coarse.csv --every 12 >/dev/null
check "resample keeps every 12th record" test "$(grep -vc '^#' coarse.csv)" -eq 12
check "unknown effect" refused "unknown effect 'warp'" generate friction -o out --effect warp=1
check "a speed listed twice is refused" refused "each speed once" generate thermal --velocity 0.066,0.11,0.11 -o dupspeed
check "and nothing of it is written" test ! -e dupspeed
check "bad log refused by check" refused "friction_semicolon.csv:" check friction "$DATA/bad/friction_semicolon.csv"

# --- friction fit ------------------------------------------------------------------------------
"$LMCAL" generate friction -o fitdata --runs 3 --guides "SRN 35C" --run-offset 0 >/dev/null
"$LMCAL" fit friction fitdata/friction.csv -o fitout --name f > fit.txt
check "fit writes json, samples and conditions" test -s fitout/f.json -a -s fitout/f_samples.csv -a -s fitout/f_conditions.csv
check "fit json records the input hash" grep -q '"sha256": "[0-9a-f]\{64\}"' fitout/f.json
check "fit summary shows all seven constants" test "$(grep -cE '^  (k1|k2|mu_st|v_st_m_s|mu_v|beta_per_K|f0) +-?[0-9][0-9.e+-]* +[0-9]' fit.txt)" -eq 7
check "fit summary reports the spread across runs" grep -q 'spread across 3 runs' fit.txt
check "the spread table carries each constant's unit, and p never 0" \
  bash -c "grep -qE '^  k2 +1/um +mean' fit.txt && ! grep -qE ' p 0( |$)' fit.txt"
check "fit summary's table has a unit column: f0 in N/mm" grep -qE '^  f0 +[-0-9.e]+ +[0-9.e-]+  N/mm ' fit.txt
check "a clean log's fit does not say the law misses structure" bash -c "! grep -q 'misses structure' fit.txt"
"$LMCAL" generate friction -o drag_fit --runs 3 --guides "SRN 35C" --effect seal_drag=100 >/dev/null
"$LMCAL" fit friction drag_fit/friction.csv -o fitout --name dragfit > fitdrag.txt
check "a fit that misses a seal drag says so and names the commands that look further" \
  grep -q 'warning: the law misses structure: .*lmcal diagnose friction.*lmcal calibrate' fitdrag.txt
check "and its JSON carries the same warning" grep -q '"the law misses structure: ' fitout/dragfit.json
"$LMCAL" generate friction -o onepc --runs 2 --guides "SRN 35C" --preload 4 >/dev/null
"$LMCAL" fit friction onepc/friction.csv -o fitout --name onepc > fit.txt
check "one preload class: k1/k2 named unidentifiable" grep -q 'NOT IDENTIFIABLE: one preload class' fit.txt
check "unknown constant refused" refused "unknown constant 'k3'" fit friction fitdata/friction.csv -o out --fix k3=1
check "bad loss refused" refused "unknown loss 'l1'" fit friction fitdata/friction.csv -o out --loss l1
check "by default the run offsets are random, chosen automatically" grep -q '"model": "random (.*); chosen automatically"' fitout/f.json
check "by default the law sees each block's mean logged temperature" grep -q '"temperature": "block-mean"' fitout/f.json
check "a robust loss turns the automatic run offsets off" bash -c '"$0" fit friction fitdata/friction.csv -o fitout --name huber --loss huber >/dev/null &&
  grep -q "\"model\": \"none; chosen automatically\"" fitout/huber.json' "$LMCAL"
check "an unknown law temperature is refused" refused "--law-temperature: unknown choice 'nominal'" fit friction fitdata/friction.csv -o out --law-temperature nominal

# --- friction diagnosis ------------------------------------------------------------------------
"$LMCAL" generate friction -o drag --runs 3 --guides "SRN 35C" --effect seal_drag=100 >/dev/null
"$LMCAL" diagnose friction drag/friction.csv -o fitout --name d > diag.txt
check "diagnosis names the hidden seal drag" grep -q 'The published law misses: seal_drag' diag.txt
check "diagnosis writes its json" grep -q '"verdict": "explained"' fitout/d.json
check "diagnosis needs three runs" refused "at least 3 runs" diagnose friction onepc/friction.csv --name x -o out
"$LMCAL" diagnose friction drag/friction.csv -o fitout --name dfix --fix f0=0.029 --run-offsets random >diagfix.txt
check "a diagnosis holds what it is told to, and never reports it as moving" awk '
  /"estimated_in_both"/ { both = $2 } /"parameter": "f0"/ { found = 1; ok = (both == "false,") }
  END { exit !(found && ok) }' fitout/dfix.json
check "the held f0 is not among the parameters that move" bash -c "! grep -q 'move: .*f0 ' diagfix.txt"
check "a diagnosis records the options it ran with, given and default" python3 -c '
import json; o = json.load(open("fitout/dfix.json"))["options"]
assert o["fix"] == "f0=0.029" and o["run-offsets"] == "random" and o["min-gain"] is not None and o["catalog"] is None, o'
check "diagnosis prints its lack-of-fit test" grep -q '^lack of fit' diagfix.txt
# Issue 41 #5: every estimate with its unit, and no 'nan' without its reason: a candidate the
# data do not identify (the drive log) or whose fit failed (the rig's heater schedule).
check "diagnosis gives each candidate's estimate with its unit" grep -qE '^  seal_drag +[-0-9.e+]+ ± [0-9.e+-]+ N s2/m2 +LRT p' diag.txt
"$LMCAL" diagnose friction "$SOURCE/measurements/axis/friction.toml" -o fitout --name dax >diagaxis.txt 2>&1
"$LMCAL" diagnose thermal "$SOURCE/measurements/rig/thermal.toml" -o fitout --name drig >diagrig.txt 2>&1
check "a candidate the data do not identify says so, no nan" \
  bash -c "grep -q '± n/a (not identified) *LRT p n/a' diagaxis.txt && ! grep -qiw nan diagaxis.txt"
check "a candidate whose fit failed says so, no nan or inf" \
  bash -c "grep -q 'n/a (the fit failed) *LRT p n/a *held-out n/a' diagrig.txt && ! grep -qiwE 'nan|inf' diagrig.txt"
check "diagnosis refuses an unknown run-offset model" refused "unknown model 'sometimes'" diagnose friction drag/friction.csv -o out --run-offsets sometimes
# Beyond the library: running-in (not a library effect) learned as an empirical term, carried by
# the calibrated model and applied (settled) by simulate friction.
"$LMCAL" generate friction -o runin --runs 4 --guides "SRN 35C" --effect running_in=0.1 --effect running_in_scale_m=100 >/dev/null
"$LMCAL" diagnose friction runin/friction.csv -o fitout --name din > diagin.txt
check "an effect outside the library is learned as an empirical term" grep -q '^verdict: unexplained — empirical term found' diagin.txt
check "the term is printed with its scale" grep -q 'exp(-s/l1)·F_law .*term1_scale = ' diagin.txt
check "the diagnosis json holds the term" grep -q '"form": "sparse"' fitout/din.json
"$LMCAL" calibrate runin -o calin >/dev/null 2>&1
check "the calibrated model carries the term, marked" grep -q 'empirical: learned from the residuals, not a named cause' calin/model.toml
cp -r calin calin_again
"$LMCAL" calibrate runin -o calin_again --no-diagnosis >/dev/null 2>&1
check "a run without diagnosis leaves no earlier run's diagnosis beside its outputs" bash -c \
  'test -s calin_again/calibration.json && test ! -e calin_again/friction_diagnosis.json && test -z "$(find calin_again -name ".*")"'
"$LMCAL" simulate friction --model calin/model.toml --temperature 26,60 -o simin.csv > simin.txt
check "simulate friction adds the term's columns" grep -q 'empirical_N,extrapolated,friction_N' simin.csv
# An input correction (the law at T - 2 K above 35 C) learned, carried and applied: the law at the
# corrected temperature above the step, the law as logged below it.
"$LMCAL" generate friction -o hot --runs 4 --guides "SRN 35C" --effect hot_offset_K=-2 --shuffle-runs >/dev/null
check "--shuffle-runs is recorded in the truth" grep -q '"shuffle_runs": true' hot/friction_truth.json
"$LMCAL" calibrate hot -o calhot > calhot.txt 2>&1
check "the law seeing another temperature above a step is learned" grep -q 'F_law(T + c1·\[T > 3[5-9]' calhot.txt
"$LMCAL" simulate friction --model calhot/model.toml --temperature 30,40 -o simhot.csv >/dev/null
check "the input correction applies above its step only" awk -F, 'NR > 1 { if ($6 == 30) { n30++; if ($13 != 0) bad = 1 } if ($6 == 40) { n40++; if ($13 == 0) bad = 1 } } END { exit bad || !n30 || !n40 }' simhot.csv

# --- thermal fit -------------------------------------------------------------------------------
"$LMCAL" generate thermal -o thermaldata --velocity 0.083,0.11 --duration 7200 --record-every 30 >/dev/null
"$LMCAL" fit thermal thermaldata/thermal.toml --friction fitout/f.json -o fitout --name t > thermal.txt
check "thermal fit writes json, samples and the alpha curve" test -s fitout/t.json -a -s fitout/t_samples.csv -a -s fitout/t_alpha_curve.csv
check "thermal fit reports alpha across runs" grep -q '^alpha across runs: ' thermal.txt
check "thermal fit compares source models" grep -q 'alpha(paper) / alpha(averaged)' thermal.txt
check "alpha curve has the runs' rows" test "$(grep -c '^v110,' fitout/t_alpha_curve.csv)" -eq 46
"$LMCAL" generate thermal -o thermal3 --velocity 0.066,0.083,0.11 --duration 5400 --record-every 60 >/dev/null
"$LMCAL" diagnose thermal thermal3/thermal.toml -o fitout --name td --fit-h --h 6 --alpha-start 0.5 >tdiag.txt
check "diagnose thermal takes what fit thermal holds and frees (h fitted: its shift is reported)" \
  grep -q '"parameter": "h_W_m2K"' fitout/td.json
check "diagnose thermal prints its lack-of-fit test" grep -q '^lack of fit' tdiag.txt
check "not a friction fit refused" refused "expected a friction fit" fit thermal thermaldata/thermal.toml --friction thermaldata/thermal_truth.json -o out
check "unknown ambient column refused" refused "no ambient column 'ambient9_C'" fit thermal thermaldata/thermal.toml --ambient ambient9_C -o out

# --- your own bar: a user catalog's [[bar]] simulated with a given heat --------------------------
cat >bars.toml <<'TOML'
[[bar]]
name = "lab bar"
area_m2 = 4e-4
perimeter_m = 0.08
contact_length_mm = 50
conductivity_W_mK = 45
density_kg_m3 = 7850
specific_heat_J_kgK = 470
TOML
check "a user catalog's bar simulates with --heat-rate" "$LMCAL" simulate thermal --catalog bars.toml --guide "lab bar" -o bar --velocity 0.1 --stroke 0.2 --rail-length 0.6 --duration 3600 --heat-rate 5
check "the bar is named in the outputs" grep -q 'lab bar' bar_time.csv
printf '[[bar]]\nname = "b"\ndensity_kg_m3 = 7.85\n' >badbar.toml
check "a non-physical catalog value refused at its line" refused "badbar.toml:3:17: density_kg_m3 = 7.85 of b is not physical" simulate thermal --catalog badbar.toml --guide b -o out/x --heat-rate 5
check "a missing catalog value says where to supply it" refused "add preload_um to its entry there" simulate thermal --catalog bars.toml --guide "lab bar" -o out/x --velocity 0.1

# --- calibrate: a measurement folder end to end -------------------------------------------------
mkdir -p calset
"$LMCAL" generate friction -o calset --runs 2 --guides "SRN 35C" >/dev/null
"$LMCAL" calibrate calset -o calout --no-diagnosis >calibrate.txt 2>calibrate.err
check "calibrate writes the fits, the summary and the report" test -s calout/friction.json -a -s calout/calibration.json -a -s calout/report.html
check "calibrate says the thermal half was skipped" grep -q 'note: no thermal manifest' calibrate.txt
check "calibrate is quiet on stderr when it is not a terminal" test ! -s calibrate.err
"$LMCAL" generate friction -o oneset --runs 1 --guides "SRN 35C" >/dev/null
"$LMCAL" generate thermal -o oneset --velocity 0.1 --repeats 1 >/dev/null
"$LMCAL" calibrate oneset -o oneout >onerun.txt 2>&1
check "a one-run set's summary says why there is no held-out RMSE, and prints no nan" \
  bash -c "grep -q '^  rail model .*: no held-out RMSE (one run: none to hold out)' onerun.txt && ! grep -qiw nan onerun.txt"
# Issue 41 #5: prose wrapped to the terminal at word boundaries (COLUMNS, or the terminal's own
# width), hanging under a label's text; nothing lost; a pipe without COLUMNS unwrapped.
COLUMNS=60 "$LMCAL" calibrate calset -o calout --no-diagnosis >wrapped60.txt 2>/dev/null
script -qec "stty cols 70 rows 50; '$LMCAL' calibrate calset -o ttyout --no-diagnosis 2>/dev/null" /dev/null | tr -d '\r' >wrapped70.txt
fits_width() {  # fits_width FILE WIDTH: no line wider, unless it is one word after its indent
  python3 - "$1" "$2" <<'PY'
import sys
lines = open(sys.argv[1], encoding="utf-8").read().splitlines()
long = [l for l in lines if len(l) > int(sys.argv[2]) and " " in l.strip()]
sys.exit(1 if long or len(lines) < 10 else 0)
PY
}
same_words() { diff <(tr -s ' \n' '\n\n' <"$1") <(tr -s ' \n' '\n\n' <"$2") >/dev/null; }
check "calibrate wraps its lines to COLUMNS" fits_width wrapped60.txt 60
check "calibrate wraps its lines to the terminal's width" fits_width wrapped70.txt 70
check "wrapping loses no word" same_words calibrate.txt wrapped60.txt
check "a pipe without COLUMNS is not wrapped" bash -c "awk 'length > 100 { n++ } END { exit !n }' calibrate.txt"
check "a wrapped line hangs under its label's text" \
  bash -c "grep -A1 '^  Friction: each of' wrapped60.txt | tail -1 | grep -qE '^ {12}[^ ]'"
check "the parameter tables carry a unit column" bash -c "grep -qE '^    parameter +value +unit +95 % interval' calibrate.txt"
check "the man page and the completion script are not wrapped" \
  bash -c "cmp -s <('$LMCAL' man) <(COLUMNS=30 '$LMCAL' man) && cmp -s <('$LMCAL' completion bash) <(COLUMNS=30 '$LMCAL' completion bash)"
# The residual plots thin their points within each level and direction: both senses are drawn
# (a plain every-nth kept one sense only, the conditions alternating direction).
both_senses() {  # both_senses REPORT PLOT-ID
  python3 - "$1" "$2" <<'PY'
import re, sys
h = open(sys.argv[1]).read()
i = h.find('id="lmcal-clip-' + sys.argv[2] + '"')
svg = h[h.rfind('<svg', 0, i):h.find('</svg>', i)]
from collections import Counter
columns = Counter(round(float(x)) for x in re.findall(r'<circle[^>]*?cx="([-0-9.]+)"', svg)).most_common(2)
sys.exit(0 if i >= 0 and len(columns) == 2 and columns[1][1] >= 10 else 1)  # the legend's marks are fewer
PY
}
script -qec "'$LMCAL' calibrate calset -o ttyout --no-diagnosis" /dev/null >tty.txt 2>&1
check "calibrate shows its steps on a terminal" grep -q '\[2/[0-9]\] friction fit' tty.txt
"$LMCAL" calibrate calset -o timed --no-diagnosis --timings >/dev/null 2>timings.txt
check "calibrate --timings gives each step's wall time and the total on stderr" \
  bash -c "grep -qE '^ +[0-9]+\.[0-9]{3} s  friction fit$' timings.txt && grep -qE '^ +[0-9]+\.[0-9]{3} s  total$' timings.txt"
check "calibrate defaults to fits/<folder name>" bash -c "cd calset && '$LMCAL' calibrate . >/dev/null && test -s fits/calset/report.html"
cat >calopts.toml <<'TOML'
[calibrate]
h = 6.5
starts = 3
TOML
"$LMCAL" --config calopts.toml calibrate calset -o calset --no-diagnosis --bootstrap 0 >/dev/null 2>&1
"$LMCAL" --config calopts.toml calibrate calset -o calset --no-diagnosis --bootstrap 0 >calagain.txt 2>&1
check "calibrate -o SET twice: its own outputs are not read as logs" grep -q 'friction_samples.csv not read: it is an output of lmcal calibrate' calagain.txt
check "calibrate options from --config reach the fits and calibration.json" grep -q '"starts": 3' calset/calibration.json
check "a folder without measurements refused" refused "expected friction logs (friction*.csv or a friction*.toml manifest) or a thermal manifest" calibrate out
check "a missing folder refused" refused "expected a measurement folder" calibrate no_such_folder -o out

# --- a log of nothing but speed and force: the law in combinations, nothing invented ------------
mkdir -p bare
awk -F, '/^#/ { next } !header++ { for (i = 1; i <= NF; ++i) col[$i] = i; print "run,velocity_m_s,friction_N"; next }
         $col["load_N"] == 3000 && $col["guide"] == "SRN 35C" && $col["preload_um"] == 4 {
           print $col["run"] "," $col["velocity_m_s"] "," $col["friction_N"] }' \
    "$SOURCE/measurements/cheng2017/friction.csv" > bare/friction.csv
"$LMCAL" check friction bare/friction.csv > bare_check.txt 2>&1
check "check says what a speed-and-force log does not give" grep -q 'note: not given: load_N, preload_um, block_length_mm, temperature_C' bare_check.txt
"$LMCAL" calibrate bare -o bare_out --no-diagnosis > bare_cal.txt 2>&1
check "calibrate quotes the combinations, not the constants" grep -q '^    viscous_N_s_m ' bare_cal.txt
check "the report lists the combinations and their spread across runs" grep -q '<td>viscous_N_s_m</td>' bare_out/report.html
check "nor any condition it was not given" bash -c '! grep -E "^ +(k1|mu_st|beta_per_K) " "$0" && ! head -1 "$1" | grep -q load_N' bare_cal.txt bare_out/friction_samples.csv
check "the report names no constant and no condition it was not given" \
  bash -c '! grep -qE "<td>(k1|mu_st|v_st_m_s|mu_v)</td>|1000 N|load \(N\)|preload \(um\)" "$0"' bare_out/report.html
check "the model file says its law holds for one setup" grep -q '^law = "combinations"' bare_out/model.toml
check "simulate refuses a combination law at other conditions" refused "fitted in combinations" simulate friction --model bare_out/model.toml -o out/f.csv --velocity 0.1
check "check counts no guide where none was named" grep -q 'samples, [0-9]* runs, no guide named$' bare_check.txt
awk -F, 'NR == 1 || $1 == "'"$(awk -F, 'NR == 2 { print $1 }' bare/friction.csv)"'"' bare/friction.csv > bare/one_run.csv
mkdir -p bare1 && mv bare/one_run.csv bare1/friction.csv
"$LMCAL" calibrate bare1 -o bare1_out --no-diagnosis > bare1_cal.txt 2>&1
check "one run: no held-out RMSE, said in words, and no NaN" \
  bash -c 'grep -q "no held-out RMSE (one run: none to hold out)" "$0" && grep -q "friction: [0-9]* samples, 1 run;" "$0" && ! grep -qi nan "$0"' bare1_cal.txt

# --- calibrate once, use everywhere: simulate with the calibrated model ------------------------
mkdir -p modelset
"$LMCAL" generate friction -o modelset --runs 2 --guides "SRN 35C" >/dev/null
"$LMCAL" generate thermal -o modelset --velocity 0.083,0.11 --duration 3600 --record-every 30 >/dev/null
"$LMCAL" calibrate modelset -o modelout --no-diagnosis >/dev/null 2>&1
check "calibrate writes the calibrated model" test -s modelout/model.toml
model_sha=$(sha256sum modelout/model.toml | cut -c1-64)
"$LMCAL" simulate friction --model modelout/model.toml -o mf.csv --velocity 0.066,0.11 --direction 1,-1 >mf.txt
check "simulate friction --model writes its outputs" test -s mf.csv -a -s mf.csv.json
check "simulate friction --model: 2 speeds x 2 directions" test "$(wc -l < mf.csv)" -eq 5
check "simulate friction --model records the model with its SHA-256" grep -q "\"sha256\": \"$model_sha\"" mf.csv.json
check "simulate friction --model records the model's provenance" grep -q '"set": "modelset"' mf.csv.json
check "simulate friction --model names the model on stdout" grep -q 'calibrated friction law of modelout/model.toml' mf.txt
"$LMCAL" simulate thermal --model modelout/model.toml -o mt --duration 3600 --output-every 600 >mt.txt
check "simulate thermal --model writes its outputs" test -s mt_time.csv -a -s mt_profile.csv -a -s mt.json
check "simulate thermal --model records the model with its SHA-256" grep -q "\"sha256\": \"$model_sha\"" mt.json
model_alpha=$(awk '/^name = "alpha"/ {a = 1} a && /^value = / {print $3; exit}' modelout/model.toml)
check "simulate thermal --model takes alpha from the model" grep -q "^  \"alpha\": $model_alpha,\$" mt.json
check "--model with a friction constant refused" refused "--k1 cannot be given with it" \
  simulate friction --model modelout/model.toml --k1 0.3 -o out/f.csv
check "--model with alpha refused" refused "--alpha cannot be given with it" \
  simulate thermal --model modelout/model.toml --alpha 0.5 -o out/t
check "a friction-only model refused by simulate thermal" refused "calout/model.toml: expected a [thermal] table" \
  simulate thermal --model calout/model.toml -o out/t
check "a bad model file refused with its line and column" refused "unknown_mechanism.toml:7:" \
  simulate thermal --model "$DATA/model/unknown_mechanism.toml" -o out/t

# A model with an effect and mechanisms: the breakdown adds up, the heat follows the rail, and
# the thermocouple lag is said to be the sensor's.
cat > mechanisms.toml <<'MODEL'
kind = "lmcal calibrated model"
set = "hand-written"

[friction]
causes = ["seal_drag"]
reference_temperature_C = 40
viscosity40_mm2_s = 99
[[friction.parameter]]
name = "k1"
value = 0.315
[[friction.parameter]]
name = "k2"
value = 0.03
[[friction.parameter]]
name = "mu_st"
value = 1.52
[[friction.parameter]]
name = "v_st_m_s"
value = 0.015
[[friction.parameter]]
name = "mu_v"
value = 0.003
[[friction.parameter]]
name = "beta_per_K"
value = 0.067
[[friction.parameter]]
name = "f0"
value = 0.029
[[friction.parameter]]
name = "seal_drag"
value = 150

[thermal]
source = "averaged"
mechanisms = ["coupling", "convection_velocity", "tc_lag"]
[[thermal.parameter]]
name = "alpha"
value = 0.6
[[thermal.parameter]]
name = "h_W_m2K"
value = 5.3
[[thermal.parameter]]
name = "coupling"
value = 1
[[thermal.parameter]]
name = "convection_velocity"
value = 6
[[thermal.parameter]]
name = "tc_lag"
value = 30
MODEL
"$LMCAL" simulate friction --model mechanisms.toml -o me.csv --velocity 0.11 >/dev/null
check "seal drag: effects_N = 150 x 0.11^2" \
  awk -v e="$(column_where me.csv effects_N velocity_m_s 0.11)" 'BEGIN { exit !(e > 1.8149 && e < 1.8151) }'
check "friction_N = the law's terms + effects_N" awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  { d = $c["coulomb_N"] + $c["stribeck_N"] + $c["viscous_N"] + $c["effects_N"] - $c["friction_N"]; exit !(d < 1e-9 && d > -1e-9) }' me.csv
check "the model's effect recorded" grep -q '"seal_drag": 150' me.csv.json
"$LMCAL" simulate thermal --model mechanisms.toml -o mm --duration 7200 --output-every 600 >mm.txt
check "simulate thermal with mechanisms writes its outputs" test -s mm_time.csv -a -s mm_profile.csv -a -s mm.json
check "the thermocouple lag is the sensor's, on stdout" grep -q "tc_lag (tau = 30 s) is a property of the thermocouples" mm.txt
check "the thermocouple lag is the sensor's, in the json" grep -q '"sensor_note": "tc_lag (tau = 30 s) is a property' mm.json
check "coupled heat rate falls while the rail warms" awk -F, 'NR > 1 && $11 == 0 {
  if (n++ && !($9 < q && $12 > t)) bad = 1; q = $9; t = $12 } END { exit bad || n < 10 }' mm_time.csv
check "with mechanisms the steady state is hotter than after 2 h" awk -F, '$10 == "end_of_run" && $11 == 0 {e = $12}
  $10 == "steady_state" && $11 == 0 {s = $12} END { exit !(s > e) }' mm_profile.csv

# --- raw load-cell logs and friction manifests --------------------------------------------------
"$LMCAL" generate friction --raw -o raw --guides "SRN 35C" --preload 1.5,4 --load 1000,3000 --temperature 22,40 \
  --velocity 0.005,0.01,0.05,0.11 --stroke 0.2 --sample-rate 100 --run-offset 0 --runs 1 --seed 3 >/dev/null
check "generate --raw writes a manifest, runs and the truth" test -s raw/friction.toml -a -s raw/friction/run08.csv -a -s raw/friction_truth.json
check "a raw run is time, position and signed force" grep -q '^time_s,position_mm,force_N$' raw/friction/run01.csv
check "the truth lists the cruises by sample" grep -q '"first_sample"' raw/friction_truth.json
"$LMCAL" check friction raw/friction.toml >raw_check.txt
check "check lists each raw run's plateaus" grep -q "run run01: .* kept in 8 plateaus; dropped .* accelerating" raw_check.txt
check "check shows a plateau's velocity" grep -qE -- "-0.11 m/s +[0-9]+ samples" raw_check.txt
"$LMCAL" check friction raw/friction.toml --force-sign opposes-motion >raw_sign.txt
check "a wrong sign convention is a warning" grep -q "looks reversed; give --force-sign follows-motion" raw_sign.txt
"$LMCAL" fit friction raw/friction.toml -o raw_fit --name raw >/dev/null
check "fit friction takes a manifest" test -s raw_fit/raw.json
check "the manifest and its runs are the fit's inputs" grep -q 'friction/run08.csv' raw_fit/raw.json
"$LMCAL" calibrate raw -o raw_cal >raw_cal.txt 2>&1
check "calibrate reads a folder's friction manifest" grep -q '"raw_friction"' raw_cal/calibration.json
check "the report plots a raw trace with its plateaus" grep -q 'data-plot="raw-trace-force"' raw_cal/report.html
# A position that goes back between reversals: refused at its cell, nothing written.
awk -F, -v OFS=, 'NR == 400 { $2 = $2 - 1 } { print }' raw/friction/run01.csv >back.csv
printf 'file = "back.csv"\n[[run]]\nid = "a"\nguide = "SRN 35C"\nload_N = 1000\npreload_um = 2.5\ntemperature_C = 24\n' >back.toml
sed -i 's/^time_s,/run,time_s,/; s/^\([0-9]\)/a,\1/' back.csv
check "a non-monotone position is refused at its line" refused "back.csv:400:" fit friction back.toml -o out
check "and says why" grep -q "position must be monotone between reversals" stderr.txt
printf 'file = "back.csv"\n[[run]]\nid = "a"\nload_N = 1000\nload_kN = 1\n' >twice.toml
check "a manifest refuses a key given twice" refused "twice.toml:5:1: duplicate key 'load_kN'" check friction twice.toml
# Files a manifest names stay inside its folder: refused at the key, nothing of the file echoed.
mkdir -p inner && cp back.csv inner/
printf 'file = "/etc/passwd"\n' >inner/passwd.toml
check "a manifest naming /etc/passwd is refused at its key" \
  refused "inner/passwd.toml:1:8: file '/etc/passwd' is outside inner" check friction inner/passwd.toml
check "and nothing of it is echoed" bash -c '! grep -q "root:" stderr.txt'
printf 'file = "../back.csv"\n[[run]]\nid = "a"\nguide = "SRN 35C"\nload_N = 1000\npreload_um = 2.5\ntemperature_C = 24\n' >inner/up.toml
check "a manifest naming ../ is refused" refused "file '../back.csv' is outside inner" fit friction inner/up.toml -o out
"$LMCAL" --allow-outside-root check friction inner/up.toml >/dev/null 2>up.txt
check "--allow-outside-root reads it (and refuses what it holds)" grep -q "back.csv:400:" up.txt
check "an output folder under a file is refused before the fit" \
  refused "-o: cannot write outputs there: " fit friction "$SOURCE/measurements/cheng2017/friction.csv" -o back.csv/out

# --- thermal runs as rigs produce them: a heater switched off, no ambient sensor, a user's bar ---
"$LMCAL" generate thermal -o heater --heater 4 --heater-off 7200 --duration 10800 --record-every 60 \
  --no-ambient-columns >/dev/null
check "a heater run gives its heat and schedule" grep -q '^heat_rate_W = 0.0$' heater/thermal.toml
check "without ambient columns the manifest gives ambient_C" grep -q '^ambient_C = 24.0$' heater/thermal.toml
check "and the run has no ambient column" grep -q '^time_s,tc1_C,tc2_C,tc3_C$' heater/thermal/heater.csv
"$LMCAL" fit thermal heater/thermal.toml -o heater_fit >/dev/null
check "a heater run fits with its given heat" grep -q '"heat_source": "given heat rate"' heater_fit/thermal.json
check "the cooling records are fitted" awk -F, 'NR == 1 { for (i = 1; i <= NF; ++i) c[$i] = i; next }
  $c["time_s"] > 7200 { n++ } END { exit !(n > 100) }' heater_fit/thermal_samples.csv
printf '[[bar]]\nname = "lab bar"\narea_m2 = 4e-4\nperimeter_m = 0.08\nconductivity_W_mK = 45\ndensity_kg_m3 = 7850\nspecific_heat_J_kgK = 470\ncontact_length_mm = 50\n' >lab.toml
sed 's/^guide = "SRN 35C"$/guide = "lab bar"/' heater/thermal.toml >heater/bar.toml
check "a bar no catalog knows is refused at its line" refused "bar.toml:7:" check thermal heater/bar.toml
check "check thermal --catalog finds the user's bar" "$LMCAL" check thermal heater/bar.toml --catalog lab.toml
printf '[[bar]]\nname = "lab bar"\narea_m2 = 4e-4\nperimeter_m = 0.08\n' >thin.toml
"$LMCAL" generate thermal -o barset --catalog lab.toml --guide "lab bar" --heater 3 --duration 3600 --record-every 60 >/dev/null
check "generate thermal makes a user's bar, its manifest naming the catalog" grep -q '^catalog = ' barset/thermal.toml
check "and the manifest's catalog is found again" "$LMCAL" check thermal barset/thermal.toml
printf '[[guide]]\nmodel = "MY 30"\nblock_length_mm = 100\n' >myguide.toml
"$LMCAL" generate friction --raw --catalog myguide.toml --guides "MY 30" --preload 2 --load 1000 --temperature 24 \
  --velocity 0.01,0.05 --runs 1 -o myraw >/dev/null
check "a raw log of the user's guide loads with its block length" "$LMCAL" check friction myraw/friction.toml
check "a bar missing its material is refused at load, naming where to add it" refused "add conductivity_W_mK to its entry there" check thermal heater/bar.toml --catalog thin.toml

# --- predict: the calibrated model over a duty cycle -------------------------------------------
"$LMCAL" predict "$SOURCE/fits/cheng2017/model.toml" "$SOURCE/examples/duty/two_shifts.toml" -o predout --samples 50 >predict.txt
check "predict writes the bands and a summary" test -s predout/prediction.json -a -s predout/prediction_time.csv
check "predict summarises the elongation with its band" grep -q 'rail elongation at the end: .* \[.*\] µm' predict.txt
check "predict gives the largest elongation with its band" grep -q 'largest [0-9.e+-]* \[[0-9.e+-]*, [0-9.e+-]*\] µm at ' predict.txt
check "predict gives each segment's end with its band" bash -c "grep -A5 'at the end of each segment' predict.txt | grep -qE '^    shift 1 +[0-9.]+ h  [0-9.e+-]+ \[[0-9.e+-]+, [0-9.e+-]+\]'"
# --dt as every other command names the time step (issue 41 #5); --time-step, its first name, still read
"$LMCAL" predict "$SOURCE/fits/cheng2017/model.toml" "$SOURCE/examples/duty/two_shifts.toml" -o predout_dt --samples 20 --dt 60 >/dev/null
"$LMCAL" predict "$SOURCE/fits/cheng2017/model.toml" "$SOURCE/examples/duty/two_shifts.toml" -o predout_ts --samples 20 --time-step 60 >/dev/null
check "predict takes --dt and --time-step alike" cmp -s predout_dt/prediction_time.csv predout_ts/prediction_time.csv
check "predict's help shows --dt, not the old --time-step" \
  bash -c "'$LMCAL' predict --help | grep -q -- '--dt FLOAT' && ! '$LMCAL' predict --help | grep -q -- '--time-step'"
check "the completion and the man page leave the old --time-step out" \
  bash -c "! '$LMCAL' completion bash | grep -q -- '--time-step' && ! '$LMCAL' man | grep -q 'time.-step'"
check "predict records the time step under --dt" python3 -c '
import json, sys
sys.exit(0 if json.load(open("predout_ts/prediction.json"))["options"]["dt"] == "60" else 1)'

check "predict records the options it ran with" python3 -c '
import json; assert json.load(open("predout/prediction.json"))["options"]["samples"] == "50"'
cat >badduty.toml <<'EOF_DUTY'
guide = "SRN 35C"
rail_length_m = 0.6
ambient_C = 24
load_N = 3000
stroke_m = 0.2
[[segment]]
duration_min = -30
velocity_m_s = 0.1
EOF_DUTY
check "a duty with a negative duration is refused, naming the field" \
  refused "badduty.toml:7:16: duration_min = -30: expected a duration > 0" predict "$SOURCE/fits/cheng2017/model.toml" badduty.toml -o predbad
check "nothing is written for a refused duty" test ! -e predbad
sed 's/^lmcal_version = "0\./lmcal_version = "7./' "$SOURCE/fits/cheng2017/model.toml" >model7.toml
check "a model file of another major version is refused" \
  refused "written by another major version of lmcal" predict model7.toml "$SOURCE/examples/duty/two_shifts.toml" -o predbad

# --- finite or refused, at the extremes of every accepted range: tests/cli_bounds_test.sh (its
# own ctest test, cli_bounds, so that the two run side by side) -----------------------------------

# --- plan: the next friction conditions to log ----------------------------------------------------
"$LMCAL" plan friction "$SOURCE/measurements/cheng2017/friction.csv" --model "$SOURCE/fits/cheng2017/model.toml" \
  --velocity 0.001,0.002,0.15,0.3 --parameters v_st_m_s,mu_st -n 3 -o planout >plan.txt
check "plan writes the plan and a friction log template to fill" test -s planout/plan.json -a -s planout/plan_friction_template.csv
check "plan says which criterion and what the SEs become" grep -q 'A-optimal for v_st_m_s, mu_st' plan.txt
check "plan records the options it ran with" python3 -c '
import json; o = json.load(open("planout/plan.json"))["options"]; assert o["velocity"] == "0.001,0.002,0.15,0.3", o'
check "the template loads as a friction log with nothing yet to fit" \
  bash -c "'$LMCAL' check friction planout/plan_friction_template.csv 2>&1 | grep -q 'friction_N empty'"
"$LMCAL" plan thermal "$SOURCE/measurements/cheng2017/thermal.toml" --model "$SOURCE/fits/cheng2017/model.toml" \
  --velocity 0.03,0.083,0.2 --separate coupling,base_loss -n 1 -o tplanout >tplan.txt
check "plan thermal writes the runs to log as a manifest to complete" grep -q '^velocity_m_s = ' tplanout/plan_thermal_manifest.toml
check "plan thermal reports how far the planned runs separate a tie" grep -q 'correlation of their estimates' tplan.txt
check "plan thermal needs the calibrated model" \
  refused "a thermal plan needs the calibrated model" plan thermal "$SOURCE/measurements/cheng2017/thermal.toml" -o out
"$LMCAL" plan friction onepc/friction.csv -o planone >planone.txt
check "plan proposes the second preload class its note asks for; SEs of the same quantity, in units, no inf or nan" \
  bash -c "grep -qE '^  k2 +n/a \(not determined yet\) -> [0-9.e+-]+ +1/um$' planone.txt &&
           grep -qE '^  k1 +n/a \(only with k2 held\) -> [0-9.e+-]+ +-$' planone.txt &&
           grep -qE '^  k1 \(k2 held\) +[0-9.e+-]+ -> [0-9.e+-]+ +-$' planone.txt &&
           grep -q 'a second preload class, which determines k2' planone.txt && ! grep -qiwE 'nan|inf' planone.txt"
check "plan and predict write their pages with the plots" \
  bash -c "grep -q 'data-plot=\"plan-se-ratio\"' planone/plan.html && grep -q 'data-plot=\"prediction-elongation\"' predout/prediction.html"
check "plan refuses a parameter the fit does not have" \
  refused "'k9' is not a free parameter of the fit" plan friction "$SOURCE/measurements/cheng2017/friction.csv" --parameters k9 -o out

# Usage errors: exit status 2, "lmcal: error:", the nearest known name; input refused: 1.
exits_with() {  # exits_with STATUS EXPECTED_TEXT ARGS...
  local status=$1 expected=$2; shift 2
  "$LMCAL" "$@" >stdout.txt 2>stderr.txt
  local rc=$?
  [[ $rc -eq $status ]] || { echo "  exit $rc, not $status: $*"; return 1; }
  grep -qF -- "lmcal: error: $expected" stderr.txt || { echo "  message lacks 'lmcal: error: $expected': $(cat stderr.txt)"; return 1; }
}
check "an unknown command names the nearest" exits_with 2 "unknown command 'calibrat'; did you mean 'calibrate'?" calibrat x
check "an unknown subcommand names the nearest" exits_with 2 "unknown command 'frcition'; did you mean 'friction'?" generate frcition
check "an unknown option names the nearest" \
  exits_with 2 "unknown option '--star'; did you mean '--start' or '--starts'?" calibrate --star 3 x
check "a choice refused names the choices, not CLI11's map" \
  exits_with 2 "--offsets: 'bogus': expected one of auto, fit, hold" fit thermal x --offsets bogus
check "a missing argument is named with what it is" exits_with 2 "missing SET: Measurement folder" calibrate
check "no command lists the commands" exits_with 2 "expected a command: simulate, generate" 
check "an option's value out of range is refused like a file's" \
  exits_with 2 "--friction-min-gain: -5 is below 0: expected a value of at least 0" calibrate x --friction-min-gain -5
check "a thermal effect is refused for a friction log" \
  exits_with 1 "--effect: coupling is thermal: a friction log does not see it" generate friction -o out --effect coupling=1
check "a CSV given as a manifest is named as one" \
  exits_with 1 "$SOURCE/measurements/cheng2017/friction.csv: this looks like a CSV file (comma-separated columns); expected a TOML manifest" \
  fit thermal "$SOURCE/measurements/cheng2017/friction.csv"
check "a missing duty cycle is named as one, not as a manifest" \
  exits_with 1 "no_such_duty.toml: cannot open duty-cycle file: No such file or directory" \
  predict "$SOURCE/fits/cheng2017/model.toml" no_such_duty.toml -o predout_missing
for command in "fit friction" "fit thermal" "generate fleet"; do
  # shellcheck disable=SC2086  # the command's words
  check "$command --help shows its off switches without CLI11's {false}" \
    sh -c "\"$LMCAL\" $command --help | grep -q -- '--no-' && ! \"$LMCAL\" $command --help | grep -q '{false}'"
done
check "a CSV given as a friction fit is named as one" \
  exits_with 1 "$SOURCE/measurements/cheng2017/friction.csv: this looks like a CSV file (comma-separated columns); expected a friction fit JSON" \
  fit thermal "$SOURCE/measurements/cheng2017/thermal.toml" --friction "$SOURCE/measurements/cheng2017/friction.csv" -o out
check "--guide is --guide in every command" "$LMCAL" generate friction --guide "SRN 35C" --runs 1 -o guide_out
printf '[calibrate]\nstarts = 4\nlrtp = 0.01\n' >options.toml
check "a config file's unknown key is refused where it is" \
  exits_with 2 "options.toml:3:1: unknown key 'calibrate.lrtp'; did you mean 'calibrate.lrt-p'?" --config options.toml calibrate x
check "a missing folder is an input error (1)" exits_with 1 "nowhere: expected a measurement folder" calibrate nowhere
check "a device is refused before a byte is read" exits_with 1 "/dev/zero: cannot open file: this is a device" check friction /dev/zero
# Issue 36: every size bounded before the work starts (docs/formats.md#limits).
check "a config file is a file: /dev/zero refused before a byte is read" \
  timeout 20 bash -c "! '$LMCAL' --config /dev/zero calibrate x 2>stderr.txt && grep -qF '/dev/zero: cannot open config file: this is a device' stderr.txt"
printf '[calibrate]\nstarts = 4\n\n[ calibrate ]\nh = 6\n' >config_twice.toml
check "a config file's table given twice is refused at the second" \
  exits_with 1 "config_twice.toml:4:1: [calibrate] given twice (first at line 1): one table per command" --config config_twice.toml calibrate x
check "--segments beyond the limit refused before the fit (was SIGABRT)" \
  exits_with 2 "--segments: 1000000000 is above 10000: expected a value from 1 to 10000 (docs/formats.md#limits)" \
  fit thermal "$SOURCE/measurements/cheng2017/thermal.toml" --segments 1000000000
check "--bootstrap beyond the limit refused" exits_with 2 "--bootstrap: 1e9 is above 100000" calibrate x --bootstrap 1e9
check "--starts beyond the limit refused (calibrate)" exits_with 2 "--starts: 1e9 is above 1000" calibrate x --starts 1e9
check "--starts beyond the limit refused (fit friction)" \
  refused "--starts = 1000000000 is invalid: expected from 1 to 1000" fit friction "$SOURCE/measurements/cheng2017/friction.csv" --starts 1000000000 -o out
check "simulate thermal --segments beyond the limit refused" refused "from 1 to 100000 segments" simulate thermal -o out/t --segments 1000000000
check "predict --samples beyond the limit refused" \
  refused "samples = 4000000000 is invalid: expected at most 100000 draws" predict "$SOURCE/fits/cheng2017/model.toml" "$SOURCE/examples/duty/two_shifts.toml" -o out --samples 4000000000
check "predict refuses what its estimate says would not fit in memory, before a draw" \
  timeout 20 bash -c "! '$LMCAL' predict '$SOURCE/fits/cheng2017/model.toml' '$SOURCE/examples/duty/two_shifts.toml' -o out --samples 100000 2>stderr.txt && grep -qF 'memory beyond 4 GiB' stderr.txt"
printf 'run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\na,0.01,3000,4,120,25,20\na,0.1,3000,4,120,30,30\nb,0.05,1000,4,120,25,15\nb,0.2,2000,4,120,35,35\nc,0.02,3000,8,120,28,25\n' >five_rows.csv
unusable_writes_nothing() {
  exits_with 4 "the friction fit is not usable: no degree of freedom left: 5 residuals for 7 free parameters; nothing was written" \
    fit friction five_rows.csv -o unusable && test ! -e unusable
}
check "a fit with no degree of freedom left exits 4, writing nothing" unusable_writes_nothing
keeps_unusable() {
  "$LMCAL" fit friction five_rows.csv -o kept --keep-unusable >/dev/null 2>stderr.txt &&
    grep -q "lmcal: warning: the friction fit is not usable" stderr.txt &&
    python3 -c 'import json,sys; s = json.load(open("kept/friction.json"))["solver"]; assert not s["usable"] and "degree of freedom" in s["unusable_reason"]'
}
check "--keep-unusable writes it, marked, and exits 0" keeps_unusable
python3 -c 'import json,sys; d = json.load(open(sys.argv[1])); [p.update(value=1e308) for p in d["parameters"] if p["name"] == "mu_st"]; json.dump(d, open("huge_mu_st.json", "w"))' \
  "$SOURCE/fits/cheng2017/friction.json"
check "friction constants that give no finite heat are refused, naming the run" \
  exits_with 1 "v066_r1: its heat rate is not finite (from the friction law (fitted constants))" \
  fit thermal "$SOURCE/measurements/cheng2017/thermal.toml" --friction huge_mu_st.json -o out

# Shell completion and the man page, generated from the command tree.
"$LMCAL" completion bash >completion.bash
completes() {  # completes EXPECTED WORD... : the last word completed after the others
  local expected=$1; shift
  (source completion.bash; COMP_WORDS=(lmcal "$@"); COMP_CWORD=$#; _lmcal; printf '%s\n' "${COMPREPLY[@]}") | grep -qx -- "$expected" ||
    { echo "  '$*' does not complete to $expected"; return 1; }
}
check "bash completes a command" completes calibrate cal
check "bash completes a subcommand" completes friction generate fr
check "bash completes an option of a subcommand, in its group too" completes --raw generate friction --ra
check "bash completes a global option" completes --json --js
check "bash completes an option's values" completes cauchy fit friction --loss c
check "bash completes a choice option's values" completes hac calibrate --covariance h
check "bash completes a value in an option group" completes trajectory fit friction --segmentation t
"$LMCAL" man >lmcal.1
check "the man page has every command and option" grep -q '^.SH lmcal generate friction' lmcal.1
check "the man page lists an option's help" grep -q '^.B \\-\\-friction\\-min\\-gain' lmcal.1
check "the man page says the exit status" grep -q '^.SH EXIT STATUS' lmcal.1
check "the man page has a description" grep -q '^.SH DESCRIPTION' lmcal.1
check "the man page has examples, the main job first" bash -c "grep -A3 '^.SH EXAMPLES' lmcal.1 | grep -q 'lmcal calibrate'"
check "--json prints the main output" bash -c '"$0" --json fit friction "$1" -o jsonout | python3 -c "import json,sys; assert json.load(sys.stdin)[\"kind\"] == \"friction fit\""' \
  "$LMCAL" "$SOURCE/measurements/cheng2017/friction.csv"
check "a global option works after the command too" bash -c '"$0" fit friction "$1" -o jsonout2 --json | python3 -c "import json,sys; json.load(sys.stdin)"' \
  "$LMCAL" "$SOURCE/measurements/cheng2017/friction.csv"
no_suggestion() { exits_with 2 "unknown option '--bogus'" fit friction x.csv --bogus && ! grep -q "did you mean" stderr.txt; }
check "an unknown option with no near one suggests nothing" no_suggestion
check "-q prints nothing" test -z "$("$LMCAL" -q fit friction "$SOURCE/measurements/cheng2017/friction.csv" -o quietout 2>&1)"

# Deterministic: the same bytes with one thread or two (no timings in the outputs, so that the
# main job leaves the committed fits as they are).
# Both bundled sets: the diagnoses fit their candidates one per thread.
same_with_threads() {  # same_with_threads SET
  rm -rf threads1 threads2
  OMP_NUM_THREADS=1 "$LMCAL" calibrate "$1" -o threads1 >/dev/null 2>&1
  OMP_NUM_THREADS=2 "$LMCAL" calibrate "$1" -o threads2 >/dev/null 2>&1
  local f
  for f in threads1/*; do
    cmp -s "$f" "threads2/${f#threads1/}" || { echo "  $f differs"; return 1; }
  done
  test -s threads1/report.html
}
# Skipped under the sanitizers (scripts/sanitize.sh says why); the release suite runs them.
if [[ -z ${LMCAL_TEST_SERIAL_BUILD:-} ]]; then
  check "calibrate gives the same outputs with 1 and 2 threads (rig-shaped set)" same_with_threads "$SOURCE/measurements/rig"
  check "calibrate gives the same outputs with 1 and 2 threads (Cheng 2017 set)" same_with_threads "$SOURCE/measurements/cheng2017"
  # 2154 conditions, thinned to about 540 per plot
  check "the residual plot against direction shows both senses" both_senses threads2/report.html friction-residual-direction
  check "the diagnosis's plot against direction shows both senses" both_senses threads2/report.html friction-diagnosis-direction
fi

# The bundled set is exactly what the recorded commands make (the command lines aside).
LMCAL="$LMCAL" bash "$SOURCE/scripts/make-bundled-data.sh" "$work/bundled" "$work/bundled-rig" "$work/bundled-axis" >/dev/null
same_as_bundled() {  # same_as_bundled SET FOLDER
  diff -r -q -I '^# Command:' "$SOURCE/measurements/$1" "$2" -x README.md
}
check "bundled data set regenerates identically" same_as_bundled cheng2017 "$work/bundled"
check "the rig-shaped set regenerates identically" same_as_bundled rig "$work/bundled-rig"
check "the drive-log set regenerates identically" same_as_bundled axis "$work/bundled-axis"

finish cli_test.sh
