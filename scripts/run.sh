#!/usr/bin/env bash
# The main job: installs what is missing, builds (Release) and runs lmcal on the
# bundled case: a check of the bundled (synthetic) measurements, a simulation of the paper's
# SRN 35C rail case (Cheng et al. 2017, Tables 2-3; fits/simulation/), and last the whole
# calibration of the bundled measurements with its report (fits/cheng2017/report.html), and
# of the rig-shaped set (fits/rig/report.html) and of a machine axis's own drive log
# (fits/axis/report.html).
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

echo
echo "== The calibration of the bundled measurements: friction fit and diagnosis, thermal fit and"
echo "   diagnosis, spread across runs, and the report (open fits/cheng2017/report.html) =="
"$lmcal" calibrate measurements/cheng2017

echo
echo "== A rig-shaped set (measurements/rig, synthetic): raw load-cell time series cut into"
echo "   constant-velocity plateaus, thermal runs that stop and cool (open fits/rig/report.html) =="
"$lmcal" calibrate measurements/rig

echo
echo "== A machine axis's own drive log (measurements/axis, synthetic): closed-loop moves on a 20 degree"
echo "   axis, the motor's force; the moving mass and the weight fitted with the law (fits/axis/report.html) =="
"$lmcal" calibrate measurements/axis
