"""The Python package end to end on the bundled measurements: the same numbers as the `lmcal`
command for the same inputs (to 1e-10), columns and DataFrames in, errors as Python
exceptions, progress, the GIL released during the long calls.

Run by ctest (test `python`) with PYTHONPATH at the build's python folder, LMCAL_CLI the
command and LMCAL_SOURCE the source tree."""

import json
import math
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import lmcal

SOURCE = os.environ.get("LMCAL_SOURCE", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("LMCAL_CLI", "lmcal")
SET = os.path.join(SOURCE, "measurements", "cheng2017")
FRICTION_CSV = os.path.join(SET, "friction.csv")
THERMAL_TOML = os.path.join(SET, "thermal.toml")

# Keys that differ by nature between two runs of the same fit: the command that made it and
# the wall time.
VOLATILE = {"command", "seconds"}
# What `calibrate` adds to every JSON file it writes (where it came from); a result's to_dict()
# describes the result alone.
PROVENANCE = {"calibration_options", "software", "inputs", "options"}


def assert_same(a, b, path="", rel=1e-10):
    """Equal JSON values: numbers to `rel` (relative, or absolute below 1), the rest exactly."""
    if isinstance(a, dict):
        assert isinstance(b, dict), path
        from_file_only = PROVENANCE - set(a) if "." not in path and "[" not in path else set()  # the top level
        assert set(a) - VOLATILE == set(b) - VOLATILE - from_file_only, f"{path}: keys {sorted(set(a) ^ set(b))}"
        for k in a:
            if k not in VOLATILE:
                assert_same(a[k], b[k], f"{path}.{k}", rel)
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_same(x, y, f"{path}[{i}]", rel)
    elif isinstance(a, float) or isinstance(b, float):
        assert isinstance(a, (int, float)) and isinstance(b, (int, float)), f"{path}: {a!r} vs {b!r}"
        assert abs(a - b) <= rel * max(1.0, abs(a), abs(b)), f"{path}: {a!r} vs {b!r}"
    else:
        assert a == b, f"{path}: {a!r} vs {b!r}"


def cli(*args, cwd=None):
    return subprocess.run([CLI, *args], check=True, capture_output=True, text=True, cwd=cwd)


@pytest.fixture(scope="module")
def friction_fit():
    return lmcal.fit_friction(FRICTION_CSV)


@pytest.fixture(scope="module")
def cli_friction(tmp_path_factory):
    out = tmp_path_factory.mktemp("cli_friction")
    cli("fit", "friction", FRICTION_CSV, "-o", str(out))
    return out


def test_friction_fit_equals_the_command(friction_fit, cli_friction):
    expected = json.loads((cli_friction / "friction.json").read_text())
    assert_same(friction_fit.to_dict(), expected)


def test_friction_fit_writes_the_commands_files(friction_fit, cli_friction, tmp_path):
    friction_fit.write(tmp_path)
    for name in ("friction_samples.csv", "friction_conditions.csv"):
        assert (tmp_path / name).read_text() == (cli_friction / name).read_text(), name
    assert not list(tmp_path.glob("*.tmp"))


def test_friction_fit_fields_are_numpy_and_agree(friction_fit):
    fit = friction_fit
    names = fit.parameter_names
    assert names[:7] == ["k1", "k2", "mu_st", "v_st_m_s", "mu_v", "beta_per_K", "f0"]
    cov = fit.covariance
    assert isinstance(cov, np.ndarray) and cov.shape == (len(names), len(names))
    # The standard errors are the square roots of the covariance's diagonal.
    np.testing.assert_allclose(np.sqrt(np.diag(cov))[:7], fit.stderr[:7], rtol=1e-12)
    for name in names[:7]:
        p = fit.params[name]
        assert p.ci[0] < p.value < p.ci[1]
        assert p.stderr > 0
    np.testing.assert_allclose(fit.residual_N, fit.measured_N - fit.predicted_N)
    assert math.isclose(fit.rmse_N, float(np.sqrt(np.mean(fit.residual_N ** 2))), rel_tol=1e-9)
    report = repr(fit)
    assert "[[Variables]]" in report and "k1:" in report and "[[Correlations]]" in report


def test_init_is_the_start_not_the_estimate(friction_fit, tmp_path):
    # lmfit's init: the value the fit started from (the paper's constants by default), also after
    # the random run offsets' later passes, which start from the one before.
    paper = {"k1": 0.315, "k2": 0.03, "mu_st": 1.52, "v_st_m_s": 0.015, "mu_v": 0.003, "beta_per_K": 0.067, "f0": 0.029}
    for name, start in paper.items():
        assert friction_fit.params[name].init == start, name
    assert friction_fit.params["k1"].value != friction_fit.params["k1"].init
    log = lmcal.load_friction_log(os.path.join(SOURCE, "measurements", "cheng2017", "friction.csv"))
    assert lmcal.fit_friction(log, start={"mu_st": 1.1}).params["mu_st"].init == 1.1


def test_the_law_reproduces_the_fits_predictions():
    # Without run offsets, at the logged temperatures, the fit's prediction is the law at its
    # constants, sample by sample.
    friction_fit = lmcal.fit_friction(FRICTION_CSV, run_offsets="none", law_temperature="logged")
    c = lmcal.load_friction_log(FRICTION_CSV).columns()
    predicted = lmcal.simulate_friction(friction_fit, velocity_m_s=c["velocity_m_s"], load_N=c["load_N"],
                                        preload_um=c["preload_um"], block_length_mm=c["block_length_mm"],
                                        temperature_C=c["temperature_C"], viscosity40_mm2_s=c["viscosity40_mm2_s"],
                                        direction=c["direction"])
    np.testing.assert_allclose(predicted, friction_fit.predicted_N, rtol=1e-12)


def test_a_dataframe_gives_the_files_fit(friction_fit):
    pd = pytest.importorskip("pandas")
    frame = pd.read_csv(FRICTION_CSV, comment="#", float_precision="round_trip")
    log = lmcal.load_friction_log(frame)
    assert len(log) == len(frame)
    from_frame = lmcal.fit_friction(log).to_dict()
    from_file = friction_fit.to_dict()
    from_frame.pop("inputs"), from_file.pop("inputs")
    assert_same(from_frame, from_file)


def test_columns_in_other_units_are_converted():
    c = lmcal.load_friction_log(FRICTION_CSV).columns()
    columns = {k: c[k] for k in ("run", "velocity_m_s", "preload_um", "block_length_mm", "temperature_C", "friction_N")}
    columns["load_kN"] = c["load_N"] / 1000
    log = lmcal.load_friction_log(columns)
    np.testing.assert_allclose(log.columns()["load_N"], c["load_N"], rtol=1e-15)
    assert log.load_reports[0]["conversions"]


def test_thermal_fit_equals_the_command(friction_fit, cli_friction, tmp_path):
    friction_json = str(cli_friction / "friction.json")
    cli("fit", "thermal", THERMAL_TOML, "--friction", friction_json, "-o", str(tmp_path))
    expected = json.loads((tmp_path / "thermal.json").read_text())
    fit = lmcal.fit_thermal(THERMAL_TOML, friction=friction_json)
    assert_same(fit.to_dict(), expected)
    alpha = fit.alpha
    assert 0 < alpha.ci[0] < alpha.value < alpha.ci[1] < 1
    s = fit.samples
    assert s["measured_C"].shape == s["simulated_C"].shape == s["time_s"].shape
    # The fit's RMSE per sensor is that of these residuals.
    r = fit.residual_C
    for g in expected["goodness"]:
        run, sensor = fit.run_names.index(g["run"]), None
        sensor = fit.sensor_names[run].index(g["sensor"])
        mask = (s["run"] == run) & (s["sensor"] == sensor)
        assert mask.sum() == g["n"]
        assert math.isclose(float(np.sqrt(np.mean(r[mask] ** 2))), g["rmse_K"], rel_tol=1e-9)
    assert "alpha:" in repr(fit)
    # A FrictionFit object in place of its JSON: the same α.
    direct = lmcal.fit_thermal(THERMAL_TOML, friction=friction_fit)
    assert math.isclose(direct.alpha.value, alpha.value, rel_tol=1e-9)


def test_a_trace_from_columns_gives_the_files_fit():
    data = lmcal.load_thermal_dataset(THERMAL_TOML)
    run = data.runs[0]
    from_columns = data.with_trace(run["id"], run["trace"])
    assert len(from_columns.inputs) == len(data.inputs) - 1  # the run's file is no longer read
    fit = lmcal.fit_thermal(data, run_fits=False)
    a, b = fit.to_dict(), lmcal.fit_thermal(from_columns, run_fits=False).to_dict()
    a.pop("inputs"), b.pop("inputs")
    assert_same(a, b)
    # NaN in a thermocouple column: a missing sample, as an empty cell in a file.
    trace = {k: np.array(v, dtype=float) for k, v in run["trace"].items()}
    trace[next(k for k in trace if k.startswith("tc"))][5] = np.nan
    with_gap = lmcal.fit_thermal(data.with_trace(run["id"], trace), run_fits=False)
    assert len(with_gap.samples["time_s"]) == len(fit.samples["time_s"]) - 1
    trace = dict(run["trace"])
    trace.pop(next(k for k in trace if k.startswith("tc")))
    with pytest.raises(ValueError, match="expected the columns of its file"):
        data.with_trace(run["id"], trace)
    with pytest.raises(lmcal.InvalidParameterError, match="no run 'nope'"):
        data.with_trace("nope", run["trace"])


def test_calibrate_equals_the_command(tmp_path):
    cli_out = tmp_path / "cli"
    cli("calibrate", SET, "-o", str(cli_out))
    steps = []
    cal = lmcal.calibrate(SET, progress=lambda what, done, total: steps.append((what, done, total)))
    assert_same(cal.to_dict(), json.loads((cli_out / "calibration.json").read_text()))
    for name, fit in (("friction", cal.friction), ("calibrated_friction", cal.calibrated_friction),
                      ("thermal", cal.thermal), ("calibrated_thermal", cal.calibrated_thermal)):
        assert_same(fit.to_dict(), json.loads((cli_out / f"{name}.json").read_text()), name)
    assert_same(cal.friction_diagnosis.to_dict(), json.loads((cli_out / "friction_diagnosis.json").read_text()))
    assert_same(cal.thermal_diagnosis.to_dict(), json.loads((cli_out / "thermal_diagnosis.json").read_text()))
    # Progress: every step, in order, from the caller's thread.
    total = steps[0][2]
    assert total > 1 and [done for what, done, t in steps if t == total] == list(range(total))
    assert steps[0][0] == "loading the measurements" and any(what.startswith("round 1") for what, _, _ in steps)
    py_out = tmp_path / "py"
    cal.write(py_out)
    assert sorted(p.name for p in py_out.iterdir()) == sorted(p.name for p in cli_out.iterdir())
    assert "<html" in cal.report_html()[:200].lower()


def test_an_exception_in_the_progress_callback_stops_the_call():
    class Stop(Exception):
        pass

    def progress(what, done, total):
        raise Stop(what)

    with pytest.raises(Stop):
        lmcal.calibrate(SET, progress=progress)


def test_the_gil_is_released_during_a_fit():
    log = lmcal.load_friction_log(FRICTION_CSV)
    done = threading.Event()
    worker_seconds = []

    def work():
        t = time.perf_counter()
        lmcal.diagnose_friction(log)
        worker_seconds.append(time.perf_counter() - t)
        done.set()

    thread = threading.Thread(target=work)
    thread.start()
    ticks = 0
    while not done.is_set():  # Python work in this thread while the diagnosis runs in C++
        ticks += 1
        time.sleep(0.001)
    thread.join()
    # Held GIL: this loop could not run while the diagnosis ran (about a second).
    assert worker_seconds[0] > 0.2
    assert ticks > 0.2 * worker_seconds[0] / 0.001 * 0.25


def test_simulate_thermal_equals_the_command(tmp_path):
    cli("simulate", "thermal", "-o", str(tmp_path / "sim"))
    sim = lmcal.simulate_thermal()
    rows = [line.split(",") for line in (tmp_path / "sim_time.csv").read_text().splitlines() if not line.startswith("#")]
    header, rows = rows[0], rows[1:]
    t, x, temp = header.index("time_s"), header.index("sensor_x_m"), header.index("temperature_C")
    expected = {(float(r[t]), float(r[x])): float(r[temp]) for r in rows}
    assert len(expected) == sim.temperature_C.size
    for i, time_s in enumerate(sim.time_s):
        for j, x_m in enumerate(sim.sensor_x_m):
            assert math.isclose(sim.temperature_C[i, j], expected[(time_s, x_m)], rel_tol=1e-10)
    # The rail warms from the ambient, most under the block.
    assert sim.temperature_C[0, 0] == pytest.approx(26.0)
    assert sim.temperature_C[-1, 0] > sim.temperature_C[-1, -1] > 26.0


# ---- bad input -------------------------------------------------------------------------------

def test_a_bad_file_names_file_line_and_column(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("run,velocity_m_s,load_N,preload_um,block_length_mm,temperature_C,friction_N\n"
                   "r1,0.1,1000,2.5,100,24,30\n"
                   "r1,0.1,abc,2.5,100,24,30\n")
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(bad)
    assert isinstance(e.value, ValueError)
    assert e.value.file == str(bad) and e.value.line == 3 and e.value.column == 8
    assert f"{bad}:3:8" in str(e.value) and "load_N" in str(e.value)


def good_columns(n=4):
    return {"run": ["r1"] * n, "velocity_m_s": np.full(n, 0.1), "load_N": np.full(n, 1000.0),
            "preload_um": np.full(n, 2.5), "block_length_mm": np.full(n, 100.0),
            "temperature_C": np.full(n, 24.0), "friction_N": np.linspace(30, 31, n)}


def test_good_columns_load():
    log = lmcal.load_friction_log(good_columns())
    assert len(log) == 4 and log.run_names == ["r1"]


@pytest.mark.parametrize("change, column, words, row", [
    (lambda c: c.update(load_N=np.full(3, 1000.0)), "load_N", "rows", None),
    (lambda c: c["friction_N"].__setitem__(2, np.nan), "friction_N", "row 2: friction_n = nan", 2),
    (lambda c: c["temperature_C"].__setitem__(1, np.inf), "temperature_C", "row 1: temperature_c = inf", 1),
    (lambda c: c.update(velocity_m_s=np.array(["2020-01-01"] * 4, dtype="datetime64[D]")), "velocity_m_s", "numbers", None),
    (lambda c: c.update(preload_um=np.full(4, True)), "preload_um", "numbers", None),
    (lambda c: c.update(load_N=np.ones((4, 2))), "load_N", "shape", None),
])
def test_bad_columns_are_a_value_error_naming_the_column(change, column, words, row):
    c = good_columns()
    change(c)
    with pytest.raises(ValueError) as e:
        lmcal.load_friction_log(c)
    assert f"'{column}'" in str(e.value) and words in str(e.value).lower()
    if row is not None:  # a value: an InputError with the row and the column's name
        assert isinstance(e.value, lmcal.InputError) and (e.value.row, e.value.column) == (row, column)


def test_a_value_out_of_range_in_columns_names_column_and_row():
    c = good_columns()
    c["load_N"][3] = -5.0
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(c)
    assert str(e.value).startswith("columns: column 'load_N', row 3: load_N = -5") and e.value.file == "columns"
    assert (e.value.row, e.value.column, e.value.line) == (3, "load_N", None)
    c = good_columns()
    c["velocity_m_s"] = np.array(["0.1", "fast", "0.1", "0.1"], dtype=object)
    with pytest.raises(lmcal.InputError, match="column 'velocity_m_s', row 1: expected a number, found 'fast'") as e:
        lmcal.load_friction_log(c)
    assert (e.value.row, e.value.column) == (1, "velocity_m_s")
    with pytest.raises(lmcal.InputError, match="missing"):
        lmcal.load_friction_log({k: v for k, v in good_columns().items() if k != "friction_N"})
    # Conditions are optional (the law in combinations), and said in the load report.
    lean = lmcal.load_friction_log({k: v for k, v in good_columns().items() if k != "load_N"})
    assert any("not given: load_N" in note for r in lean.load_reports for note in r["notes"])


def test_bad_options_name_the_option():
    log = lmcal.load_friction_log(good_columns())
    with pytest.raises(lmcal.InvalidParameterError) as e:
        lmcal.fit_friction(log, loss="square")
    assert e.value.parameter == "loss" and "huber" in str(e.value)
    with pytest.raises(lmcal.InvalidParameterError, match="unknown constant 'k3'"):
        lmcal.fit_friction(log, free=["k3"])
    with pytest.raises(lmcal.InputError):
        lmcal.load_thermal_dataset(os.path.join(SOURCE, "no_such_manifest.toml"))


def test_bad_option_types_name_the_argument_and_what_was_expected():
    log = lmcal.load_friction_log(good_columns())
    with pytest.raises(TypeError, match=r"fixed\['k1'\]: expected a number, got str 'abc'"):
        lmcal.fit_friction(log, fixed={"k1": "abc"})
    with pytest.raises(TypeError, match=r"bounds\['k1'\]: expected a \(low, high\) pair"):
        lmcal.fit_friction(log, bounds={"k1": 3.0})
    with pytest.raises(TypeError, match="start: expected a dict"):
        lmcal.fit_friction(log, start=[("k1", 0.3)])


def test_a_run_name_that_is_not_text_is_a_value_error_naming_it():
    c = good_columns()
    c["run"] = np.array(["r\udc80"] * 4, dtype=object)
    with pytest.raises(ValueError, match=r"column 'run', row 0: .* is not valid text"):
        lmcal.load_friction_log(c)
    data = lmcal.load_thermal_dataset(THERMAL_TOML)
    with pytest.raises(ValueError, match="run: .* is not valid text"):
        data.with_trace("v\udc80", {"time_s": [0.0, 1.0], "ambient_C": [24.0, 24.0]})


def test_a_manifests_files_stay_inside_its_folder_unless_allowed(tmp_path):
    (tmp_path / "set").mkdir()
    (tmp_path / "shared.csv").write_text("not a log\n")
    manifest = tmp_path / "set" / "friction.toml"
    manifest.write_text('file = "../shared.csv"\n')
    with pytest.raises(lmcal.InputError, match="file '../shared.csv' is outside") as e:
        lmcal.load_friction_log(manifest)
    assert (e.value.line, e.value.column) == (1, 8)
    # Allowed, the file is read (and refused for what it holds).
    with pytest.raises(lmcal.InputError) as e:
        lmcal.load_friction_log(manifest, allow_outside_root=True)
    assert "shared.csv" in str(e.value) and "is outside" not in str(e.value)
    (tmp_path / "set" / "friction.csv").symlink_to(tmp_path / "shared.csv")
    manifest.unlink()
    with pytest.raises(lmcal.InputError, match="through a symbolic link"):
        lmcal.calibrate(tmp_path / "set")


def test_numbers_that_leave_are_finite_or_refused(tmp_path):
    with pytest.raises(lmcal.InvalidParameterError, match="velocity_m_s = 1e\\+308"):
        lmcal.simulate_thermal(velocity_m_s=1e308)
    with pytest.raises(lmcal.InvalidParameterError, match="velocity_m_s"):
        lmcal.simulate_friction(velocity_m_s=1e308, load_N=3000, preload_um=4, block_length_mm=120.2, temperature_C=26)
    duty = tmp_path / "fast.toml"
    duty.write_text('guide = "SRN 35C"\nrail_length_m = 0.6\nambient_C = 24\nload_N = 3000\npreload_um = 4\n'
                    'stroke_m = 0.2\n[[segment]]\nduration_h = 1\nvelocity_m_s = 3\n')
    with pytest.raises(lmcal.InputError, match="drives the rail to") as e:
        lmcal.predict(os.path.join(SOURCE, "fits", "cheng2017", "model.toml"), duty, samples=20)
    assert e.value.line == 7


def test_the_example_runs(tmp_path):
    example = os.path.join(SOURCE, "examples", "python", "fit_friction_dataframe.py")
    env = dict(os.environ, MPLBACKEND="Agg")
    done = subprocess.run([__import__("sys").executable, example, str(tmp_path)], env=env, capture_output=True,
                          text=True, cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert "[[Variables]]" in done.stdout and "k1 = " in done.stdout
    assert (tmp_path / "cheng2017" / "report.html").is_file()
    assert (tmp_path / "cheng2017" / "calibration.json").is_file()


def test_predict_equals_the_command(tmp_path):
    model = os.path.join(SOURCE, "fits", "cheng2017", "model.toml")
    duty = os.path.join(SOURCE, "examples", "duty", "two_shifts.toml")
    cli("predict", model, duty, "-o", str(tmp_path), "--samples", "50")
    p = lmcal.predict(model, duty, samples=50)
    assert_same(p.to_dict(), json.loads((tmp_path / "prediction.json").read_text()))
    e = p.elongation_um
    assert np.all(e["low"] <= e["value"] + 1e-12) and np.all(e["value"] <= e["high"] + 1e-12)
    assert e["value"].max() > 10  # microns: the rail grows in the shifts
