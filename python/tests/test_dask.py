"""Dask: the runs of a study (and lists of simulate calls) on a LocalCluster give
the same numbers as on this machine."""

import numpy as np
import pandas as pd
import pytest

import rocklab
import rocklab.dask
from conftest import BLOCK, FIXTURES, NRC_1030, STUDY

distributed = pytest.importorskip("distributed")


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        with distributed.Client(cluster) as c:
            yield c


def test_partition_keeps_order_and_covers_everything():
    items = list(range(1009))
    for n in [1, 2, 7, 8, 1009, 5000]:
        parts = rocklab.dask.partition(items, n)
        assert [x for p in parts for x in p] == items
        assert all(parts) and max(map(len, parts)) - min(map(len, parts)) <= 1


def test_1008_facade_runs_on_dask_equal_the_sequential_run(client):
    # 84 scale factors × 3 records × 2 coefficient sets × 2 polarities = 1008 runs,
    # each repeated at 100× looser and tighter tolerances (well_conditioned).
    runs = rocklab.plan_facade(STUDY, scales="0.2:1.8:84")
    assert len(runs) == 1008
    seq = rocklab.facade_runs(STUDY, runs, sensitivity=True)
    on_dask = rocklab.dask.facade_runs(client, STUDY, runs, sensitivity=True)
    assert len(on_dask) == 1008
    pd.testing.assert_frame_equal(on_dask.drop(columns=["solve_wall_s"]), seq.drop(columns=["solve_wall_s"]), check_exact=True)
    # A real ensemble: some runs overturn, some do not, some are knife-edge.
    assert 0 < on_dask["overturned"].sum() < len(on_dask)
    # Scale 1.0 is not on this grid; the CLI's own study (scale 1) is compared in
    # test_facade.py. The rows carry the run they belong to.
    assert list(zip(on_dask["record"], on_dask["coefficients"], on_dask["polarity"], on_dask["scale"])) == [tuple(r) for r in runs]


def test_ida_points_on_dask_equal_the_cli_ida(client):
    full = rocklab.facade(STUDY, scales="0.5:1.5:5")
    on_dask = rocklab.dask.facade_runs(client, STUDY, scales="0.5:1.5:5", sensitivity=False, partitions=7)
    pd.testing.assert_frame_equal(on_dask, full.ida, check_exact=True)


def test_simulate_many_on_dask_equals_sequential(client):
    acc = np.loadtxt(FIXTURES / "ground-motions" / "synthetic" / "one_sine_pulse_1col.txt", comments="#")
    pulse = rocklab.GroundMotion(acc, 0.005, "g")
    calls = []
    for e in [0.6, 0.8, 0.95]:
        for pol in [1, -1]:
            calls.append(dict(block=str(BLOCK), record=str(NRC_1030), scale=1.27, polarity=pol, e=e))
            calls.append(dict(block=str(BLOCK), record=pulse, scale=2.5, polarity=pol, e_in=e, e_out=0.7))
    seq = rocklab.dask.simulate_sequential(calls)
    on_dask = rocklab.dask.simulate_many(client, calls)
    # Each row keeps its run's measured time (from the summary's "timing"): the
    # only column that may differ between two runs of the same call.
    assert (on_dask["solve_wall_s"] > 0).all()
    pd.testing.assert_frame_equal(on_dask.drop(columns=["solve_wall_s"]), seq.drop(columns=["solve_wall_s"]), check_exact=True)
    one = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, polarity=-1, e=0.8, history=False)
    row = on_dask[(on_dask["e_in"] == 0.8) & (on_dask["polarity"] == -1) & (on_dask["record"] == str(NRC_1030))].iloc[0]
    assert row["max_theta_over_alpha"] == one.summary["max_theta_over_alpha"]
