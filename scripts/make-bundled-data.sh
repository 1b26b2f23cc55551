#!/usr/bin/env bash
# Regenerates measurements/cheng2017/, the bundled SYNTHETIC data set, with the virtual
# rig; measurements/rig/, a set shaped as rigs log (raw load-cell time series with a
# friction manifest; thermal runs that stop and cool, without ambient sensors); and
# measurements/axis/, a machine axis's own drive log (closed-loop moves on an inclined axis,
# the motor's force, no load cell). Same lmcal version and seeds, same bytes. Run from the
# repository root after scripts/build.sh. Optional: output folders instead of
# measurements/cheng2017, measurements/rig and measurements/axis (the tests regenerate the
# sets elsewhere and compare), and LMCAL=path/to/lmcal.
set -euo pipefail
cd "$(dirname "$0")/.."
lmcal=${LMCAL:-build/lmcal}
out=${1:-measurements/cheng2017}
rig=${2:-measurements/rig}
axis=${3:-measurements/axis}

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

# Rig-shaped: SRN 35C, preload 1.5 / 4 um, 1 / 3 kN, 22 / 40 C, one setup per run, each a raw
# time series at 50 Hz over a 0.15 m stroke (0.5 m/s2 ramps, 1 um encoder, 2 kg moving mass,
# a tared load cell drifting 0.2 N/h); the runs' conditions in friction.toml.
"$lmcal" generate friction --raw -o "$rig" --seed 2026 --runs 1 --guides "SRN 35C" --preload 1.5,4 \
  --load 1000,3000 --temperature 22,40 --velocity 0.005,0.01,0.02,0.05,0.11 --stroke 0.15 \
  --sample-rate 50 --run-offset 0 --drift 0.2
# Thermal: three runs at 0.066, 0.083 and 0.11 m/s that stop after 4 h and cool for 2 h, logged every
# 30 s without ambient sensors (ambient_C in the manifest: a steady room, as that assumes).
"$lmcal" generate thermal -o "$rig" --seed 2026 --name rig --velocity 0.066,0.083,0.11 --stop 14400 \
  --record-every 30 --no-ambient-columns --ambient-drift 0 --ambient-wave 0

# A drive's own log: a 40 kg carriage on a 20 degree axis under a cascaded P-PI controller,
# trapezoidal moves at 5 top speeds (1 m/s2, 0.5 s cruise), 1 kHz, 1 um encoder, the motor's
# force K_f i with current noise; one run per load (1 / 2 / 3 kN on the block). Read as a
# trajectory: the moving mass and the weight along the axis are fitted with the law.
"$lmcal" generate axis -o "$axis" --seed 2027 --incline 20 --load 1000,2000,3000 \
  --velocity 0.005,0.02,0.05,0.1,0.15 --cycles 1 --cruise 0.5
