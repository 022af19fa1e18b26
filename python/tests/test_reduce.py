"""reduce / reduce_log against the CLI's summary.json and tables."""

import json
import tomllib

import numpy as np
import pandas as pd
import pytest

import rocklab
from conftest import ONE_SIDED, TWO_SIDED, run_cli


@pytest.mark.parametrize("manifest", [ONE_SIDED, TWO_SIDED], ids=["one-sided", "two-sided"])
def test_reduce_equals_cli_summary_and_tables(cli, tmp_path, manifest):
    run_cli(cli, "reduce", manifest, "--out", tmp_path, "--no-plots")
    expected = json.loads((tmp_path / "summary.json").read_text())
    res = rocklab.reduce(manifest)
    # The whole document, every value exactly (same float formatting both ways).
    assert res.summary == expected
    for name in ["table1", "table2", "table3"]:
        cli_table = rocklab.read_csv(tmp_path / f"{name}.csv")
        pd.testing.assert_frame_equal(res.tables[name], cli_table, check_exact=True)
    # The per-test frame carries the summary's values.
    ok = [t for t in expected["tests"] if t["status"] == "ok"]
    assert list(res.tests["id"]) == [t["id"] for t in expected["tests"]]
    for t in ok:
        row = res.tests.set_index("id").loc[t["id"]]
        for k in ["e", "e_plus", "e_minus", "r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2"]:
            assert row[k] == t[k]
    assert len(res.peaks) == sum(len(t["peaks"]) for t in ok)
    assert res.mean == expected["mean"]
    assert res.left_out == expected["mean_left_out"]
    assert res.statuses == {t["id"]: t["status"] for t in expected["tests"]}
    first = res.peaks[res.peaks["test"] == ok[0]["id"]]
    assert list(first["velocity_mm_s"]) == [p["velocity_mm_s"] for p in ok[0]["peaks"]]


def test_reduce_savgol_equals_cli(cli, tmp_path):
    run_cli(cli, "reduce", ONE_SIDED, "--out", tmp_path, "--no-plots", "--method", "savgol", "--window", "15", "--order", "3")
    expected = json.loads((tmp_path / "summary.json").read_text())
    assert rocklab.reduce(ONE_SIDED, method="savgol", window=15, order=3).summary == expected


def _wall(manifest):
    m = tomllib.loads(manifest.read_text())
    return m, m["wall"], m["channels"]["displacement"]["height_m"]


@pytest.mark.parametrize("manifest", [ONE_SIDED, TWO_SIDED], ids=["one-sided", "two-sided"])
def test_reduce_log_on_arrays_equals_reduce_on_the_file(manifest):
    m, wall, sensor = _wall(manifest)
    full = rocklab.reduce(manifest, series=True)
    for spec in m["test"]:
        log = rocklab.read_csv(manifest.parent / spec["file"], comment="#")
        one = rocklab.reduce_log(
            log["time_s"].to_numpy(),
            log["disp_mm"].to_numpy(),
            wall=wall,
            sensor_height_m=sensor,
            rocking=m["campaign"]["rocking"],
            test_id=spec["id"],
            exclude_from_mean=spec.get("exclude_from_mean", False),
        )
        got = one.test(spec["id"])
        assert got == full.test(spec["id"])
        for k in ["alpha_rad", "e_housner", "rocking", "method"]:
            assert one.summary[k] == full.summary[k]
        # The series are the reduction's own (same lengths as the log, same values).
        s, f = one.series[spec["id"]], full.series[spec["id"]]
        assert len(s["t_s"]) == len(log)
        for key in f:
            np.testing.assert_array_equal(s[key], f[key])


def test_reduce_log_units_and_sign():
    """Time in ms, displacement in m and an inverted sensor are converted as the
    CLI converts a log's columns (value × unit factor × outward_sign): the same
    numbers as arrays already in s and mm, outward positive."""
    m, wall, sensor = _wall(ONE_SIDED)
    log = rocklab.read_csv(ONE_SIDED.parent / "100_1.csv", comment="#")
    t_ms, x_m = log["time_s"].to_numpy() * 1e3, log["disp_mm"].to_numpy() / 1e3
    ref = rocklab.reduce_log(t_ms * 1e-3, x_m * 1e3, wall=wall, sensor_height_m=sensor).test("log")
    other = rocklab.reduce_log(t_ms, -x_m, wall=wall, sensor_height_m=sensor, time_unit="ms", displacement_unit="m", outward_sign=-1).test("log")
    assert ref["status"] == "ok"
    assert other == ref


def test_without_pandas_tables_are_lists(monkeypatch):
    monkeypatch.setattr(rocklab, "_pd", None)
    res = rocklab.reduce(ONE_SIDED)
    assert isinstance(res.tables["table1"], list)
    assert res.tables["table1"][0]["test"] == "150_1"
    assert res.tables["table1"][0]["r_plus"] == res.test("150_1")["r_plus"]
    assert isinstance(res.tests, list) and res.tests[0]["id"] == "150_1"
