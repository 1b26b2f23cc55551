"""Every JSON file the commands write follows docs/schema/lmcal-output.schema.json: its kind,
where it came from (command starting with lmcal, inputs with SHA-256, software versions), and
every parameter record anywhere in it (the quoted interval in ci95)."""
import json
import os
import pathlib
import subprocess

import jsonschema
import pytest

SOURCE = pathlib.Path(os.environ["LMCAL_SOURCE"])
CLI = os.environ["LMCAL_CLI"]
SET = SOURCE / "measurements" / "cheng2017"
SCHEMA = json.loads((SOURCE / "docs" / "schema" / "lmcal-output.schema.json").read_text())


def cli(*args):
    done = subprocess.run([CLI, *map(str, args)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def parameter_records(value):
    """Every list of parameter records (dicts with a ci95 and an interval) anywhere in a JSON value."""
    if isinstance(value, dict):
        for key, item in value.items():
            if key == "parameters" and isinstance(item, list) and item and isinstance(item[0], dict) and "ci95" in item[0]:
                yield item
            yield from parameter_records(item)
    elif isinstance(value, list):
        for item in value:
            yield from parameter_records(item)


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    out = tmp_path_factory.mktemp("outputs")
    cli("calibrate", SET, "-o", out / "calibrate")
    cli("fit", "friction", SET / "friction.csv", "-o", out / "fit")
    cli("fit", "thermal", SET / "thermal.toml", "--friction", out / "fit" / "friction.json", "-o", out / "fit")
    cli("diagnose", "friction", SET / "friction.csv", "-o", out / "diagnose")
    cli("predict", out / "calibrate" / "model.toml", SOURCE / "examples" / "duty" / "two_shifts.toml", "-o", out / "predict")
    cli("plan", "friction", SET / "friction.csv", "-o", out / "plan")
    return sorted(out.rglob("*.json"))


def test_every_output_follows_the_schema(outputs):
    assert len(outputs) >= 15
    validator = jsonschema.Draft202012Validator(SCHEMA)
    parameter = jsonschema.Draft202012Validator({**SCHEMA["$defs"]["parameter"], "$defs": SCHEMA["$defs"]})
    for file in outputs:
        document = json.loads(file.read_text())
        errors = [e.message for e in validator.iter_errors(document)]
        assert not errors, f"{file.name}: {errors[:3]}"
        for records in parameter_records(document):
            for record in records:
                errors = [e.message for e in parameter.iter_errors(record)]
                assert not errors, f"{file.name} {record.get('name')}: {errors[:3]}"


def test_ci95_is_the_interval_the_text_quotes(outputs):
    checked = 0
    for file in outputs:
        for records in parameter_records(json.loads(file.read_text())):
            for p in records:
                quoted = {"linear": p["linear_ci95"], "log": p["linear_ci95"], "logit": p["linear_ci95"], "clipped": p["linear_ci95"],
                          "profile": p["profile_ci95"], "none": [None, None]}[p["interval"]]
                assert p["ci95"] == quoted, f"{file.name} {p['name']}"
                checked += 1
    assert checked > 50


def test_a_document_without_its_provenance_fails_the_schema():
    validator = jsonschema.Draft202012Validator(SCHEMA)
    document = {"kind": "friction fit", "lmcal_version": "0.2.0", "schema_version": 2, "command": ["/usr/bin/lmcal", "fit"],
                "inputs": [], "software": {}}
    messages = " ".join(e.message for e in validator.iter_errors(document))
    assert "'lmcal' was expected" in messages and "'Ceres Solver' is a required property" in messages
