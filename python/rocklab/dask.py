"""Scale rocklab runs out on a Dask cluster (``dask.distributed``).

The same code runs on a laptop's ``LocalCluster`` and on a Slurm, PBS or
Kubernetes cluster (``dask_jobqueue.SLURMCluster``, ``dask_kubernetes``): build a
``distributed.Client`` for the cluster and pass it in. The runs are cut into
partitions, each partition runs on a worker (one after the other there: the
cluster gives the parallelism), and the results come back as one DataFrame in the
order of the runs. A run is computed by the same library function on a worker as
on this machine, so the numbers are identical to :func:`rocklab.facade_runs` (and
to the CLI); only the measured ``solve_wall_s`` differs.

What a worker needs: rocklab installed (``pip install ./python``) and the study's
files (study, block, records) readable at the same absolute path (a shared file
system), or records passed as arrays (:class:`rocklab.GroundMotion`) in
:func:`simulate_many`.

Example::

    from distributed import Client, LocalCluster
    import rocklab, rocklab.dask

    with LocalCluster(n_workers=2, threads_per_worker=1) as cluster, Client(cluster) as client:
        runs = rocklab.plan_facade("fixtures/facade/study.toml", scales="0.1:2.0:100")
        df = rocklab.dask.facade_runs(client, "fixtures/facade/study.toml", runs, sensitivity=False)
"""

from __future__ import annotations

import os
from typing import Any, Mapping, Optional, Sequence

import rocklab

__all__ = ["facade_runs", "simulate_many", "partition"]


def partition(items: Sequence, n: int) -> list:
    """`items` cut into `n` contiguous, nearly equal, non-empty parts (in order)."""
    n = max(1, min(n, len(items)))
    q, r = divmod(len(items), n)
    parts, start = [], 0
    for i in range(n):
        end = start + q + (1 if i < r else 0)
        parts.append(list(items[start:end]))
        start = end
    return parts


def _default_partitions(client, n_items: int) -> int:
    """Four partitions per worker thread (load balance), at most one per item."""
    threads = sum(client.nthreads().values()) or 1
    return max(1, min(n_items, 4 * threads))


def _facade_partition(study: str, runs: list, sensitivity: bool) -> list:
    # Runs one after the other: each worker thread is one core.
    import json

    payload = json.dumps([[str(r), str(s), int(p), float(sc)] for r, s, p, sc in runs])
    return json.loads(rocklab._rocklab.facade_runs(study, payload, sensitivity, False))


def facade_runs(
    client,
    study,
    runs: Optional[Sequence[Sequence]] = None,
    *,
    scales=(1.0,),
    sensitivity: bool = True,
    partitions: Optional[int] = None,
):
    """Run a façade study's runs on a Dask cluster; one DataFrame, in run order.

    Args:
        client: a ``distributed.Client``.
        study: the study file (made absolute here; workers must read the same path).
        runs: [(record, set, polarity, scale)], default
            :func:`rocklab.plan_facade` (``study``, ``scales``).
        sensitivity: as in :func:`rocklab.facade_runs`.
        partitions: number of tasks (default four per worker thread).
    """
    study = os.path.abspath(os.fspath(study))
    if runs is None:
        runs = rocklab.plan_facade(study, scales)
    runs = [tuple(r) for r in runs]
    parts = partition(runs, partitions or _default_partitions(client, len(runs)))
    futures = client.map(_facade_partition, [study] * len(parts), parts, [sensitivity] * len(parts), pure=False)
    rows = [row for part in client.gather(futures) for row in part]
    return rocklab._frame(rocklab._run_rows(rows))


def _simulate_partition(calls: list) -> list:
    out = []
    for call in calls:
        res = rocklab.simulate(**{**call, "history": False})
        row = {k: v for k, v in res.summary.items() if not isinstance(v, (list, dict))}
        # summary.json keeps measured times under "timing"; the row keeps the run's own.
        row["solve_wall_s"] = res.summary.get("timing", {}).get("/solve_wall_s")
        out.append(row)
    return out


def _absolute_paths(call: Mapping[str, Any]) -> dict:
    """A call with its file arguments made absolute (workers may start elsewhere)."""
    out = dict(call)
    for key in ("block", "record", "calibration"):
        v = out.get(key)
        if isinstance(v, (str, os.PathLike)):
            out[key] = os.path.abspath(os.fspath(v))
    return out


def simulate_many(client, calls: Sequence[Mapping[str, Any]], *, partitions: Optional[int] = None):
    """Run a list of :func:`rocklab.simulate` calls on a Dask cluster.

    Each call is a dict of :func:`rocklab.simulate`'s arguments (``block``,
    ``record``, ``scale``, ``polarity``, ``e_in``, ...; paths must be readable by
    the workers). Returns one row per call, in order, with the scalar fields of
    each run's ``summary`` (the CLI's ``summary.json`` without events and notes).
    Relative paths are made absolute here.
    """
    calls = [_absolute_paths(c) for c in calls]
    parts = partition(calls, partitions or _default_partitions(client, len(calls)))
    futures = client.map(_simulate_partition, parts, pure=False)
    rows = [row for part in client.gather(futures) for row in part]
    return rocklab._frame(rows)


def simulate_sequential(calls: Sequence[Mapping[str, Any]]):
    """The same rows as :func:`simulate_many`, computed here one call at a time."""
    return rocklab._frame(_simulate_partition([dict(c) for c in calls]))
