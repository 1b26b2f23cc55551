"""The Python package as lmfit users expect it (issue 41 #8): ``init`` the start, starts and
fixed values inside their bounds, errors from columns naming the column and the row, a fit
evaluated at new conditions (``eval``), ``plot()`` and ``to_dataframe()`` with their optional
packages imported only when asked for, ``simulate_friction(guide=...)`` and the virtual rig in
memory (``generate_friction``), each checked against the command where the command has it.

Run by ctest (test `python`), as test_lmcal.py."""

import json
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import lmcal

SOURCE = os.environ.get("LMCAL_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("LMCAL_CLI", "lmcal")
SET = os.path.join(SOURCE, "measurements", "cheng2017")
THERMAL_TOML = os.path.join(SET, "thermal.toml")
MODEL = os.path.join(SOURCE, "fits", "cheng2017", "model.toml")
DUTY = os.path.join(SOURCE, "examples", "duty", "two_shifts.toml")
PAPER = {"k1": 0.315, "k2": 0.03, "mu_st": 1.52, "v_st_m_s": 0.015, "mu_v": 0.003, "beta_per_K": 0.067, "f0": 0.029}


def cli(*args):
    return subprocess.run([CLI, *map(str, args)], check=True, capture_output=True, text=True)


def read_csv(path) -> dict:
    """A CSV the command wrote as columns (numbers as floats where every cell is one)."""
    lines = [line for line in open(path).read().splitlines() if not line.startswith("#")]
    header, rows = lines[0].split(","), [line.split(",") for line in lines[1:]]
    columns = {}
    for j, name in enumerate(header):
        cells = [row[j] for row in rows]
        try:
            columns[name] = np.array([float(c) for c in cells])
        except ValueError:
            columns[name] = cells
    return columns


@pytest.fixture(scope="module")
def rig():
    """Three runs of the virtual rig with a seal drag the published law lacks."""
    return lmcal.generate_friction(seed=3, runs=3, effects={"seal_drag": 40})


@pytest.fixture(scope="module")
def fit(rig):
    """The law with the seal drag, the temperature as logged (eval then reproduces predicted_N)."""
    return lmcal.fit_friction(rig.log, effects=["seal_drag"], law_temperature="logged")


def combination_law_fit():
    """A log of one setup without its load, preload and block length: the law in combinations."""
    one = lmcal.generate_friction(seed=2, runs=2, guides="SRN 35C", preload_um=4, load_N=2000, temperature_C=26)
    c = one.log.columns()
    return lmcal.fit_friction({k: v for k, v in c.items() if k not in ("load_N", "preload_um", "block_length_mm", "guide")})


@pytest.fixture(scope="module")
def thermal_fit():
    return lmcal.fit_thermal(THERMAL_TOML, run_fits=False)


# ---- init, start, fixed, bounds --------------------------------------------------------------

def test_init_is_the_start_fixed_or_given_for_friction_and_thermal(rig, thermal_fit):
    held = lmcal.fit_friction(rig.log, fixed={"k2": 0.05}, start={"mu_st": 1.4}, run_fits=False)
    assert held.params["k2"].init == held.params["k2"].value == 0.05 and not held.params["k2"].free
    assert held.params["mu_st"].init == 1.4 and held.params["mu_st"].value != 1.4
    assert held.params["k1"].init == PAPER["k1"]
    assert thermal_fit.params["alpha"].init == 0.6 and thermal_fit.params["alpha"].value != 0.6
    assert lmcal.fit_thermal(THERMAL_TOML, alpha_start=0.45, run_fits=False).params["alpha"].init == 0.45


@pytest.mark.parametrize("options, parameter, words", [
    ({"fixed": {"k2": -2.0}}, "k2", "fixed = -2 is outside its bounds [-1, 1]"),
    ({"start": {"k1": 9.0}}, "k1", "start = 9 is outside its bounds [0, 5]"),
    ({"fixed": {"mu_v": 0.5}, "bounds": {"mu_v": (0.0, 0.2)}}, "mu_v", "fixed = 0.5 is outside its bounds [0, 0.2]"),
    ({"bounds": {"k1": (1.0, 2.0)}}, "k1", "the paper's start 0.315 is outside the bounds given [1, 2]"),
    ({"bounds": {"f0": (0.5, -0.5)}}, "f0", "bounds=(0.5, -0.5): expected finite low < high"),
])
def test_a_start_or_fixed_value_outside_its_bounds_is_refused_naming_it(rig, options, parameter, words):
    for call in (lambda: lmcal.fit_friction(rig.log, **options), lambda: lmcal.calibrate(SET, diagnose=False, **options)):
        with pytest.raises(lmcal.InvalidParameterError) as e:
            call()
        assert isinstance(e.value, ValueError) and e.value.parameter == parameter
        assert str(e.value) == f"{parameter}: {words}" + (": give a value inside them, or bounds that contain it"
                                                          if "fixed" in words or "start =" in words else
                                                          ": give a start inside them (start=)" if "paper" in words else "")


def test_a_value_on_its_bound_is_inside_and_a_thermal_start_outside_is_refused(rig):
    assert lmcal.fit_friction(rig.log, fixed={"k2": -1.0}, run_fits=False).params["k2"].value == -1.0
    with pytest.raises(lmcal.InvalidParameterError, match=r"alpha = 1.5 .* inside the bounds \[0, 1\]") as e:
        lmcal.fit_thermal(THERMAL_TOML, alpha_start=1.5, run_fits=False)
    assert e.value.parameter == "alpha"


# ---- errors from columns ---------------------------------------------------------------------

def test_an_error_from_a_dataframe_names_column_row_and_index_label(rig):
    pd = pytest.importorskip("pandas")
    frame = rig.log.to_dataframe().iloc[:20].copy()
    frame.index = pd.date_range("2024-03-01 08:00", periods=20, freq="s")
    frame.iloc[7, frame.columns.get_loc("load_N")] = -5.0          # refused by the loader's rules
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(frame)
    assert (e.value.file, e.value.row, e.value.column, e.value.line) == ("columns", 7, "load_N", None)
    assert str(e.value).startswith("columns: column 'load_N', row 7 (index 2024-03-01 08:00:07): load_N = -5")
    frame.iloc[7, frame.columns.get_loc("load_N")] = np.nan         # refused before the loader
    with pytest.raises(lmcal.InputError, match=r"column 'load_N', row 7 \(index 2024-03-01 08:00:07\): load_N = nan") as e:
        lmcal.fit_friction(frame)
    assert (e.value.row, e.value.column) == (7, "load_N")
    # A problem of the whole column (none missing) has no row.
    frame.iloc[7, frame.columns.get_loc("load_N")] = 2000.0
    with pytest.raises(lmcal.InputError, match="missing column 'friction_N'") as e:
        lmcal.load_friction_log(frame.drop(columns=["friction_N"]))
    assert e.value.row is None and e.value.column is None


def test_an_error_in_a_unit_converted_column_or_a_trace_names_it(rig):
    c = rig.log.columns()
    c["temperature_K"] = c.pop("temperature_C") + 273.15
    c["temperature_K"][11] = -3.0
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(c)
    assert (e.value.row, e.value.column) == (11, "temperature_K") and "temperature_K = -3" in str(e.value)
    c = rig.log.columns()
    c["run"][5] = "r\x07n"  # a message without the column's name: the column from where the cell is
    with pytest.raises(lmcal.InputError, match="column 'run', row 5: run name: control character U\\+0007") as e:
        lmcal.load_friction_log(c)
    assert (e.value.row, e.value.column) == (5, "run")
    data = lmcal.load_thermal_dataset(THERMAL_TOML)
    run = data.runs[0]
    trace = {k: np.array(v, dtype=float) for k, v in run["trace"].items()}
    trace["time_s"][4] = np.nan
    with pytest.raises(lmcal.InputError) as e:
        data.with_trace(run["id"], trace)
    assert (e.value.row, e.value.column) == (4, "time_s")
    trace["time_s"][4] = trace["time_s"][2]  # time going back: the loader's rule
    with pytest.raises(lmcal.InputError) as e:
        data.with_trace(run["id"], trace)
    assert (e.value.row, e.value.column) == (4, "time_s")
    assert "not later than the previous row's (row 3)" in str(e.value)  # the row, not the temporary file's line


def test_a_file_error_keeps_its_line_and_column():
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(os.path.join(SOURCE, "no_such_log.csv"))
    assert e.value.row is None and isinstance(e.value.line, int)


# ---- eval ------------------------------------------------------------------------------------

def test_eval_at_the_logs_conditions_is_the_fits_prediction(fit, rig):
    c = rig.log.columns()
    np.testing.assert_allclose(fit.eval(c), fit.predicted_N, rtol=1e-12, atol=1e-12)
    # Without the runs: the law alone, each run's zero offset taken out.
    c.pop("run")
    offsets = np.array([fit.run_offset_N[r] for r in rig.log.columns()["run"]])
    assert np.ptp(offsets) > 0.05
    np.testing.assert_allclose(fit.eval(c), fit.predicted_N - offsets, rtol=1e-12, atol=1e-12)
    # A DataFrame (the log's) passes as conditions too.
    pytest.importorskip("pandas")
    np.testing.assert_allclose(fit.eval(rig.log.to_dataframe()), fit.predicted_N, rtol=1e-12, atol=1e-12)


def test_eval_is_the_fitted_law_with_its_effects_broadcast(fit):
    v = np.linspace(0.005, 0.15, 30)[:, None]
    load = np.array([1000.0, 2000.0, 3000.0])[None, :]
    got = fit.eval(velocity_m_s=v, load_N=load, preload_um=2.5, block_length_mm=120.2, temperature_C=30)
    assert got.shape == (30, 3)
    assert fit.effects["seal_drag"] > 10
    law = lmcal.simulate_friction(fit.constants, fit.effects, velocity_m_s=v, load_N=load, preload_um=2.5,
                                  block_length_mm=120.2, temperature_C=30)
    np.testing.assert_allclose(got, law, rtol=1e-13)
    without = lmcal.simulate_friction(fit.constants, velocity_m_s=v, load_N=load, preload_um=2.5, block_length_mm=120.2,
                                      temperature_C=30)
    assert np.all(got - without > 0.5 * fit.effects["seal_drag"] * v ** 2)  # the seal drag is in it
    # Keywords win over the mapping; a catalog guide fills preload and block length.
    by_guide = fit.eval({"velocity_m_s": v, "load_N": 5.0}, load_N=load, guide="SRN 35C", temperature_C=30)
    np.testing.assert_allclose(by_guide, fit.eval(velocity_m_s=v, load_N=load, preload_um=4.0, block_length_mm=120.2,
                                                  temperature_C=30), rtol=1e-15)


def test_eval_refuses_bad_conditions_naming_them(fit):
    base = dict(velocity_m_s=[0.01, 0.02, 0.05], load_N=2000, preload_um=2.5, block_length_mm=100, temperature_C=26)
    with pytest.raises(lmcal.InvalidParameterError) as e:
        fit.eval(base, velocity_m_s=[0.01, np.nan, 0.05])
    assert (e.value.parameter, e.value.row) == ("velocity_m_s", 1) and str(e.value).startswith("row 1: velocity_m_s = nan")
    with pytest.raises(lmcal.InvalidParameterError) as e:
        fit.eval(base, load_N=[2000, 2000, -1])
    assert (e.value.parameter, e.value.row) == ("load_N", 2) and str(e.value).startswith("row 2: load_N = -1")
    with pytest.raises(lmcal.InvalidParameterError) as e:
        fit.eval(base, velocity_m_s=[[0.01, 0.02], [0.03, -0.04]])
    assert (e.value.parameter, e.value.row) == ("velocity_m_s", (1, 1)) and str(e.value).startswith("index (1, 1):")
    with pytest.raises(lmcal.InvalidParameterError, match="direction = 0.5 is invalid: expected \\+1 or -1"):
        fit.eval(base, direction=0.5)
    with pytest.raises(lmcal.InvalidParameterError) as e:
        fit.eval(base, run=["run01", "run09", "run02"])
    assert (e.value.parameter, e.value.row) == ("run", 1) and "its runs are run01, run02, run03" in str(e.value)
    with pytest.raises(ValueError, match="unknown condition 'load_kN'"):
        fit.eval(base, load_kN=2)
    with pytest.raises(ValueError, match="no temperature_C given"):
        fit.eval({k: v for k, v in base.items() if k != "temperature_C"})
    with pytest.raises(ValueError, match="guide 'SRG 25C' has no preload_um in the catalog"):
        fit.eval({k: v for k, v in base.items() if k != "preload_um"}, guide="SRG 25C")
    with pytest.raises(TypeError, match="load_N: expected numbers, got str 'heavy'"):
        fit.eval(base, load_N="heavy")


def test_eval_of_a_combination_law_defaults_to_the_setup_it_was_fitted_at():
    v = np.array([0.01, 0.1])
    lean = combination_law_fit()
    np.testing.assert_allclose(lean.eval(velocity_m_s=v, temperature_C=26),
                               lean.eval(velocity_m_s=v, temperature_C=26, load_N=1000, preload_um=1, block_length_mm=1))


# ---- simulate_friction(guide=) ---------------------------------------------------------------

def test_simulate_friction_with_a_guide_is_the_commands(tmp_path):
    out = tmp_path / "sweep.csv"
    cli("simulate", "friction", "--guide", "SRN 35C", "--load", "2500", "--temperature", "31", "-o", out)
    expected = read_csv(out)
    got = lmcal.simulate_friction(velocity_m_s=expected["velocity_m_s"], load_N=2500, temperature_C=31, guide="SRN 35C")
    np.testing.assert_allclose(got, expected["friction_N"], rtol=1e-12)
    spec = lmcal.guide("SRN 35C")
    assert set(expected["preload_um"]) == {spec["preload_um"]} and set(expected["block_length_mm"]) == {spec["block_length_mm"]}
    # A value given wins over the catalog's, as --preload does.
    np.testing.assert_allclose(
        lmcal.simulate_friction(velocity_m_s=0.1, load_N=2500, temperature_C=31, guide="SRN 35C", preload_um=1.5),
        lmcal.simulate_friction(velocity_m_s=0.1, load_N=2500, temperature_C=31, preload_um=1.5,
                                block_length_mm=spec["block_length_mm"]), rtol=1e-15)
    with pytest.raises(ValueError, match="no preload_um, block_length_mm given"):
        lmcal.simulate_friction(velocity_m_s=0.1, load_N=2500, temperature_C=31)
    with pytest.raises(lmcal.InvalidParameterError, match="guide: unknown model 'NO SUCH GUIDE'"):
        lmcal.simulate_friction(velocity_m_s=0.1, load_N=2500, temperature_C=31, guide="NO SUCH GUIDE")


def test_simulate_friction_takes_a_guide_per_condition():
    guides = np.array(["SRN 35C", "SRG 45C"])
    got = lmcal.simulate_friction(velocity_m_s=0.05, load_N=2000, temperature_C=30, guide=guides, preload_um=2.5)
    for one, value in zip(guides, got):
        assert value == lmcal.simulate_friction(velocity_m_s=0.05, load_N=2000, temperature_C=30, preload_um=2.5,
                                                block_length_mm=lmcal.guide(one)["block_length_mm"])
    assert got[0] != got[1]


# ---- to_dataframe ----------------------------------------------------------------------------

def test_a_friction_fits_dataframe_is_its_samples_file(fit, tmp_path):
    pytest.importorskip("pandas")
    fit.write(tmp_path)
    expected = read_csv(tmp_path / "friction_samples.csv")
    df = fit.to_dataframe()
    assert len(df) == len(fit.measured_N)
    shared = [name for name in expected if name in df.columns]
    assert set(expected) - set(shared) == {"line"}  # a generated log has no lines
    for name in shared:
        if isinstance(expected[name], list):
            assert df[name].tolist() == expected[name], name
        else:
            np.testing.assert_allclose(df[name].to_numpy(dtype=float), expected[name], rtol=1e-15, err_msg=name)
    p = fit.to_dataframe("parameters")
    assert list(p.index) == list(fit.params) and p.loc["seal_drag", "unit"] == "N s2/m2"
    assert p.loc["k1", "value"] == fit.params["k1"].value and p.loc["k1", "ci95_high"] == fit.params["k1"].ci[1]
    assert p.loc["k1", "init"] == PAPER["k1"]
    with pytest.raises(ValueError, match="table: unknown 'residuals'"):
        fit.to_dataframe("residuals")
    # Conditions the log did not give are not data: not columns.
    lean = combination_law_fit().to_dataframe()
    assert "load_N" not in lean.columns and "velocity_m_s" in lean.columns


def test_a_thermal_fits_dataframe_is_its_samples_file(thermal_fit, tmp_path):
    pytest.importorskip("pandas")
    thermal_fit.write(tmp_path)
    expected = read_csv(tmp_path / "thermal_samples.csv")
    df = thermal_fit.to_dataframe()
    assert df.columns.tolist() == ["run", "sensor", "time_s", "measured_C", "simulated_C", "residual_K"]
    assert df["run"].tolist() == expected["run"] and df["sensor"].tolist() == expected["sensor"]
    for name in ("time_s", "measured_C", "simulated_C", "residual_K"):
        np.testing.assert_allclose(df[name].to_numpy(), expected[name], rtol=1e-15, atol=1e-15, err_msg=name)
    assert thermal_fit.to_dataframe("parameters").loc["alpha", "unit"] == "1"


def test_a_diagnosis_dataframe_lists_every_cause_tried(rig):
    pytest.importorskip("pandas")
    diagnosis = lmcal.diagnose_friction(rig.log)
    d = diagnosis.to_dict()
    df = diagnosis.to_dataframe()
    assert len(df) == sum(len(r) for r in d["rounds"]) and df["round"].max() == len(d["rounds"])
    assert df[df["accepted"]]["cause"].tolist() == [c["effect"] for c in diagnosis.causes] == ["seal_drag"]
    seal = df[df["accepted"]].iloc[0]
    assert seal["unit"] == "N s2/m2" and seal["ci95_low"] < 40 < seal["ci95_high"]
    assert {"value", "se", "lrt_p", "cv_rmse_N", "cv_gain_percent", "reason"} <= set(df.columns)


def test_a_predictions_dataframe_is_its_time_file(tmp_path):
    pytest.importorskip("pandas")
    cli("predict", MODEL, DUTY, "-o", tmp_path, "--samples", "30")
    p = lmcal.predict(MODEL, DUTY, samples=30)
    df = p.to_dataframe()
    long = read_csv(tmp_path / "prediction_time.csv")
    checked = 0
    for quantity, positions in (("temperature_C", p.positions_m), ("scale_error_um", p.scale_positions_m)):
        for x in positions:
            rows = [i for i, (q, at) in enumerate(zip(long["quantity"], long["position_m"]))
                    if q == quantity and at and float(at) == x]
            for band in ("value", "low", "high"):
                column = f"{quantity}_at_{x:g}m" + ("" if band == "value" else f"_{band}")
                np.testing.assert_allclose(df[column].to_numpy(), long[band][rows], rtol=1e-12, err_msg=column)
                checked += 1
            assert df["segment"].tolist() == [long["segment"][i] for i in rows]
    assert checked >= 6
    assert {"elongation_um", "elongation_um_low", "elongation_um_high", "friction_N", "heat_rate_W"} <= set(df.columns)
    np.testing.assert_array_equal(df["elongation_um_high"].to_numpy(), p.elongation_um["high"])


def test_without_pandas_to_dataframe_says_what_to_install(fit, thermal_fit, rig, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas now fails
    prediction = lmcal.predict(MODEL, DUTY, samples=20)
    for call, name in ((fit.to_dataframe, "FrictionFit"), (thermal_fit.to_dataframe, "ThermalFit"),
                       (rig.log.to_dataframe, "FrictionLog"), (prediction.to_dataframe, "Prediction")):
        with pytest.raises(ImportError, match=f"{name}.to_dataframe\\(\\) needs pandas, which is not installed: "
                                              "`apt-get install python3-pandas`"):
            call()


def test_import_lmcal_imports_neither_pandas_nor_matplotlib():
    code = ("import sys, lmcal; lmcal.fit_friction(lmcal.generate_friction(runs=2).log, run_fits=False); "
            "print(sorted(m for m in ('pandas', 'matplotlib') if m in sys.modules))")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=dict(os.environ))
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


# ---- plot ------------------------------------------------------------------------------------

@pytest.fixture()
def pyplot():
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    yield plt
    plt.close("all")


def test_a_friction_fits_plot_draws_every_sample_both_ways(fit, rig, pyplot):
    fig = fit.plot()
    assert isinstance(fig, pyplot.Figure)
    left, right = fig.axes
    for ax in (left, right):
        points = [c.get_offsets() for c in ax.collections]
        assert sum(len(p) for p in points) == len(fit.measured_N)
        assert len(points) == 2  # forward and backward
    residuals = np.concatenate([c.get_offsets()[:, 1] for c in right.collections])
    np.testing.assert_allclose(np.sort(residuals), np.sort(fit.residual_N), rtol=1e-12)
    assert right.get_xscale() == "log" and right.get_xlabel() == "velocity (m/s)"
    assert any("RMSE" in text.get_text() for text in fig.texts)
    assert fit.plot(x="temperature_C").axes[1].get_xlabel() == "temperature (°C)"
    with pytest.raises(ValueError, match="x: unknown 'speed'"):
        fit.plot(x="speed")


def test_a_thermal_fits_plot_draws_measured_and_simulated(thermal_fit, pyplot):
    fig = thermal_fit.plot()
    top, bottom = fig.axes
    n = len(thermal_fit.samples["time_s"])
    assert sum(len(line.get_xdata()) for line in top.lines) == 2 * n
    assert sum(len(line.get_xdata()) for line in bottom.lines if line.get_linestyle() == "None") == n
    run = thermal_fit.run_names[1]
    one = thermal_fit.plot(run=run)
    assert sum(len(line.get_xdata()) for line in one.axes[0].lines) == \
        2 * int(np.sum(thermal_fit.samples["run"] == 1))
    with pytest.raises(ValueError, match="no run 'v999'"):
        thermal_fit.plot(run="v999")


def test_without_matplotlib_plot_says_what_to_install(fit, thermal_fit, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    for call, name in ((fit.plot, "FrictionFit"), (thermal_fit.plot, "ThermalFit")):
        with pytest.raises(ImportError, match=f"{name}.plot\\(\\) needs matplotlib, which is not installed: "
                                              "`apt-get install python3-matplotlib`"):
            call()


# ---- the virtual rig -------------------------------------------------------------------------

def test_generate_friction_is_the_commands_virtual_rig(tmp_path):
    cli("generate", "friction", "-o", tmp_path, "--seed", "5", "--runs", "2", "--guide", "SRN 35C,SRG 45C",
        "--temperature", "24,36", "--effect", "seal_drag=30", "--effect", "direction_asymmetry=0.02")
    made = lmcal.generate_friction(seed=5, runs=2, guides=["SRN 35C", "SRG 45C"], temperature_C=[24, 36],
                                   effects={"seal_drag": 30, "direction_asymmetry": 0.02})
    from_file = lmcal.load_friction_log(tmp_path / "friction.csv").columns()
    columns = made.log.columns()
    assert len(made.log) == len(from_file["run"]) > 1000
    for name, values in from_file.items():
        if values.dtype == object:
            assert columns[name].tolist() == values.tolist(), name
        else:
            np.testing.assert_array_equal(columns[name], values, err_msg=name)
    assert made.truth == json.loads((tmp_path / "friction_truth.json").read_text())
    assert made.truth["effects"]["seal_drag"]["value"] == 30
    assert "from the virtual rig" in repr(made.log)
    log, truth = made  # a named pair
    assert truth is made.truth


def test_generate_friction_refuses_what_the_rig_does_not_have():
    with pytest.raises(lmcal.InvalidParameterError, match="no_such_effect"):
        lmcal.generate_friction(effects={"no_such_effect": 1.0})
    with pytest.raises(lmcal.InvalidParameterError, match="noise_ar1"):
        lmcal.generate_friction(noise_ar1=1.5)
    with pytest.raises(TypeError, match="load_N: expected a number or a list of numbers"):
        lmcal.generate_friction(load_N="heavy")
    truth = lmcal.generate_friction(runs=1, constants={"k1": 0.4}).truth
    assert truth["friction_constants"]["k1"] == 0.4 and not math.isnan(truth["noise_N"])
