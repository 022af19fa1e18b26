"""Throughput of the same façade runs: the CLI, rocklab on this machine, and Dask.

The runs are the incremental dynamic analysis of the paper's study
(fixtures/facade/study.toml): every record × coefficient set × polarity at each
scale of --scales (one integration per run). Three ways:

- the CLI: ``rocklab facade STUDY --scales …`` (rayon over this machine's cores);
  its own "IDA: N runs … in S s" line, and the whole command's wall time
  (which also runs the 12-run study at three tolerances and draws the plots);
- ``rocklab.facade_runs(study, runs, sensitivity=False)`` (rayon, in process);
- ``rocklab.dask.facade_runs`` on a ``LocalCluster`` of --workers processes with one
  thread each (cluster start-up timed apart).

Each is repeated --repeat times; the median is printed, with runs per second.
Checks on the way that the three give the same max θ/α and outcome for every run.

    python python/examples/dask_throughput.py --cli target/release/rocklab
"""

import argparse
import re
import statistics
import subprocess
import tempfile
import time

import pandas as pd

import rocklab
import rocklab.dask


def median_time(f, repeat):
    times, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), out


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cli", required=True, help="the rocklab binary (a release build)")
    p.add_argument("--study", default="fixtures/facade/study.toml")
    p.add_argument("--scales", default="0.05:2.0:100")
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--repeat", type=int, default=3)
    a = p.parse_args()

    runs = rocklab.plan_facade(a.study, a.scales)
    n = len(runs)
    print(f"{n} runs: {a.study}, scales {a.scales}")

    cli_ida, cli_wall = [], []
    for _ in range(a.repeat):
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            r = subprocess.run([a.cli, "facade", a.study, "--out", out, "--scales", a.scales], capture_output=True, text=True, check=True)
            cli_wall.append(time.perf_counter() - t0)
            cli_ida.append(float(re.search(r"IDA: \d+ runs .* in ([0-9.]+) s", r.stdout).group(1)))
            ida_csv = rocklab.read_csv(f"{out}/ida.csv")
    t_cli_ida, t_cli_wall = statistics.median(cli_ida), statistics.median(cli_wall)

    t_local, local = median_time(lambda: rocklab.facade_runs(a.study, runs, sensitivity=False), a.repeat)

    from distributed import Client, LocalCluster

    t0 = time.perf_counter()
    with LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        t_start = time.perf_counter() - t0
        rocklab.dask.facade_runs(client, a.study, runs[:8], sensitivity=False)  # warm the workers (import, first load)
        t_dask, on_dask = median_time(lambda: rocklab.dask.facade_runs(client, a.study, runs, sensitivity=False), a.repeat)

    pd.testing.assert_frame_equal(on_dask, local, check_exact=True)
    pd.testing.assert_frame_equal(local, ida_csv, check_exact=True)
    print("the three agree on every run (exactly)")
    print(f"| way | median wall (s) | runs/s |")
    print(f"|---|---:|---:|")
    print(f"| CLI `rocklab facade --scales` IDA part (rayon, 2 threads) | {t_cli_ida:.3f} | {n / t_cli_ida:.0f} |")
    print(f"| CLI whole command (+ 12-run study at 3 tolerances, plots, report) | {t_cli_wall:.3f} | {n / t_cli_wall:.0f} |")
    print(f"| `rocklab.facade_runs` in Python (rayon, 2 threads) | {t_local:.3f} | {n / t_local:.0f} |")
    print(f"| `rocklab.dask.facade_runs`, LocalCluster {a.workers} workers × 1 thread | {t_dask:.3f} | {n / t_dask:.0f} |")
    print(f"LocalCluster start-up: {t_start:.2f} s (once per session)")


if __name__ == "__main__":
    main()
