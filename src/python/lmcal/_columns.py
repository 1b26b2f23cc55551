"""Columns from Python (a dict of arrays or a pandas DataFrame) checked before they reach the
C++ core, and every complaint about them naming the column and the row: numbers for the
loaders (``prepare``), operating conditions for the friction law (``law_conditions``)."""

from collections.abc import Mapping

import numpy as np

from . import _lmcal
from ._lmcal import InputError, InvalidParameterError

# Columns the loaders keep as text (names); every other column holds numbers.
TEXT_COLUMNS = {"run", "guide"}


def items(data) -> list:
    """(name, values) of a mapping of columns or of a pandas DataFrame."""
    if isinstance(data, Mapping):
        return [(str(k), v) for k, v in data.items()]
    if hasattr(data, "columns") and hasattr(data, "__getitem__"):  # a DataFrame, without importing pandas
        return [(str(k), data[k]) for k in data.columns]
    raise TypeError(f"expected a dict of columns or a pandas DataFrame, got {type(data).__name__}")


def row_labels(data):
    """A DataFrame's index labels where they are not its rows' numbers 0, 1, ... (then an error
    names both); None otherwise."""
    index = getattr(data, "index", None)
    if index is None or isinstance(data, Mapping):
        return None
    labels = list(index)
    return None if labels == list(range(len(labels))) else labels


def text(value: str, what: str) -> str:
    """``value`` if lmcal can take it as text (UTF-8); ValueError naming ``what`` otherwise (a
    lone surrogate from a mis-decoded file, say)."""
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as e:
        raise ValueError(f"{what}: {value!r} is not valid text ({e.reason} at character {e.start}); "
                         "expected text that can be written as UTF-8") from None
    return value


def columns_error(column, row, message, labels=None) -> InputError:
    """lmcal.InputError about loaded columns, as the C++ core raises them: ``file`` "columns",
    ``row`` (0-based), ``column`` (the name), ``line`` None."""
    at = ", ".join(part for part in (f"column '{column}'" if column else "", "" if row is None else f"row {row}") if part)
    error = InputError(f"columns: {at}: {message}")
    error.file, error.line, error.row, error.column = "columns", None, row, column
    return with_label(error, labels)


def with_label(error: InputError, labels) -> InputError:
    """``error`` about columns with the DataFrame's index label of its row beside the row."""
    if labels is not None and getattr(error, "row", None) is not None and error.row < len(labels):
        error.index = labels[error.row]
        error.args = (str(error).replace(f"row {error.row}:", f"row {error.row} (index {error.index}):", 1),)
    return error


def _not_finite(a: np.ndarray, missing_allowed: bool):
    """The first offending position of ``a`` and how many there are, or None."""
    bad = np.flatnonzero(np.isinf(a) if missing_allowed else ~np.isfinite(a))
    if not bad.size:
        return None
    return int(bad[0]), bad.size


def prepare(data, missing_allowed=lambda name: False) -> tuple[list, list]:
    """Names and values for the CSV loader: equal lengths, numbers as float64 without NaN
    (except in columns where ``missing_allowed(name)``: a missing sample) or infinity, text as
    str. ValueError naming the column otherwise (and the row: lmcal.InputError)."""
    given = items(data)
    if not given:
        raise ValueError("no columns given")
    labels = row_labels(data)
    arrays = [(name, np.asarray(values)) for name, values in given]
    lengths = {name: a.shape[0] for name, a in arrays if a.ndim == 1}
    rows = max(lengths.values()) if lengths else 1
    names, columns = [], []
    for name, a in arrays:
        if a.ndim == 0:
            a = np.full(rows, a.item(), dtype=a.dtype)  # a scalar: the same value on every row
        elif a.ndim != 1:
            raise ValueError(f"column '{name}': expected one value per row, got an array of shape {a.shape}")
        if a.shape[0] != rows:
            longest = max(lengths, key=lengths.get)
            raise ValueError(f"column '{name}' has {a.shape[0]} rows, column '{longest}' has {rows}: "
                             "every column needs one value per row")
        names.append(text(name, "a column's name") if isinstance(name, str) else name)
        if name in TEXT_COLUMNS or a.dtype.kind in "OUS":
            columns.append([text("" if v is None else str(v), f"column '{name}', row {row}")
                            for row, v in enumerate(a.tolist())])
            continue
        if a.dtype.kind not in "iuf":
            raise ValueError(f"column '{name}': expected numbers, got values of dtype {a.dtype}")
        a = a.astype(np.float64)
        if bad := _not_finite(a, missing_allowed(name)):
            row, count = bad
            raise columns_error(name, row, f"{name} = {a[row]}: expected a finite number ({count} of {rows} rows are "
                                           "not: drop or fill them first)", labels)
        columns.append(a)
    return names, columns


# ---- the friction law's conditions ------------------------------------------------------------

# The law's five conditions, needed; then those with a default; then what a log's columns hold
# that is no condition (a log's or a fit's DataFrame passes as conditions).
LAW = ("velocity_m_s", "load_N", "preload_um", "block_length_mm", "temperature_C")
DEFAULTS = {"viscosity40_mm2_s": 99.0, "direction": 1.0}
MOTION = ("acceleration_m_s2", "position_m", "distance_since_reversal_m")  # 0 unless given
NOT_CONDITIONS = {"time_s", "line", "friction_N", "measured_N", "predicted_N", "residual_N", "sigma_N"}


def condition_error(name: str, row, message: str) -> InvalidParameterError:
    """lmcal.InvalidParameterError about a condition: ``parameter`` its name, ``row`` where (an
    index for an N-d condition), in the words of the C++ core's: "row 3: load_N = -5 is ..."."""
    error = InvalidParameterError(f"{'row' if isinstance(row, int) else 'index'} {row}: {message}")
    error.parameter, error.row = name, row
    return error


def _position(flat: int, shape: tuple):
    """A flat position as the caller sees it: the row of a column, the index of an N-d array."""
    return flat if len(shape) <= 1 else tuple(int(i) for i in np.unravel_index(flat, shape))


def _from_guides(guides, catalog, wanted: list) -> dict:
    """``wanted`` (preload_um, block_length_mm) of each guide name in ``guides``, from the
    catalog, as arrays of the guides' shape."""
    names = np.asarray(guides, dtype=object)
    specs = {}
    for model in set(names.ravel().tolist()):
        if not isinstance(model, str) or not model:
            raise ValueError(f"guide: expected a catalog guide's name, got {model!r}")
        specs[model] = _lmcal.guide(model, catalog)
    out = {}
    for field in wanted:
        for model, spec in specs.items():
            if field not in spec:
                raise ValueError(f"guide '{model}' has no {field} in the catalog ({spec['source']}): give {field}")
        out[field] = np.vectorize(lambda m: specs[m][field], otypes=[float])(names) if names.ndim else specs[str(names)][field]
    return out


def law_conditions(given: Mapping, *, function: str, defaults=None, guide=None, catalog=None):
    """The conditions of ``given`` (name -> array or number) for the friction law: broadcast,
    flattened to float64 columns, checked (numbers, finite), the missing ones from ``defaults``,
    preload and block length from ``guide`` (catalog names) when not given. Returns (columns,
    shape, runs: the ``run`` names broadcast, or None)."""
    given = {k: v for k, v in given.items() if v is not None}
    unknown = set(given) - set(LAW) - set(DEFAULTS) - set(MOTION) - NOT_CONDITIONS - TEXT_COLUMNS
    if unknown:
        raise ValueError(f"{function}: unknown condition {', '.join(sorted(map(repr, unknown)))}; expected "
                         f"{', '.join(LAW + tuple(DEFAULTS) + MOTION)}, guide or run")
    guide = given.pop("guide", None) if guide is None else guide
    runs = given.pop("run", None)
    wanted = [k for k in ("preload_um", "block_length_mm") if k not in given]
    if guide is not None and wanted:
        given.update(_from_guides(guide, catalog, wanted))
    given = {**DEFAULTS, **(defaults or {}), **given}
    missing = [name for name in LAW if name not in given]
    if missing:
        raise ValueError(f"{function}: no {', '.join(missing)} given (preload_um and block_length_mm may come from "
                         "guide=, a catalog guide's name)")
    arrays = {}
    for name in LAW + tuple(DEFAULTS) + MOTION:
        if name not in given:
            continue
        a = np.asarray(given[name])
        if a.dtype.kind not in "iuf":
            what = f"values of dtype {a.dtype}" if a.ndim else f"{type(given[name]).__name__} {given[name]!r}"
            raise TypeError(f"{function}: {name}: expected numbers, got {what}")
        a = a.astype(np.float64)
        if bad := _not_finite(a.ravel(), False):
            flat, count = bad
            raise condition_error(name, _position(flat, a.shape), f"{name} = {a.ravel()[flat]}: expected a finite "
                                                                  f"number ({count} of {a.size} values are not)")
        arrays[name] = a
    if runs is not None:
        arrays["run"] = np.asarray(runs, dtype=object)
    try:
        broadcast = dict(zip(arrays, np.broadcast_arrays(*arrays.values())))
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(v)}" for k, v in arrays.items() if np.ndim(v))
        raise ValueError(f"{function}: the conditions' shapes do not broadcast together: {shapes}") from None
    shape = next(iter(broadcast.values())).shape
    runs = broadcast.pop("run").ravel() if "run" in broadcast else None
    return {k: np.ascontiguousarray(v).ravel() for k, v in broadcast.items()}, shape, runs


def law_values(evaluate, columns: dict, shape: tuple) -> np.ndarray:
    """``evaluate(columns)`` (the C++ law) shaped as the conditions, a refused row named as the
    caller's position (the index of an N-d condition)."""
    try:
        return evaluate(columns).reshape(shape)
    except InvalidParameterError as e:
        row = getattr(e, "row", None)
        if row is not None and len(shape) > 1:
            e.row = _position(row, shape)
            e.args = (str(e).replace(f"row {row}:", f"index {e.row}:", 1),)
        raise
