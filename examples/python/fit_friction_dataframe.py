"""lmcal from Python: the bundled friction log fitted from a pandas DataFrame, the fit
plotted (when matplotlib is installed) and evaluated at new conditions, then the whole
calibration of the bundled set.

    PYTHONPATH=build/python python3 examples/python/fit_friction_dataframe.py [OUTPUT_DIR]

(or without PYTHONPATH once `cmake --install` put the package into your site-packages)."""

import os
import sys

import numpy as np

import lmcal

here = os.path.dirname(os.path.abspath(__file__))
measurements = os.path.join(here, "..", "..", "measurements", "cheng2017")
output = sys.argv[1] if len(sys.argv) > 1 else "lmcal-example"

# 1. The log as a DataFrame (any source: a database, an instrument's API, ...); columns are
#    named as in a CSV log, units in the names. round_trip: pandas' exact float parsing.
try:
    import pandas as pd
    frame = pd.read_csv(os.path.join(measurements, "friction.csv"), comment="#", float_precision="round_trip")
except ImportError:  # without pandas a dict of NumPy columns goes in the same way
    import csv
    with open(os.path.join(measurements, "friction.csv")) as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    frame = {k: [r[k] for r in rows] if k in ("run", "guide") else np.array([float(r[k]) for r in rows])
             for k in rows[0]}
log = lmcal.load_friction_log(frame)
print(log)

# 2. The seven constants with their uncertainty: the report, and the numbers as Python values.
fit = lmcal.fit_friction(log)
print(fit)
k1 = fit.params["k1"]
print(f"k1 = {k1.value:.4f} ± {k1.stderr:.4f}, 95 % [{k1.ci[0]:.4f}, {k1.ci[1]:.4f}] ({k1.interval})")

# 3. Measured against fitted, and the residuals by speed (every sample, both directions), and
#    the fitted law at conditions of your own.
os.makedirs(output, exist_ok=True)
try:
    import matplotlib
    matplotlib.use("Agg")
    fit.plot(x="velocity_m_s").savefig(os.path.join(output, "friction_fit.png"), dpi=120)
    print("plot:", os.path.join(output, "friction_fit.png"))
except ImportError as e:  # the message says how to install it
    print(f"no plot: {e}")
speeds = np.array([0.01, 0.05, 0.1])
print("fitted friction at 2.5 kN, 30 C on an SRN 35C (N):",
      fit.eval(velocity_m_s=speeds, load_N=2500, temperature_C=30, guide="SRN 35C").round(2))

# 4. The whole calibration, as `lmcal calibrate` does it, with progress.
cal = lmcal.calibrate(measurements, progress=lambda what, done, total: print(f"  {what} ({done + 1}/{total})"))
print(cal.summary())
cal.write(os.path.join(output, "cheng2017"))
print("wrote", os.path.join(output, "cheng2017", "report.html"))
