"""lmcal: calibration of roller linear-motion guides, from Python.

The same library as the `lmcal` command, with the same numbers: a result's ``to_dict()`` is
the JSON the command writes for the same inputs and options.

    import lmcal
    log = lmcal.load_friction_log("measurements/cheng2017/friction.csv")   # or a DataFrame
    fit = lmcal.fit_friction(log)
    fit                      # the fit report: estimates, standard errors, intervals, correlations
    fit.params["k1"].ci      # (low, high), 95 %
    fit.covariance           # NumPy arrays; fit.residual_N, fit.predicted_N, ...
    fit.eval(velocity_m_s=[0.01, 0.1], load_N=2500, temperature_C=30, guide="SRN 35C")  # N
    fit.plot(); fit.to_dataframe()   # with matplotlib and pandas, imported only then
    cal = lmcal.calibrate("measurements/cheng2017", progress=print)
    cal.write("fits/cheng2017")   # every file `lmcal calibrate` writes, report.html included

Units are SI except where a name says otherwise (``preload_um``, ``block_length_mm``). Bad input
raises ``lmcal.InputError`` (a ValueError naming the file, line and column, or for columns the
column and the row: ``row`` and ``column`` attributes) or ``lmcal.InvalidParameterError`` (a
ValueError naming the parameter, and for a condition its ``row``). The long calls release the
GIL; ``progress(what, done, total)`` is called as they go, and Ctrl-C stops them.
"""

from __future__ import annotations

import dataclasses
import json
import math
import numbers
import os
from collections.abc import Mapping
from typing import Any, Callable, NamedTuple, Optional, Sequence

import numpy as np

from . import _columns, _lmcal, _plot, _tables
from ._lmcal import InputError, InvalidParameterError
from ._report import fit_report

__version__ = _lmcal.__version__
__all__ = [
    "InputError", "InvalidParameterError", "FrictionLog", "ThermalDataSet", "Parameter", "FrictionFit",
    "ThermalFit", "FrictionDiagnosis", "ThermalDiagnosis", "Calibration", "ThermalSimulation",
    "Prediction", "predict", "load_friction_log", "load_thermal_dataset", "fit_friction", "fit_thermal", "diagnose_friction",
    "diagnose_thermal", "calibrate", "simulate_friction", "simulate_thermal", "generate_friction", "GeneratedFriction",
    "guide", "friction_effect_names",
]

Progress = Callable[[str, int, int], Any]

# ---- loading ---------------------------------------------------------------------------------

_text = _columns.text


def _number_map(given, argument: str, pairs: bool = False):
    """``given`` (name -> number, or with ``pairs`` name -> (low, high)) checked: TypeError naming
    ``argument`` and the entry for anything else, before it reaches the C++ core."""
    if given is None:
        return None
    if not isinstance(given, Mapping):
        raise TypeError(f"{argument}: expected a dict of constant names to "
                        f"{'(low, high) pairs' if pairs else 'numbers'}, got {type(given).__name__}")

    def number(name, v):
        if isinstance(v, bool) or not isinstance(v, numbers.Real):
            raise TypeError(f"{argument}[{name!r}]: expected a number, got {type(v).__name__} {v!r}")
        return float(v)

    out = {}
    for name, v in given.items():
        if not isinstance(name, str):
            raise TypeError(f"{argument}: expected constant names as keys, got {type(name).__name__} {name!r}")
        _text(name, argument)
        if pairs:
            if not isinstance(v, (tuple, list)) or len(v) != 2:
                raise TypeError(f"{argument}[{name!r}]: expected a (low, high) pair, got {v!r}")
            out[name] = (number(name, v[0]), number(name, v[1]))
        else:
            out[name] = number(name, v)
    return out


def _load_columns(load, data, **prepare):
    """``load(names, columns)`` of columns checked by _columns.prepare; an error about a row
    also gives a DataFrame's index label of that row."""
    names, columns = _columns.prepare(data, **prepare)
    try:
        return load(names, columns)
    except InputError as e:
        raise _columns.with_label(e, _columns.row_labels(data)) from None


class FrictionLog:
    """Load-cell samples, one per row: run, velocity_m_s, load_N, preload_um, block_length_mm,
    temperature_C, friction_N (and time_s, viscosity40_mm2_s, direction, guide)."""

    def __init__(self, handle, origin: str = "columns"):
        self._h = handle
        self._origin = origin  # what the log came from when no file

    @classmethod
    def from_columns(cls, data, **raw) -> "FrictionLog":
        """A log from a dict of columns or a pandas DataFrame, named as in a CSV log (any
        accepted unit: ``load_kN``, ``temperature_K``, ...) and checked by the same rules. A
        value refused is an InputError with the column's name and the row (0-based; with a
        DataFrame's own index, its label too)."""
        return cls(_load_columns(lambda names, columns: _lmcal.friction_log_from_columns(names, columns, raw), data))

    def __len__(self) -> int:
        return len(self._h)

    @property
    def run_names(self) -> list:
        return self._h.run_names

    @property
    def inputs(self) -> list:
        """(file, sha256) of every file read."""
        return self._h.inputs

    @property
    def load_reports(self) -> list:
        """Per file: rows read and kept, rows skipped and why, unit conversions, warnings."""
        return self._h.load_reports()

    def columns(self) -> dict:
        """The samples in SI and the log's units, as NumPy arrays; ``run`` and ``guide`` as names."""
        c = self._h.columns()
        c["run"] = np.asarray(self.run_names, dtype=object)[c["run"]]
        c["guide"] = np.asarray(self._h.guide_names, dtype=object)[c["guide"]]
        return c

    def to_dataframe(self):
        """columns() as a pandas DataFrame (pandas is needed for this alone)."""
        return _tables.frame(self.columns(), "FrictionLog.to_dataframe()")

    def to_csv(self) -> str:
        return self._h.csv()

    def __repr__(self) -> str:
        files = ", ".join(os.path.basename(f) for f, _ in self.inputs) or self._origin
        return f"<lmcal.FrictionLog: {len(self)} samples in {len(self.run_names)} runs from {files}>"


def load_friction_log(source, *, catalog: Optional[str] = None, allow_outside_root: bool = False, **raw) -> FrictionLog:
    """A friction log from a CSV file, several CSV files (one log), a friction manifest
    (``.toml``), or columns (a dict or a pandas DataFrame). ``raw`` settings segment raw
    load-cell logs: force_sign, moving_mass_kg, max_acceleration_m_s2, settling_s, ...
    A manifest's files must lie inside its folder unless ``allow_outside_root``."""
    if isinstance(source, FrictionLog):
        return source
    if isinstance(source, (str, os.PathLike)):
        path = os.fspath(source)
        if path.endswith(".toml"):
            return FrictionLog(_lmcal.load_friction_manifest(path, catalog, raw, allow_outside_root))
        return FrictionLog(_lmcal.load_friction_files([path], raw))
    if isinstance(source, Sequence) and all(isinstance(s, (str, os.PathLike)) for s in source):
        return FrictionLog(_lmcal.load_friction_files([os.fspath(s) for s in source], raw))
    return FrictionLog.from_columns(source, **raw)


class ThermalDataSet:
    """Thermal runs of a manifest: each run's conditions and its temperature trace."""

    def __init__(self, handle):
        self._h = handle

    @property
    def name(self) -> str:
        return self._h.name

    @property
    def runs(self) -> list:
        """Per run a dict: id, guide, velocity_m_s, load_N, stroke_m, rail_length_m,
        sensor_position_m, and ``trace`` (time_s and every temperature column, NumPy)."""
        return self._h.runs()

    @property
    def inputs(self) -> list:
        return self._h.inputs

    def with_trace(self, run: str, columns) -> "ThermalDataSet":
        """A copy with run ``run``'s trace taken from columns (a dict or a DataFrame with the
        columns of its file: time_s, the ambient and tc… columns) instead of its file. NaN in a
        temperature column is a missing sample, as an empty cell in the file."""
        run = _text(run, "run")
        return ThermalDataSet(_load_columns(lambda names, values: _lmcal.thermal_with_trace(self._h, run, names, values),
                                            columns, missing_allowed=lambda name: not name.startswith("time")))

    def __repr__(self) -> str:
        return f"<lmcal.ThermalDataSet '{self.name}': {len(self.runs)} runs>"


def load_thermal_dataset(manifest, *, catalog: Optional[str] = None, allow_outside_root: bool = False) -> ThermalDataSet:
    """The runs of a thermal manifest (TOML) with their traces; its files must lie inside its
    folder unless ``allow_outside_root``."""
    if isinstance(manifest, ThermalDataSet):
        return manifest
    return ThermalDataSet(_lmcal.load_thermal_manifest(os.fspath(manifest), catalog, allow_outside_root))


# ---- results ---------------------------------------------------------------------------------

@dataclasses.dataclass(frozen=True)
class Parameter:
    """One estimate, as lmcal reports it. ``ci`` is the interval to quote (``interval`` says
    which: linear t interval with the chosen covariance, or profile likelihood)."""
    name: str
    value: float
    stderr: float
    unit: str
    ci: tuple
    interval: str
    free: bool
    held: bool        # asked to be fitted, held at its start because the data cannot determine it
    at_bound: bool
    init: float
    bounds: tuple

    @classmethod
    def from_json(cls, p: dict) -> "Parameter":
        def num(v):
            return math.nan if v is None else float(v)
        ci = p.get("ci95")  # the interval the text quotes ("interval" says which)
        return cls(p["name"], num(p.get("value")), num(p.get("se")), p.get("unit", ""),
                   tuple(num(v) for v in (ci or (None, None))), p.get("interval", "linear"), bool(p.get("free")),
                   bool(p.get("held_unidentifiable")), bool(p.get("at_bound")), num(p.get("start")),
                   tuple(num(v) for v in p.get("bounds", (None, None))))


class _Result:
    """A result handle with its JSON (``to_dict``), its summary and, for fits, its arrays."""

    def __init__(self, handle):
        self._h = handle
        self._json = None
        self._arrays = None

    def to_dict(self) -> dict:
        """The result as the `lmcal` command writes it (its JSON file), as plain Python types."""
        if self._json is None:
            self._json = self._h.json()
        return json.loads(self._json)

    def summary(self) -> str:
        """The few lines the `lmcal` command prints."""
        return self._h.summary()

    def _array(self, key):
        if self._arrays is None:
            self._arrays = self._h.arrays()
        return self._arrays[key]


class _Fit(_Result):
    _fit_key = None  # where the fit's parameters are in to_dict() (None: at the top)

    def _fit_dict(self) -> dict:
        d = self.to_dict()
        return d[self._fit_key] if self._fit_key else d

    @property
    def params(self) -> dict:
        """Name -> Parameter, every parameter of the fit (per-run nuisance ones included)."""
        return {p["name"]: Parameter.from_json(p) for p in self._fit_dict()["parameters"]}

    @property
    def parameter_names(self) -> list:
        return list(self._array("names"))

    @property
    def values(self) -> np.ndarray:
        return self._array("values")

    @property
    def stderr(self) -> np.ndarray:
        return self._array("se")

    @property
    def covariance(self) -> np.ndarray:
        """The quoted covariance of every parameter (rows and columns of held ones zero)."""
        return self._array("covariance")

    @property
    def correlation(self) -> np.ndarray:
        return self._array("correlation")

    @property
    def converged(self) -> bool:
        return bool(self._fit_dict()["solver"]["converged"])

    @property
    def warnings(self) -> list:
        return list(self._fit_dict().get("warnings", []))

    def write(self, folder) -> None:
        """The files `lmcal fit` writes, into ``folder``, all or none."""
        self._h.write(os.fspath(folder))

    def to_dataframe(self, table: str = "samples"):
        """A pandas DataFrame (pandas is needed for this alone) of the fit's ``table``:
        "samples", one row per fitted sample (its conditions, the measured and fitted values, the
        residual, as the command's NAME_samples.csv), or "parameters", one row per parameter
        indexed by name (value, stderr, unit, ci95_low, ci95_high, interval, init, bounds, ...)."""
        what = f"{type(self).__name__}.to_dataframe()"
        if table == "samples":
            return _tables.frame(self._samples(), what)
        if table == "parameters":
            return _tables.parameters(self.params, what)
        raise ValueError(f"table: unknown '{table}'; expected samples or parameters")


class FrictionFit(_Fit):
    """A friction fit: the seven constants (and effects) with uncertainty, per-sample
    predictions and residuals, the spread across runs."""

    @property
    def measured_N(self) -> np.ndarray:
        return self._array("measured_N")

    @property
    def predicted_N(self) -> np.ndarray:
        return self._array("predicted_N")

    @property
    def residual_N(self) -> np.ndarray:
        """measured - predicted, per sample."""
        return self.measured_N - self.predicted_N

    @property
    def sigma_N(self) -> np.ndarray:
        return self._array("sigma_N")

    @property
    def rmse_N(self) -> float:
        return float(self.to_dict()["goodness"]["rmse_N"])

    @property
    def run_offset_N(self) -> dict:
        return dict(zip(self._array("run_names"), self._array("run_offset_N").tolist()))

    @property
    def constants(self) -> dict:
        """The fitted law's seven constants by name (held ones at their values)."""
        return self._h.constants()

    @property
    def effects(self) -> dict:
        return self._h.effects()

    @property
    def log(self) -> FrictionLog:
        """The log fitted (the fit's samples are its rows, in order)."""
        return FrictionLog(self._h.log())

    def eval(self, conditions=None, *, guide=None, catalog: Optional[str] = None, **given) -> np.ndarray:
        """The fitted model's friction force (N) at ``conditions``: a dict of arrays or numbers, or
        a DataFrame, and/or keywords (which win), broadcast like NumPy arrays. Conditions:
        velocity_m_s, load_N, preload_um, block_length_mm, temperature_C (the law's);
        viscosity40_mm2_s (99), direction (+1), acceleration_m_s2, position_m,
        distance_since_reversal_m (0); ``guide`` (a catalog guide's name, or names) fills
        preload_um and block_length_mm where not given; with ``run`` (names of the fit's runs)
        each row carries its run's zero offset as ``predicted_N`` does, without it the law alone
        (a new setup). A log's columns pass as they are (time_s, friction_N are not conditions).
        Conditions the fitted log did not give (a combination law's) default to the fit's own."""
        merged = dict(_columns.items(conditions)) if conditions is not None else {}
        merged.update(given)
        columns, shape, runs = _columns.law_conditions(merged, function="FrictionFit.eval", guide=guide, catalog=catalog,
                                                       defaults=self._h.unlogged_conditions())
        values = _columns.law_values(self._h.eval, columns, shape)
        return values if runs is None else values + self._offsets(runs).reshape(shape)

    def _offsets(self, runs) -> np.ndarray:
        offsets = self.run_offset_N
        for row, run in enumerate(runs):
            if run not in offsets:
                raise _columns.condition_error("run", row, f"run = {run!r}: no such run in the fit; its runs are "
                                                           f"{', '.join(offsets)}")
        return np.array([offsets[run] if math.isfinite(offsets[run]) else 0.0 for run in runs])

    def plot(self, x: str = "velocity_m_s"):
        """A matplotlib figure (matplotlib is needed for this alone): measured against fitted
        friction, and the residuals against ``x`` (a condition of the log, or "sample"); every
        sample drawn, both senses of travel told apart."""
        return _plot.friction_fit(self, x)

    def _samples(self) -> dict:
        columns = self.log.columns()
        for name in self._h.unlogged_conditions():  # not data: the value the fit took
            columns.pop(name, None)
        columns.pop("friction_N")
        return {**columns, "measured_N": self.measured_N, "predicted_N": self.predicted_N,
                "residual_N": self.residual_N, "sigma_N": self.sigma_N}

    def __repr__(self) -> str:
        d = self.to_dict()
        return fit_report(f"friction fit '{d['name']}'", d, [("RMSE", f"{d['goodness']['rmse_N']:.6g} N"),
                                                              ("runs", len(d.get("runs", [])))])


class ThermalFit(_Fit):
    """A thermal fit: α (and h, mechanisms) over all runs, per-run fits, simulated vs measured
    temperature at every fitted record (``samples``)."""
    _fit_key = "joint"

    @property
    def alpha(self) -> Parameter:
        return self.params["alpha"]

    @property
    def samples(self) -> dict:
        """Columns run (index into run_names), sensor, time_s, measured_C, simulated_C."""
        return dict(self._array("samples"))

    @property
    def residual_C(self) -> np.ndarray:
        """measured - simulated, per fitted record (in ``samples`` order)."""
        s = self._array("samples")
        return s["measured_C"] - s["simulated_C"]

    @property
    def run_names(self) -> list:
        return list(self._array("run_names"))

    @property
    def sensor_names(self) -> list:
        """Per run, its sensors' names (``samples["sensor"]`` indexes the run's list)."""
        return list(self._array("sensor_names"))

    def plot(self, run: Optional[str] = None):
        """A matplotlib figure (matplotlib is needed for this alone): measured and simulated
        rail temperatures over time, and their difference, for every sensor of ``run`` (None:
        every run)."""
        return _plot.thermal_fit(self, run)

    def _samples(self) -> dict:
        s = self.samples
        runs, sensors = self.run_names, self.sensor_names
        return {"run": [runs[r] for r in s["run"]], "sensor": [sensors[r][k] for r, k in zip(s["run"], s["sensor"])],
                "time_s": s["time_s"], "measured_C": s["measured_C"], "simulated_C": s["simulated_C"],
                "residual_K": s["measured_C"] - s["simulated_C"]}

    def __repr__(self) -> str:
        d = self.to_dict()
        runs = d.get("alpha_across_runs") or {}
        stats = [("max error", f"{d.get('max_error_percent', math.nan):.4g} %"), ("runs", len(d.get("runs", [])))]
        if runs.get("n"):
            stats.append(("alpha across runs", f"{runs['mean']:.4g} +/- {runs['sd_eq1']:.2g} (Eq. 1 sd)"))
        return fit_report(f"thermal fit '{d['name']}'", d["joint"], stats)


class _Diagnosis(_Result):
    _what = ""

    @property
    def verdict(self) -> str:
        return self.to_dict()["verdict"]

    @property
    def causes(self) -> list:
        """The accepted causes: name, value, interval, held-out gain."""
        return [c for c in self.to_dict()["causes"] if c.get("accepted")]

    def to_dataframe(self):
        """A pandas DataFrame (pandas is needed for this alone) of every cause tried, round by
        round: round, cause, accepted, value with its unit, se, ci95_low, ci95_high, lrt_p, the
        held-out RMSE (cv_rmse_N or cv_rmse_K) and cv_gain_percent, and the reason."""
        return _tables.candidates(self.to_dict(), f"{type(self).__name__}.to_dataframe()")

    def __repr__(self) -> str:
        return f"[[{self._what} diagnosis]] {self.verdict}\n{self.summary()}"


class FrictionDiagnosis(_Diagnosis):
    _what = "friction"


class ThermalDiagnosis(_Diagnosis):
    _what = "thermal"


class Calibration(_Result):
    """A whole calibration of a measurement folder (`lmcal calibrate`)."""

    def _optional(self, wrap, value):
        return None if value is None else wrap(value)

    @property
    def friction(self) -> Optional[FrictionFit]:
        """The published law's fit (friction.json)."""
        return self._optional(FrictionFit, self._h.friction(False))

    @property
    def thermal(self) -> Optional[ThermalFit]:
        return self._optional(ThermalFit, self._h.thermal(False))

    @property
    def calibrated_friction(self) -> Optional[FrictionFit]:
        """The law with the accepted causes, refitted (calibrated_friction.json)."""
        return self._optional(FrictionFit, self._h.friction(True))

    @property
    def calibrated_thermal(self) -> Optional[ThermalFit]:
        return self._optional(ThermalFit, self._h.thermal(True))

    @property
    def friction_diagnosis(self) -> Optional[FrictionDiagnosis]:
        return self._optional(FrictionDiagnosis, self._h.friction_diagnosis())

    @property
    def thermal_diagnosis(self) -> Optional[ThermalDiagnosis]:
        return self._optional(ThermalDiagnosis, self._h.thermal_diagnosis())

    def report_html(self) -> str:
        """report.html, one self-contained page."""
        return self._h.report_html()

    def write(self, folder) -> None:
        """Every file `lmcal calibrate` writes (model.toml, the fits, the diagnoses,
        calibration.json, report.html) into ``folder``, all or none."""
        self._h.write(os.fspath(folder))

    def __repr__(self) -> str:
        return "[[calibration]]\n" + self.summary()


# ---- fitting ---------------------------------------------------------------------------------

def _given(**options) -> dict:
    """The options the caller gave (None: lmcal's default, as on the command line)."""
    return {k: (list(v) if isinstance(v, (tuple, set)) else v) for k, v in options.items() if v is not None}


def _command(function: str, options: dict) -> list:
    shown = ", ".join(f"{k}={v!r}" for k, v in options.items() if not callable(v))
    return [f"lmcal.{function}({shown})"]


def fit_friction(log, *, free: Optional[Sequence[str]] = None, fixed: Optional[Mapping[str, float]] = None,
                 start: Optional[Mapping[str, float]] = None, bounds: Optional[Mapping[str, tuple]] = None,
                 effects: Optional[Sequence[str]] = None, run_offsets: Optional[str] = None,
                 law_temperature: Optional[str] = None, loss: Optional[str] = None, loss_scale: Optional[float] = None, weights: Optional[str] = None,
                 starts: Optional[int] = None, seed: Optional[int] = None, profile: Optional[str] = None,
                 covariance: Optional[str] = None, bootstrap: Optional[int] = None, run_fits: Optional[bool] = None,
                 cross_validate: Optional[bool] = None, name: str = "friction") -> FrictionFit:
    """Fits the friction constants (``lmcal fit friction``). ``log``: a FrictionLog, a file,
    files, a manifest, or columns. Options as the command's flags (None: its default):
    free (constants to fit; default all seven), fixed/start (name -> value), bounds
    (name -> (low, high)), effects (named effects on top of the law), run_offsets
    ('auto', 'none', 'fixed', 'random'), law_temperature ('block-mean', 'logged'), loss ('none', 'huber', 'cauchy') and loss_scale, weights
    ('none', 'per-run', 'per-condition'), starts and seed (multi-start), profile ('auto',
    'all', 'none'), covariance ('auto', 'iid', 'hac', 'cluster', 'bootstrap'), bootstrap
    (replicates), run_fits (per-run fits for the spread across runs), cross_validate."""
    log = load_friction_log(log)
    fixed, start, bounds = _number_map(fixed, "fixed"), _number_map(start, "start"), _number_map(bounds, "bounds", pairs=True)
    options = _given(free=free, fixed=fixed, start=start, bounds=bounds, effects=effects, run_offsets=run_offsets,
                     law_temperature=law_temperature, loss=loss, loss_scale=loss_scale, weights=weights, starts=starts, seed=seed, profile=profile,
                     covariance=covariance, bootstrap=bootstrap, run_fits=run_fits, cross_validate=cross_validate)
    return FrictionFit(_lmcal.fit_friction(log._h, options, name, _command("fit_friction", options)))


def _thermal_options(friction, heat, source, scheme, half_rail_segments, time_step_s, every, ambient, alpha_start,
                     fit_h, h_W_m2K, offsets, fit_initial, extensions, covariance, bootstrap, run_fits,
                     cross_validate) -> dict:
    if isinstance(friction, FrictionFit):
        friction = friction._h
    elif friction is not None:
        friction = os.fspath(friction)
    return _given(friction=friction, heat=heat, source=source, scheme=scheme, half_rail_segments=half_rail_segments,
                  time_step_s=time_step_s, every=every, ambient=ambient, alpha_start=alpha_start, fit_h=fit_h,
                  h_W_m2K=h_W_m2K, offsets=offsets, fit_initial=fit_initial, extensions=extensions,
                  covariance=covariance, bootstrap=bootstrap, run_fits=run_fits, cross_validate=cross_validate)


def fit_thermal(data, *, friction=None, heat: Optional[str] = None, source: Optional[str] = None,
                scheme: Optional[str] = None, half_rail_segments: Optional[int] = None,
                time_step_s: Optional[float] = None, every: Optional[int] = None, ambient: Optional[str] = None,
                alpha_start: Optional[float] = None, fit_h: Optional[bool] = None, h_W_m2K: Optional[float] = None,
                offsets: Optional[str] = None, fit_initial: Optional[bool] = None,
                extensions: Optional[Sequence[str]] = None, covariance: Optional[str] = None,
                bootstrap: Optional[int] = None, run_fits: Optional[bool] = None,
                cross_validate: Optional[bool] = None, name: str = "thermal") -> ThermalFit:
    """Fits α (and h, offsets, mechanisms) to thermal runs (``lmcal fit thermal``). ``data``:
    a ThermalDataSet or a manifest. ``friction``: a FrictionFit or a friction fit JSON file for
    the heat rate (its covariance carries into α's interval). Other options as the command's
    flags: heat ('auto', 'friction', 'measured'), source ('paper', 'averaged', 'moving'), scheme,
    half_rail_segments, time_step_s, every, ambient, alpha_start, fit_h, h_W_m2K, offsets
    ('auto', 'fit', 'hold'), fit_initial, extensions, covariance, bootstrap, run_fits."""
    data = load_thermal_dataset(data)
    options = _thermal_options(friction, heat, source, scheme, half_rail_segments, time_step_s, every, ambient,
                               alpha_start, fit_h, h_W_m2K, offsets, fit_initial, extensions, covariance, bootstrap,
                               run_fits, cross_validate)
    return ThermalFit(_lmcal.fit_thermal(data._h, options, name, _command("fit_thermal", options)))


def diagnose_friction(log, *, progress: Optional[Progress] = None, lrt_p: Optional[float] = None,
                      min_gain_percent: Optional[float] = None, **fit_options) -> FrictionDiagnosis:
    """What the published friction law misses, named and measured on held-out runs
    (``lmcal diagnose friction``). ``fit_options``: those of fit_friction for the baseline
    (run_offsets defaults to 'random' here)."""
    log = load_friction_log(log)
    options = _given(lrt_p=lrt_p, min_gain_percent=min_gain_percent, **fit_options)
    return FrictionDiagnosis(_lmcal.diagnose_friction(log._h, options, progress))


def diagnose_thermal(data, *, friction=None, progress: Optional[Progress] = None, lrt_p: Optional[float] = None,
                     min_gain_percent: Optional[float] = None, heat: Optional[str] = None,
                     source: Optional[str] = None, time_step_s: Optional[float] = None) -> ThermalDiagnosis:
    """What the rail model misses (``lmcal diagnose thermal``); ``friction`` as in fit_thermal."""
    data = load_thermal_dataset(data)
    options = _thermal_options(friction, heat, source, None, None, time_step_s, None, None, None, None, None, None,
                               None, None, None, None, None, None)
    options.update(_given(lrt_p=lrt_p, min_gain_percent=min_gain_percent))
    return ThermalDiagnosis(_lmcal.diagnose_thermal(data._h, options, progress))


def calibrate(folder, *, output_dir=None, diagnose: Optional[bool] = None, catalog: Optional[str] = None,
              progress: Optional[Progress] = None, covariance: Optional[str] = None, bootstrap: Optional[int] = None,
              starts: Optional[int] = None, seed: Optional[int] = None, free: Optional[Sequence[str]] = None,
              fixed: Optional[Mapping[str, float]] = None, start: Optional[Mapping[str, float]] = None,
              bounds: Optional[Mapping[str, tuple]] = None, run_offsets: Optional[str] = None,
              law_temperature: Optional[str] = None, raw: Optional[Mapping[str, Any]] = None,
              allow_outside_root: bool = False) -> Calibration:
    """The whole calibration of a measurement folder (``lmcal calibrate``): fits, spread,
    diagnoses, the calibrated model and the report. With ``output_dir`` its files are written
    there too. ``progress(step_or_detail, done, total)`` is called as it goes."""
    options = _given(diagnose=diagnose, catalog=catalog, raw=raw)
    if allow_outside_root:
        options["allow_outside_root"] = True
    options["uncertainty"] = _given(covariance=covariance, bootstrap=bootstrap)
    options["friction"] = _given(starts=starts, seed=seed, free=free, fixed=fixed, start=start, bounds=bounds,
                                 run_offsets=run_offsets, law_temperature=law_temperature)
    result = Calibration(_lmcal.calibrate(os.fspath(folder), options, progress))
    if output_dir is not None:
        result.write(output_dir)
    return result


# ---- prediction ------------------------------------------------------------------------------

class Prediction:
    """The calibrated model over a duty cycle (``lmcal predict``): each quantity a dict of
    NumPy arrays ``value``, ``low``, ``high`` (the 95 % band) over ``time_s``."""

    def __init__(self, d: dict):
        self._json = d["json"]
        self._summary = d["summary"]
        self.time_s = d["time_s"]
        self.segment = d["segment"]                    # the duty's segment at each time
        self.positions_m = d["positions_m"]
        self.temperature_C = d["temperature_C"]        # one band per position
        self.elongation_um = d["elongation_um"]
        self.scale_positions_m = d["scale_positions_m"]
        self.scale_error_um = d["scale_error_um"]      # one band per scale position
        self.friction_N = d["friction_N"]
        self.heat_rate_W = d["heat_rate_W"]

    def to_dict(self) -> dict:
        """prediction.json as `lmcal predict` writes it."""
        return json.loads(self._json)

    def summary(self) -> str:
        return self._summary

    def to_dataframe(self):
        """A pandas DataFrame (pandas is needed for this alone), one row per output time:
        time_s, segment, and each quantity with its band (NAME, NAME_low, NAME_high):
        elongation_um, friction_N, heat_rate_W, temperature_C_at_Xm per position,
        scale_error_um_at_Xm per scale position."""
        named = [("elongation_um", self.elongation_um), ("friction_N", self.friction_N), ("heat_rate_W", self.heat_rate_W)]
        named += [(_tables.at_position("temperature_C", x), b) for x, b in zip(self.positions_m, self.temperature_C)]
        named += [(_tables.at_position("scale_error_um", x), b) for x, b in zip(self.scale_positions_m, self.scale_error_um)]
        return _tables.bands(self.time_s, named, "Prediction.to_dataframe()", segment=self.segment)

    def __repr__(self) -> str:
        return "[[prediction]]\n" + self._summary


def predict(model, duty, *, samples: int = 200, seed: int = 1, allow_outside_root: bool = False) -> Prediction:
    """The calibrated model (model.toml of calibrate) over a duty cycle (TOML), with bands. The
    duty's catalog must lie inside its folder unless ``allow_outside_root``."""
    options = {"samples": samples, "seed": seed}
    return Prediction(_lmcal.predict(os.fspath(model), os.fspath(duty), samples, seed, _command("predict", options),
                                     allow_outside_root))


# ---- simulation ------------------------------------------------------------------------------

def _law(constants, effects) -> tuple[dict, dict]:
    if isinstance(constants, FrictionFit):
        return constants.constants, dict(constants.effects, **(effects or {}))
    return dict(constants or {}), dict(effects or {})


def simulate_friction(constants=None, effects: Optional[Mapping[str, float]] = None, *, velocity_m_s, load_N,
                      temperature_C, preload_um=None, block_length_mm=None, guide=None, catalog: Optional[str] = None,
                      viscosity40_mm2_s=99.0, direction=1.0) -> np.ndarray:
    """Friction force (N) of the law at each operating point; the conditions broadcast like
    NumPy arrays. ``constants``: a FrictionFit (its law: constants, effects, empirical terms;
    as its eval()), or name -> value over the paper's Eq. 8 (default: the paper's constants);
    ``effects``: name -> value of named effects. ``guide``: a catalog guide's name (built-in,
    or of ``catalog``), or names, whose preload and block length fill preload_um and
    block_length_mm where not given, as ``lmcal simulate friction --guide`` does."""
    given = dict(velocity_m_s=velocity_m_s, load_N=load_N, preload_um=preload_um, block_length_mm=block_length_mm,
                 temperature_C=temperature_C, viscosity40_mm2_s=viscosity40_mm2_s, direction=direction)
    columns, shape, _ = _columns.law_conditions(given, function="simulate_friction", guide=guide, catalog=catalog)
    if isinstance(constants, FrictionFit) and not effects:
        return _columns.law_values(constants._h.eval, columns, shape)
    k, e = _law(constants, effects)
    return _columns.law_values(lambda c: _lmcal.friction_law(k, e, c), columns, shape)


@dataclasses.dataclass
class ThermalSimulation:
    """The rail's temperature: ``temperature_C[time, sensor]`` at ``time_s`` and ``sensor_x_m``
    (from the rail centre), and the profile along the rail at the end (``x_m``, ``profile_C``)."""
    time_s: np.ndarray
    sensor_x_m: np.ndarray
    temperature_C: np.ndarray
    x_m: np.ndarray
    profile_C: np.ndarray
    heat_rate_W: float
    time_step_s: float

    def to_dict(self) -> dict:
        return {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in dataclasses.asdict(self).items()}


def simulate_thermal(*, guide: str = "SRN 35C", velocity_m_s: float = 0.11, load_N: float = 3000,
                     preload_um: Optional[float] = None, block_length_mm: Optional[float] = None,
                     contact_length_mm: Optional[float] = None, stroke_m: float = 0.2, rail_length_m: float = 0.6,
                     heat_rate_W: Optional[float] = None, constants=None, effects=None, alpha: float = 0.6,
                     h_W_m2K: float = 5.3, ambient_C=26.0, initial_C: Optional[float] = None,
                     sensors_m: Sequence[float] = (0.0, 0.05, 0.1), duration_s: float = 21600,
                     output_every_s: float = 300, time_step_s: float = 60, segments: int = 100,
                     source: str = "averaged", scheme: str = "crank-nicolson") -> ThermalSimulation:
    """One case of ``lmcal simulate thermal`` (same defaults): a catalog guide's rail heated by
    its block. The heat is the friction law's at the start temperature (``constants``: a
    FrictionFit or name -> value) unless ``heat_rate_W`` is given. ``ambient_C``: a number, or
    (times_s, temperatures_C) of an ambient trace."""
    k, e = _law(constants, effects)
    if not isinstance(ambient_C, (int, float)):
        times, temperatures = ambient_C
        ambient_C = (list(map(float, times)), list(map(float, temperatures)))
    else:
        ambient_C = float(ambient_C)
    d = _lmcal.simulate_thermal(dict(
        guide=guide, velocity_m_s=velocity_m_s, load_N=load_N, preload_um=preload_um,
        block_length_mm=block_length_mm, contact_length_mm=contact_length_mm, stroke_m=stroke_m,
        rail_length_m=rail_length_m, heat_rate_W=heat_rate_W, constants=k, effects=e, alpha=alpha,
        h_W_m2K=h_W_m2K, ambient_C=ambient_C, initial_C=initial_C, sensors_m=list(sensors_m),
        duration_s=duration_s, output_every_s=output_every_s, time_step_s=time_step_s, segments=segments,
        source=source, scheme=scheme))
    return ThermalSimulation(**d)


class GeneratedFriction(NamedTuple):
    """A virtual rig's log and its truth (friction_truth.json of ``lmcal generate friction``)."""
    log: FrictionLog
    truth: dict


def generate_friction(*, seed: int = 1, effects: Optional[Mapping[str, float]] = None,
                      constants: Optional[Mapping[str, float]] = None, guides=None, preload_um=None, load_N=None,
                      velocity_m_s=None, temperature_C=None, runs: Optional[int] = None,
                      one_setup_per_run: Optional[bool] = None, temperature_outermost: Optional[bool] = None,
                      shuffle_runs: Optional[bool] = None, noise_N: Optional[float] = None,
                      noise_ar1: Optional[float] = None, run_offset_N: Optional[float] = None,
                      temperature_noise_K: Optional[float] = None) -> GeneratedFriction:
    """A synthetic friction log with a known truth: ``lmcal generate friction`` (the virtual
    rig) in memory, the same samples for the same options and seed. ``effects``: rig effect
    name -> value (``lmcal generate effects`` lists them); ``constants``: the true law's
    (default the paper's); guides, preload_um, load_N, velocity_m_s, temperature_C: the values
    swept (a number or a list each); None: the command's default."""
    def numbers_of(name, value):
        values = np.atleast_1d(np.asarray(value))
        if values.ndim != 1 or values.dtype.kind not in "iuf":
            raise TypeError(f"{name}: expected a number or a list of numbers, got {value!r}")
        return [float(v) for v in values]

    sweeps = {name: numbers_of(name, value) for name, value in
              (("preload_um", preload_um), ("load_N", load_N), ("velocity_m_s", velocity_m_s),
               ("temperature_C", temperature_C)) if value is not None}
    options = _given(seed=seed, runs=runs, one_setup_per_run=one_setup_per_run, temperature_outermost=temperature_outermost,
                     shuffle_runs=shuffle_runs, noise_N=noise_N, noise_ar1=noise_ar1, run_offset_N=run_offset_N,
                     temperature_noise_K=temperature_noise_K, effects=_number_map(effects, "effects"),
                     constants=_number_map(constants, "constants"),
                     guides=[guides] if isinstance(guides, str) else guides, **sweeps)
    handle, truth = _lmcal.generate_friction(options)
    return GeneratedFriction(FrictionLog(handle, origin="the virtual rig"), json.loads(truth))


def guide(model: str, *, catalog: Optional[str] = None) -> dict:
    """A guide's catalog entry (built-in, or from ``catalog``): block and contact lengths,
    rail section, material."""
    return _lmcal.guide(model, catalog)


def friction_effect_names() -> list:
    """The named friction effects a fit may add."""
    return _lmcal.friction_effect_names()
