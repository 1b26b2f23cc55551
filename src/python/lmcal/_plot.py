"""The figures of ``plot()``: a fit's data against the fitted model and its residuals, every
sample drawn (nothing thinned away), with matplotlib imported only when a plot is asked for."""

import numpy as np

from ._optional import require

# How each sense of travel is drawn (both always: a bias in one alone is what a plot must show).
_DIRECTIONS = ((1, "forward", "tab:blue"), (-1, "backward", "tab:orange"))
_LABELS = {"velocity_m_s": "velocity (m/s)", "load_N": "load (N)", "preload_um": "preload (µm)",
           "block_length_mm": "block length (mm)", "temperature_C": "temperature (°C)", "time_s": "time (s)",
           "viscosity40_mm2_s": "ν40 (mm²/s)", "direction": "direction", "sample": "sample"}


def friction_fit(fit, x: str):
    """Measured against fitted friction (left) and the residuals against ``x`` (right): a
    condition of the log (velocity_m_s, load_N, temperature_C, ...) or "sample"."""
    plt = require("matplotlib.pyplot", "FrictionFit.plot()")
    columns = fit.log.columns()
    measured, predicted = fit.measured_N, fit.predicted_N
    if x == "sample":
        along = np.arange(measured.size)
    elif x in _LABELS and x in columns:
        along = columns[x]
    else:
        raise ValueError(f"x: unknown '{x}'; expected sample or a condition of the log: "
                         f"{', '.join(k for k in _LABELS if k in columns)}")
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2), constrained_layout=True)
    for sense, name, color in _DIRECTIONS:
        shown = columns["direction"] == sense
        if not shown.any():
            continue
        label = f"{name} ({shown.sum()} samples)"
        left.scatter(predicted[shown], measured[shown], s=3, alpha=0.35, color=color, label=label, rasterized=True)
        right.scatter(along[shown], measured[shown] - predicted[shown], s=3, alpha=0.35, color=color, label=label,
                      rasterized=True)
    low, high = float(min(measured.min(), predicted.min())), float(max(measured.max(), predicted.max()))
    left.plot([low, high], [low, high], "k--", lw=1, label="measured = fitted")
    left.set_xlabel("fitted friction (N)")
    left.set_ylabel("measured friction (N)")
    left.legend(loc="upper left", fontsize="small")
    right.axhline(0, color="k", lw=1)
    if x == "velocity_m_s" and np.all(along > 0):
        right.set_xscale("log")
    right.set_xlabel(_LABELS[x])
    right.set_ylabel("measured − fitted (N)")
    d = fit.to_dict()
    fig.suptitle(f"friction fit '{d['name']}': {measured.size} samples, RMSE {fit.rmse_N:.3g} N")
    return fig


def thermal_fit(fit, run):
    """Measured (dots) and simulated (lines) rail temperatures over time (top) and their
    difference (bottom), every sensor of ``run`` (a run's id; None: every run)."""
    plt = require("matplotlib.pyplot", "ThermalFit.plot()")
    runs = fit.run_names
    if run is not None and run not in runs:
        raise ValueError(f"run: no run '{run}' in the fit; its runs are {', '.join(runs)}")
    chosen = runs if run is None else [run]
    s = fit.samples
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(10, 6.5), constrained_layout=True,
                                      gridspec_kw={"height_ratios": [2, 1]})
    colors = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for r, name in enumerate(chosen):
        index = runs.index(name)
        color = colors[r % len(colors)]
        for k, sensor in enumerate(fit.sensor_names[index]):
            shown = (s["run"] == index) & (s["sensor"] == k)
            hours = s["time_s"][shown] / 3600
            label = name if k == 0 else None
            top.plot(hours, s["measured_C"][shown], ".", ms=2, color=color, label=label)
            top.plot(hours, s["simulated_C"][shown], "-", lw=1, color=color)
            bottom.plot(hours, s["measured_C"][shown] - s["simulated_C"][shown], ".", ms=2, color=color)
    top.set_ylabel("rail temperature (°C)")
    if len(chosen) <= 12:
        top.legend(title="run (dots measured, lines simulated)", fontsize="small", ncol=2)
    bottom.axhline(0, color="k", lw=1)
    bottom.set_ylabel("measured − simulated (K)")
    bottom.set_xlabel("time (h)")
    alpha = fit.alpha
    fig.suptitle(f"thermal fit '{fit.to_dict()['name']}': α = {alpha.value:.4g} "
                 f"[{alpha.ci[0]:.4g}, {alpha.ci[1]:.4g}], {'every run' if run is None else 'run ' + run}")
    return fig
