#!/usr/bin/env bash
# Regenerates measurements/cheng2017/, the bundled SYNTHETIC data set, with the virtual
# rig. Same lmcal version and seeds, same bytes. Run from the repository root after
# scripts/build.sh. Optional: an output folder instead of measurements/cheng2017 (the
# tests regenerate the set elsewhere and compare), and LMCAL=path/to/lmcal.
set -euo pipefail
cd "$(dirname "$0")/.."
lmcal=${LMCAL:-build/lmcal}
out=${1:-measurements/cheng2017}

# Friction: three guides, three preload classes, loads 1-3 kN, 10 speeds, 4 temperatures,
# both directions, 10 repeats. Effects the paper's law leaves out: seal drag and a
# direction asymmetry.
"$lmcal" generate friction -o "$out" --seed 2017 --runs 10 \
  --effect seal_drag=150 --effect direction_asymmetry=0.03

# Thermal: SRN 35C, P = 3 kN, L1 = 0.2 m, 6 h at 5 s, V = 0.066/0.083/0.11 m/s, two runs
# each; two ambient sensors, three rail thermocouples. Effects: two-way friction-temperature
# coupling, velocity-dependent convection, the moving block, thermocouple lag; and the same
# guide's friction as the log above (seal drag, direction asymmetry), so that the heat the
# friction fit predicts is the heat the rail saw.
"$lmcal" generate thermal -o "$out" --seed 2017 --name cheng2017 --repeats 2 \
  --effect coupling=1 --effect convection_velocity=6 --effect moving_source=1 --effect tc_lag=30 \
  --effect seal_drag=150 --effect direction_asymmetry=0.03
