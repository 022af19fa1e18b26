#!/usr/bin/env python3
"""One logged test seen through a digital logger filter, made with scipy (not
rocklab's filter code), for the regression test
`tests/truth.rs::a_filter_and_failing_contacts_leave_the_test_suspect`.

Reads a rocklab CSV log (comment lines, header `time_s,disp_mm`), passes the
displacement through a causal 4th-order Bessel low-pass on its own samples
(scipy.signal.bessel(4, 2 fc / fs, norm='mag'), −3 dB at fc = FC_OVER_FS · fs,
started in steady state at the first sample) and writes it with the same header
and one more comment line that says so.

    python3 tools/filtered_log.py fixtures/campaigns/mujoco-public-like-two-sided-100hz/Q2_110_1.csv \
        fixtures/campaigns/mujoco-public-like-two-sided-100hz-filtered/Q2_110_1_bessel.csv --fc-over-fs 0.35
"""
import argparse

import numpy as np
from scipy import signal


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("src")
    ap.add_argument("out")
    ap.add_argument("--fc-over-fs", type=float, default=0.35)
    args = ap.parse_args()
    lines = open(args.src).read().splitlines()
    comments = [l for l in lines if l.startswith("#")]
    rows = [l for l in lines if l and not l.startswith("#") and not l.startswith("time_s")]
    d = np.array([[float(v) for v in l.split(",")] for l in rows])
    fs = 1.0 / np.median(np.diff(d[:, 0]))
    b, a = signal.bessel(4, 2.0 * args.fc_over_fs, norm="mag")
    y = signal.lfilter(b, a, d[:, 1] - d[0, 1]) + d[0, 1]
    note = f"# filtered: causal Bessel 4, -3 dB at {args.fc_over_fs:g} fs ({args.fc_over_fs * fs:g} Hz), scipy lfilter on the samples (tools/filtered_log.py)"
    with open(args.out, "w") as f:
        f.write("\n".join(comments + [note, "time_s,disp_mm"]) + "\n")
        f.write("\n".join(f"{t:.6f},{x:.4f}" for t, x in zip(d[:, 0], y)) + "\n")


if __name__ == "__main__":
    main()
