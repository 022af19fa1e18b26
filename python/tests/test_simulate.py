"""simulate against the CLI's summary.json and history.csv; records and blocks
given as Python objects."""

import json
import tomllib

import numpy as np
import pandas as pd
import pytest

import rocklab
from conftest import BLOCK, FIXTURES, NRC_1030, run_cli

PULSE_1COL = FIXTURES / "ground-motions" / "synthetic" / "one_sine_pulse_1col.txt"
PULSE_2COL = FIXTURES / "ground-motions" / "synthetic" / "one_sine_pulse.csv"

# The measured solver time differs from run to run (it sits under "timing");
# everything else must not.
TIMING = {"timing"}


def _strip(doc, drop=TIMING):
    return {k: v for k, v in doc.items() if k not in drop}


@pytest.mark.parametrize(
    "flags, kwargs",
    [
        (["--scale", "1.27", "--polarity", "-1", "--e-in", "0.59", "--e-out", "0.68"], dict(scale=1.27, polarity=-1, e_in=0.59, e_out=0.68)),
        (["--scale", "1.27", "--polarity", "1", "--e", "0.98"], dict(scale=1.27, polarity=1, e=0.98)),  # overturns
    ],
    ids=["calibrated-stands", "housner-overturns"],
)
def test_simulate_equals_cli_summary_and_history(cli, tmp_path, flags, kwargs):
    run_cli(cli, "simulate", "--block", BLOCK, "--record", NRC_1030, *flags, "--out", tmp_path)
    expected = json.loads((tmp_path / "summary.json").read_text())
    res = rocklab.simulate(BLOCK, NRC_1030, **kwargs)
    # The record is named as given: the CLI ran with the same absolute path.
    assert _strip(res.summary) == _strip(expected)
    hist = rocklab.read_csv(tmp_path / "history.csv")
    assert len(hist) == len(res.history["t_s"]) > 1000
    for col in ["t_s", "theta_rad", "theta_over_alpha", "theta_dot_rad_s", "ag_m_s2"]:
        np.testing.assert_array_equal(res.history[col], hist[col].to_numpy(), err_msg=col)
    pd.testing.assert_frame_equal(res.history_frame(), hist, check_exact=True)


def test_simulate_array_record_and_dict_block_equal_the_files():
    by_file = rocklab.simulate(BLOCK, PULSE_1COL, format="one-column", dt=0.005, units="g", scale=2.0, e=0.9)
    acc = np.loadtxt(PULSE_1COL, comments="#")
    block = tomllib.loads(BLOCK.read_text())
    by_obj = rocklab.simulate(block, rocklab.GroundMotion(acc, 0.005, "g"), scale=2.0, e=0.9)
    assert by_obj.summary["record"] == "<array>"
    assert _strip(by_obj.summary, TIMING | {"record", "record_notes"}) == _strip(by_file.summary, TIMING | {"record", "record_notes"})
    for k, v in by_file.history.items():
        np.testing.assert_array_equal(by_obj.history[k], v, err_msg=k)
    # The pulse rocks the block (a real run, not an empty one).
    assert by_file.summary["impacts"] > 0 and by_file.summary["max_theta_over_alpha"] > 0.01
    # The [block] table alone is enough too.
    only_block = rocklab.simulate(block["block"] | {}, rocklab.GroundMotion(acc, 0.005, "g"), scale=2.0, e=0.9)
    assert only_block.summary["i0_kg_m2"] == by_file.summary["i0_kg_m2"]


def test_two_column_record_equals_one_column():
    a = rocklab.simulate(BLOCK, PULSE_1COL, format="one-column", dt=0.005, units="g", e=0.9, scale=2.0, history=False)
    b = rocklab.simulate(BLOCK, PULSE_2COL, units="g", e=0.9, scale=2.0, history=False)
    for k in ["max_theta_over_alpha", "min_theta_over_alpha", "impacts", "overturned", "pga_g"]:
        assert a.summary[k] == b.summary[k], k
    assert a.history == {}
