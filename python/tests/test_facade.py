"""calibrate and facade against the CLI's outputs."""

import json

import pandas as pd
import pytest

import rocklab
from conftest import ONE_SIDED, STUDY, run_cli

# Measured times: summary.json keeps them under "timing"; the rows of facade_runs
# carry each run's own.
TIMING = "timing"
RUN_TIMING = "solve_wall_s"


def _runs_without_timing(runs):
    return [{k: v for k, v in r.items() if k != RUN_TIMING} for r in runs]


def test_calibrate_equals_cli(cli, tmp_path):
    run_cli(cli, "calibrate", ONE_SIDED, "--out", tmp_path)
    expected = json.loads((tmp_path / "summary.json").read_text())
    res = rocklab.calibrate(ONE_SIDED)
    # The calibration's own run time is measured, not computed.
    assert res.summary.pop(TIMING)["/calibration/wall_s"] >= 0
    expected.pop(TIMING)
    assert res.summary == expected
    assert res.calibration_toml == (tmp_path / "calibration.toml").read_text()
    assert list(res.fits["id"]) == [t["id"] for t in expected["calibration"]["tests"]]
    assert 0 < res.calibration["e_in"] < 1 and 0 < res.calibration["e_out"] < 1
    # Issue 20: the law by replay, per included test and for the campaign.
    law = res.summary["calibration"]["law_replay"]
    assert sorted([t["id"] for t in law["tests"]] + [f[0] for f in law["failed"]]) == sorted(expected["calibration"]["included"])
    assert law["notes"] and law["law"]["form"] in ("constant", "speed-loss")
    # A one-sided law by replay carries the campaign's Ω/p, as the law from the
    # readings does, so that a study can read it by the impact's speed.
    push = expected["restitution_law"]["parameters"]["push_speed"]
    assert push["impacts"] > 0 and law["law"]["parameters"]["push_speed"] == push


def test_facade_equals_cli_summary_and_ida(cli, tmp_path):
    run_cli(cli, "facade", STUDY, "--out", tmp_path, "--scales", "0.5:1.5:3")
    expected = json.loads((tmp_path / "summary.json").read_text())
    res = rocklab.facade(STUDY, scales="0.5:1.5:3")
    assert _runs_without_timing(res.summary["runs"]) == _runs_without_timing(expected["runs"])
    # facade runs the nominal study and the IDA; the CLI's summary also holds the
    # ensembles and fragility fits of issue #10, which facade_ensembles gives
    # (test_facade_law.py compares them with the CLI's).
    drop = {"runs", TIMING, "ensemble", "fragility"}
    assert {k: v for k, v in res.summary.items() if k not in drop} == {k: v for k, v in expected.items() if k not in drop}
    ida = rocklab.read_csv(tmp_path / "ida.csv")
    pd.testing.assert_frame_equal(res.ida, ida, check_exact=True)
    assert len(res.runs) == 12 and res.runs["overturned"].any() and not res.runs["overturned"].all()


def test_facade_runs_are_the_studys_runs():
    """facade_runs on the study's own plan gives the study's runs (sensitivity
    included) and, without sensitivity, the IDA's points."""
    full = rocklab.facade(STUDY, scales=[1.0, 1.3])
    runs = rocklab.facade_runs(STUDY)  # plan_facade at scale 1
    pd.testing.assert_frame_equal(runs.drop(columns=[RUN_TIMING]), full.runs.drop(columns=[RUN_TIMING], errors="ignore"), check_exact=True)
    ida = rocklab.facade_runs(STUDY, scales=[1.0, 1.3], sensitivity=False)
    pd.testing.assert_frame_equal(ida, full.ida, check_exact=True)
    sequential = rocklab.facade_runs(STUDY, scales=[1.0, 1.3], sensitivity=False, parallel=False)
    pd.testing.assert_frame_equal(sequential, full.ida, check_exact=True)


def test_facade_runs_reject_unknown_names():
    with pytest.raises(rocklab.RocklabError, match=r'record "nope" is not in the study \(records: 20161030_NRC, 20160824_NRC, 20161030_ACC\)'):
        rocklab.facade_runs(STUDY, [("nope", "housner", 1, 1.0)])
    with pytest.raises(rocklab.RocklabError, match="coefficient set"):
        rocklab.facade_runs(STUDY, [("20161030_NRC", "nope", 1, 1.0)])


def test_floats_reach_rust_exactly():
    """Regression: serde_json's default float parser may be 1 ULP off; the binding
    parses with float_roundtrip, so every scale arrives (and returns) bit for bit."""
    rng = __import__("random").Random(11)
    scales = [rng.uniform(0.05, 0.3) for _ in range(40)]
    runs = [("20160824_NRC", "calibrated", 1, s) for s in scales]
    out = rocklab.facade_runs(STUDY, runs, sensitivity=False)
    assert list(out["scale"]) == scales
