"""Columns from Python (a dict of arrays or a pandas DataFrame) checked before they reach the
C++ core, and every complaint about them naming the column and the row: numbers for the
loaders (``prepare``)."""

from collections.abc import Mapping

import numpy as np

from ._lmcal import InputError

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

