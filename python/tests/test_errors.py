"""Bad input raises RocklabError with the CLI's message; a panic never crashes the
interpreter."""

import math
import threading
import time

import numpy as np
import pytest

import rocklab
from conftest import BLOCK, NRC_1030, ONE_SIDED, STUDY, run_cli


def _cli_error(cli, *args):
    p = run_cli(cli, *args, ok=False)
    assert p.returncode == 2, p.stderr
    # `error: ` then the message, which may span lines (TOML errors show the line).
    assert p.stderr.startswith("error: "), p.stderr
    return p.stderr[len("error: "):].rstrip("\n")


def test_bad_manifest_raises_the_cli_message(cli, tmp_path):
    text = ONE_SIDED.read_text().replace("hinge_height_m = 0.23", "hinge_height_m = 0.23\nhieght = 3")
    bad = tmp_path / "campaign.toml"
    bad.write_text(text)
    message = _cli_error(cli, "reduce", bad, "--out", tmp_path / "out")
    assert "hieght" in message and str(bad) in message
    with pytest.raises(rocklab.RocklabError) as e:
        rocklab.reduce(bad)
    assert str(e.value) == message
    assert isinstance(e.value, ValueError)


def test_bad_log_line_and_column(cli, tmp_path):
    """A broken log stops its own test with file:line:column, as in the CLI."""
    src = ONE_SIDED.parent
    lines = (src / "150_1.csv").read_text().splitlines(keepends=True)
    cells = lines[8].split(",")
    lines[8] = ",".join([cells[0], "abc", *cells[2:]])  # line 9, column 2
    (tmp_path / "150_1.csv").write_text("".join(lines))
    (tmp_path / "100_1.csv").write_text((src / "100_1.csv").read_text())
    manifest = tmp_path / "campaign.toml"
    manifest.write_text(
        (src / "campaign.toml").read_text().split("[[test]]")[0]
        + '[[test]]\nid = "150_1"\nfile = "150_1.csv"\n[[test]]\nid = "100_1"\nfile = "100_1.csv"\n'
    )
    p = run_cli(cli, "reduce", manifest, "--out", tmp_path / "out", "--no-plots", ok=False)
    assert p.returncode == 1
    res = rocklab.reduce(manifest)
    err = res.failed["150_1"]
    assert err.startswith(f"{tmp_path / '150_1.csv'}:9:2: column 'disp_mm': 'abc' is not a number"), err
    assert f"test 150_1: {err}" in p.stderr
    assert res.test("100_1")["status"] == "ok"


def test_bad_record_and_block_raise_the_cli_message(cli, tmp_path):
    rec = tmp_path / "rec.txt"
    rec.write_text("0.0\n0.1\nnot-a-number\n0.2\n")
    message = _cli_error(cli, "simulate", "--block", BLOCK, "--record", rec, "--format", "one-column", "--dt", "0.01", "--units", "g", "--e", "0.9", "--out", tmp_path / "o")
    assert str(rec) in message
    with pytest.raises(rocklab.RocklabError) as e:
        rocklab.simulate(BLOCK, rec, format="one-column", dt=0.01, units="g", e=0.9)
    assert str(e.value) == message
    blk = tmp_path / "block.toml"
    blk.write_text(BLOCK.read_text().replace("height_m = 7.64\nthickness_m", "height_m = -7.64\nthickness_m"))
    message = _cli_error(cli, "simulate", "--block", blk, "--record", NRC_1030, "--e", "0.9", "--out", tmp_path / "o")
    with pytest.raises(rocklab.RocklabError) as e:
        rocklab.simulate(blk, NRC_1030, e=0.9)
    assert str(e.value) == message and "[block].height_m = -7.64" in message


def test_bad_study_raises_the_cli_message(cli, tmp_path):
    study = tmp_path / "study.toml"
    study.write_text(STUDY.read_text().replace("polarities = [1, -1]", "polarities = [2]").replace('"../', f'"{STUDY.parent}/../').replace('"block.toml"', f'"{STUDY.parent}/block.toml"'))
    message = _cli_error(cli, "facade", study, "--out", tmp_path / "o")
    assert "polarities" in message
    with pytest.raises(rocklab.RocklabError) as e:
        rocklab.facade(study)
    assert str(e.value) == message


def test_array_errors_name_the_index():
    m = {"height_m": 2.7, "thickness_m": 0.36, "hinge_height_m": 0.23}
    t = np.arange(100) * 0.005
    t[40] = t[39]
    with pytest.raises(rocklab.RocklabError, match=r"t\[40\] = 0.195 after t\[39\] = 0.195: expected strictly increasing time"):
        rocklab.reduce_log(t, np.zeros(100), wall=m, sensor_height_m=2.56)
    x = np.zeros(100)
    x[7] = np.nan
    with pytest.raises(rocklab.RocklabError, match=r"x\[7\] = NaN: expected finite numbers"):
        rocklab.reduce_log(np.arange(100) * 0.005, x, wall=m, sensor_height_m=2.56)
    with pytest.raises(rocklab.RocklabError, match="t has 100 values and x 99"):
        rocklab.reduce_log(np.arange(100) * 0.005, np.zeros(99), wall=m, sensor_height_m=2.56)
    with pytest.raises(rocklab.RocklabError, match="units is missing"):
        rocklab.simulate(BLOCK, {"acc": np.zeros(10), "dt": 0.01, "units": None}, e=0.9)
    with pytest.raises(rocklab.RocklabError, match="polarity = 3: expected 1 or -1"):
        rocklab.simulate(BLOCK, NRC_1030, e=0.9, polarity=3)
    # The same ranges as the command line (rocklab::limits), so that a call from a
    # script cannot ask for a run of 1e300 s or a record magnified 1e6 times.
    for kwargs, message in [
        ({"t_extra": 1e300}, r"t_extra = 1e300: expected a value from 0 to 3600 s"),
        ({"scale": 1e6}, r"scale = 1e6: expected a value from 0.001 to 100"),
        ({"rtol": 0.5}, r"rtol = 0.5: expected a value from 1e-12 to 0.001"),
        ({"overturn_limit": float("nan")}, r"overturn_limit = NaN: expected a value"),
    ]:
        with pytest.raises(rocklab.RocklabError, match=message):
            rocklab.simulate(BLOCK, NRC_1030, e=0.9, **kwargs)
    with pytest.raises(rocklab.RocklabError, match=r"\[wall\].thickness_m = -0.36"):
        rocklab.reduce_log(np.arange(100) * 0.005, np.zeros(100), wall={**m, "thickness_m": -0.36}, sensor_height_m=2.56)


def test_facade_sizes_and_scales_within_the_cli_ranges():
    # The command line's bounds (rocklab::limits), checked before any run starts:
    # an ensemble of 10^9 samples or a scale of 1e9 from a script is refused.
    with pytest.raises(rocklab.RocklabError, match=r"samples = 1000000000: expected at most 100000"):
        rocklab.facade_ensembles(STUDY, samples=10**9)
    with pytest.raises(rocklab.RocklabError, match=r"scales\[1\] = 1e9: expected a value from 0.001 to 100"):
        rocklab.facade(STUDY, scales=[1.0, 1e9])
    with pytest.raises(rocklab.RocklabError, match=r"scale = 1e9: expected a value from 0.001 to 100"):
        rocklab.facade_runs(STUDY, [("20161030_ACC", "housner", 1, 1e9)], sensitivity=False)


def test_a_flat_log_is_a_test_error_not_an_exception():
    res = rocklab.reduce_log(np.arange(400) * 0.005, np.zeros(400), wall={"height_m": 2.7, "thickness_m": 0.36}, sensor_height_m=2.56)
    assert res.test("log")["status"] == "error"
    assert "no release found" in res.failed["log"]


def test_panic_becomes_an_exception():
    with pytest.raises(rocklab.RocklabError, match="internal error in rocklab .*test panic"):
        rocklab._rocklab._panic_for_tests()
    # The interpreter and the extension still work.
    assert rocklab.reduce(ONE_SIDED).summary["campaign"] == "one-sided-demo"


def test_long_calls_release_the_gil():
    """While one thread runs a batch in Rust, another thread keeps running Python:
    its longest pause is well under the call's duration (a held GIL would stop it
    for the whole call). The batch is sized on this machine first, to last about a
    second alone, so a fast or a loaded machine cannot make it too short to tell."""
    runs = rocklab.plan_facade(STUDY, scales=[0.5, 1.0, 1.5])
    t0 = time.perf_counter()
    rocklab.facade_runs(STUDY, runs, sensitivity=True, parallel=False)
    alone = time.perf_counter() - t0
    runs = runs * max(1, math.ceil(1.0 / max(alone, 1e-3)))
    done = threading.Event()
    took = []

    def work():
        t0 = time.perf_counter()
        rocklab.facade_runs(STUDY, runs, sensitivity=True, parallel=False)
        took.append(time.perf_counter() - t0)
        done.set()

    th = threading.Thread(target=work)
    last, longest = time.perf_counter(), 0.0
    th.start()
    while not done.is_set():
        now = time.perf_counter()
        longest = max(longest, now - last)
        last = now
    th.join()
    assert took[0] > 0.2, "the batch is too short to tell"
    assert longest < 0.5 * took[0], (longest, took[0])
