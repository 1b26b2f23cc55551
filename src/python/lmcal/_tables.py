"""The DataFrames of ``to_dataframe()``: one row per sample, parameter, candidate cause or output
time, each column named with its unit as lmcal names quantities (``measured_N``, ``time_s``,
``elongation_um``); where the unit differs from row to row (parameters, causes) a ``unit``
column gives each row's."""

import math

import numpy as np

from ._optional import require


def frame(columns: dict, what: str, index=None):
    """A DataFrame of ``columns`` (name -> values); ImportError naming ``what`` without pandas."""
    pd = require("pandas", what)
    df = pd.DataFrame(columns)
    return df.set_index(index) if index else df


def _interval(pair):
    low, high = pair if pair else (None, None)
    return (math.nan if low is None else low), (math.nan if high is None else high)


def parameters(params: dict, what: str):
    """A fit's parameters (name -> Parameter), indexed by name: value, stderr and the 95 %
    interval in ``unit``, how the interval was made, free/held/at bound, the start and bounds."""
    ps = list(params.values())
    return frame({"name": [p.name for p in ps], "value": [p.value for p in ps], "stderr": [p.stderr for p in ps],
                  "unit": [p.unit for p in ps], "ci95_low": [p.ci[0] for p in ps], "ci95_high": [p.ci[1] for p in ps],
                  "interval": [p.interval for p in ps], "free": [p.free for p in ps], "held": [p.held for p in ps],
                  "at_bound": [p.at_bound for p in ps], "init": [p.init for p in ps],
                  "bound_low": [p.bounds[0] for p in ps], "bound_high": [p.bounds[1] for p in ps]}, what, index="name")


def candidates(diagnosis: dict, what: str):
    """Every cause a diagnosis tried, round by round (round 1 first): its estimate with the unit,
    the likelihood-ratio test's p, the held-out RMSE and gain, accepted or why not."""
    rmse = "cv_rmse_K" if "cv_rmse_before_K" in diagnosis else "cv_rmse_N"  # a thermal diagnosis' or a friction one's
    rows = [(r, c) for r, tried in enumerate(diagnosis.get("rounds", []), start=1) for c in tried]
    number = lambda v: math.nan if v is None else v  # noqa: E731
    return frame({"round": [r for r, _ in rows], "cause": [c["effect"] for _, c in rows],
                  "accepted": [bool(c.get("accepted")) for _, c in rows],
                  "value": [number(c.get("value")) for _, c in rows], "unit": [c.get("unit", "") for _, c in rows],
                  "se": [number(c.get("se")) for _, c in rows],
                  "ci95_low": [_interval(c.get("ci95"))[0] for _, c in rows],
                  "ci95_high": [_interval(c.get("ci95"))[1] for _, c in rows],
                  "lrt_p": [number(c.get("lrt_p")) for _, c in rows],
                  rmse: [number(c.get(rmse)) for _, c in rows],
                  "cv_gain_percent": [number(c.get("cv_gain_percent")) for _, c in rows],
                  "reason": [c.get("reason", "") for _, c in rows]}, what)


def bands(time_s, named_bands: list, what: str, segment=None):
    """Bands over time as columns: ``NAME``, ``NAME_low``, ``NAME_high`` for each (NAME, band)."""
    columns = {"time_s": np.asarray(time_s)}
    if segment is not None:
        columns["segment"] = list(segment)
    for name, band in named_bands:
        columns[name] = band["value"]
        columns[f"{name}_low"] = band["low"]
        columns[f"{name}_high"] = band["high"]
    return frame(columns, what)


def at_position(quantity: str, x_m: float) -> str:
    """A column name of a quantity at a place on the rail: ``temperature_C_at_0.05m``."""
    return f"{quantity}_at_{x_m:g}m"
