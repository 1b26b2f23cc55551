#!/usr/bin/env bash
# The main job: installs what is missing, builds (Release) and runs lmcal on the
# bundled case: a check of the bundled (synthetic) measurements, the friction and thermal
# fits (fits/cheng2017/) and a simulation of the paper's SRN 35C rail case (Cheng et al. 2017,
# Tables 2-3; fits/simulation/).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
out=fits/simulation
lmcal=build/lmcal

echo
echo "== Bundled measurements (measurements/cheng2017, synthetic: see its README) =="
"$lmcal" check friction measurements/cheng2017/friction.csv
"$lmcal" check thermal measurements/cheng2017/thermal.toml

echo
echo "== Friction constants fitted to the bundled friction log (fits/cheng2017/) =="
"$lmcal" fit friction measurements/cheng2017/friction.csv -o fits/cheng2017 --name friction

echo
echo "== What the published friction law gets wrong on the bundled log, and why =="
"$lmcal" diagnose friction measurements/cheng2017/friction.csv -o fits/cheng2017 --name friction_diagnosis

echo
echo "== Heat partition alpha fitted to the bundled thermal runs, heat from the friction fit =="
"$lmcal" fit thermal measurements/cheng2017/thermal.toml --friction fits/cheng2017/friction.json \
  -o fits/cheng2017 --name thermal

echo
echo "== What the published rail model gets wrong on the bundled thermal runs, and why =="
"$lmcal" diagnose thermal measurements/cheng2017/thermal.toml --friction fits/cheng2017/friction.json \
  -o fits/cheng2017 --name thermal_diagnosis

echo
echo "== Friction law (Eqs. 3-7) over speed, load, preload and temperature (Figs. 4-7) =="
"$lmcal" simulate friction -o "$out/friction.csv" \
  --velocity 0.005:0.2:0.005 --load 1000,2000,3000 --preload 1.5,2.5,4 --temperature 26,40

echo
echo "== SRN 35C rail, the paper's model and numerics (paper source, 50 segments, 600 s, backward Euler) =="
echo "   with the numerical error of that setup against a converged solution"
"$lmcal" simulate thermal -o "$out/paper" --velocity 0.066,0.083,0.11 \
  --source paper --scheme be --segments 50 --dt 600 --output-every 600 --reference

echo
echo "== The same rail with the energy-exact averaged source (converged numerics) =="
"$lmcal" simulate thermal -o "$out/averaged" --velocity 0.066,0.083,0.11 --source averaged
