"""The fit report of a result's repr: lmfit's layout (fit statistics, variables with their
standard error, relative error and start value, the strong correlations), with lmcal's
interval, its method and the solver's verdict."""

import math


def _number(value, digits=6):
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "nan"
    return f"{value:.{digits}g}"


def fit_report(title, fit_dict, statistics, min_correlation=0.1):
    """Text of a fit: `fit_dict` is a fit's JSON as a dict (parameters, correlation, solver,
    uncertainty), `statistics` (label, value) pairs shown under [[Fit Statistics]]."""
    parameters = fit_dict["parameters"]
    solver = fit_dict.get("solver", {})
    uncertainty = fit_dict.get("uncertainty", {})
    lines = [f"[[{title}]]"]
    lines.append("[[Fit Statistics]]")
    rows = [("data points", fit_dict.get("residuals")), ("variables", fit_dict.get("free_parameters"))]
    rows += statistics
    rows.append(("converged", f"{solver.get('converged')} ({solver.get('termination', '')})"))
    if solver.get("starts"):
        rows.append(("starts at the best minimum", f"{solver.get('starts_agreed')} of {solver.get('starts')}"))
    method = uncertainty.get("method")
    if method:
        rows.append(("intervals", f"95 %, covariance '{method}': {uncertainty.get('reason', '')}"))
    for label, value in rows:
        text = _number(value) if isinstance(value, float) else str(value)
        lines.append(f"    {label + ':':<29}{text}")

    model = [p for p in parameters if not p.get("per_run")]
    width = max([len(p["name"]) for p in model] + [4])
    lines.append("[[Variables]]")
    for p in model:
        value, se = p.get("value"), p.get("se")
        unit = "" if p.get("unit") in (None, "", "1") else f" {p['unit']}"
        if not p.get("free"):
            lines.append(f"    {p['name'] + ':':<{width + 1}} {_number(value, 8)}{unit} (fixed)")
            continue
        if p.get("held_unidentifiable"):
            lines.append(f"    {p['name'] + ':':<{width + 1}} {_number(value, 8)}{unit} (held: not identifiable)")
            continue
        relative = ""
        if se is not None and value not in (None, 0) and math.isfinite(se):
            relative = f" ({abs(se / value) * 100:.2f}%)"
        interval = p.get("ci95")  # the interval the text quotes ("interval" says which)
        ci = ""
        if interval and None not in interval:
            ci = f" [{_number(interval[0])}, {_number(interval[1])}]{' profile' if p.get('interval') == 'profile' else ''}"
        bound = " (at bound)" if p.get("at_bound") else ""
        lines.append(f"    {p['name'] + ':':<{width + 1}} {_number(value, 8)} +/- {_number(se, 4)}{relative}{unit}"
                     f"{ci}{bound} (init = {_number(p.get('start'))})")
    nuisance = len(parameters) - len(model)
    if nuisance:
        lines.append(f"    (+ {nuisance} per-run nuisance parameters: offsets, start temperatures; see to_dict())")

    names = [p["name"] for p in parameters]
    matrix = (fit_dict.get("correlation") or {}).get("matrix") or []
    pairs = []
    shown = {p["name"] for p in model}
    for i, row in enumerate(matrix):
        for j in range(i + 1, len(row)):
            r = row[j]
            if r is not None and math.isfinite(r) and abs(r) >= min_correlation and names[i] in shown and names[j] in shown:
                pairs.append((abs(r), names[i], names[j], r))
    if pairs:
        lines.append(f"[[Correlations]] (unreported correlations are < {min_correlation:.3f})")
        for _, a, b, r in sorted(pairs, reverse=True):
            lines.append(f"    C({a}, {b}){'':<{max(0, 2 * width - len(a) - len(b))}} = {r:+.4f}")
    for issue in (fit_dict.get("identifiability") or {}).get("issues", []):
        lines.append(f"[[Not identifiable]] {issue.get('why', '')}")
    for warning in fit_dict.get("warnings", []):
        lines.append(f"[[Warning]] {warning}")
    return "\n".join(lines)
