#!/usr/bin/env python3
"""A two-sided free-rocking campaign seen through a stated logger filter, made
independently of rocklab (scipy's solver and scipy's analogue Bessel filter), for
the calibration's filtered replay (tests/calibrate.rs,
`a_stated_filter_is_replayed`).

The wall (H 2.70 m, b 0.36 m, hinge 0.23 m, sensor at 2.56 m) rocks freely
(paper Eq. 1, rigid block, instantaneous impacts θ' <- e θ' with one e = 0.85),
released from rest at x0. The sensor reading L sin θ (held at x0 before the
release) is simulated on a grid 20x finer than the logger, passed through a
4th-order Bessel low-pass (scipy.signal.bessel(4, 2π fc, analog=True,
norm='mag'), −3 dB at fc = 0.10 fs, started in steady state at x0), then
sampled at fs = 100 Hz with a random phase, with N(0, 0.03 mm) noise.

    python3 tools/filtered_replay_campaign.py OUT_DIR [--fc-over-fs 0.10] [--seed 1]
"""
import argparse
import json
import os

import numpy as np
from scipy import signal
from scipy.integrate import solve_ivp

H, B, HINGE, SENSOR = 2.70, 0.36, 0.23, 2.56
E = 0.85
FS = 100.0
SIGMA = 0.03
TESTS = [("T0", 150), ("T1", 120), ("T2", 100), ("T3", 140)]


def rocking(theta0, e, t_end):
    """θ(t) of the rigid block released from rest at θ0 (t from the release)."""
    h = H - HINGE
    alpha = np.arctan(B / h)
    p2 = 3 * 9.81 / (4 * 0.5 * np.hypot(B, h))

    def rhs(_, y):
        s = np.sign(y[0]) if y[0] != 0 else np.sign(y[1])
        return [y[1], -p2 * s * np.sin(alpha - s * y[0])]

    def crossing(_, y):
        return y[0]

    crossing.terminal = True
    arcs, t0, y = [], 0.0, [theta0, 0.0]
    while t0 < t_end:
        sol = solve_ivp(rhs, (t0, t_end), y, events=crossing, rtol=1e-11, atol=1e-13, dense_output=True, max_step=0.01)
        arcs.append(sol)
        if sol.status != 1:
            break
        w = sol.y_events[0][0][1]
        t0, y = sol.t_events[0][0] + 1e-12, [1e-12 * np.sign(w), e * w]
        if abs(y[1]) < 1e-4:
            break

    def theta(t):
        out = np.zeros_like(t)
        for a in arcs:
            m = (t >= a.t[0]) & (t <= a.t[-1])
            if m.any():
                out[m] = a.sol(t[m])[0]
        return out

    return theta


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("out")
    ap.add_argument("--fc-over-fs", type=float, default=0.10)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    os.makedirs(args.out, exist_ok=True)
    lever = SENSOR - HINGE
    fc = args.fc_over_fs * FS
    b, a = signal.bessel(4, 2 * np.pi * fc, analog=True, norm="mag")
    t_hold, duration = 1.0, 6.0
    manifest = [
        "# Two-sided free rocking seen through a stated 4th-order Bessel logger filter;",
        "# made by tools/filtered_replay_campaign.py (scipy), truth in truth.json.",
        "[campaign]", 'name = "bessel-replay"', 'rocking = "two-sided"', "",
        "[wall]", f"height_m = {H}", f"thickness_m = {B}", "width_m = 1.68", "weight_kN = 29.4",
        f"hinge_height_m = {HINGE}", "",
        "[channels]", 'time = { column = "time_s", unit = "s" }',
        f'displacement = {{ column = "disp_mm", unit = "mm", height_m = {SENSOR} }}', "outward_sign = 1", "",
    ]
    for tid, x0 in TESTS:
        theta = rocking(np.arcsin(x0 / 1e3 / lever), E, duration)
        fine = np.arange(0.0, t_hold + duration, 1 / (20 * FS))
        x = np.where(fine < t_hold, x0, 1e3 * lever * np.sin(theta(np.clip(fine - t_hold, 0, None))))
        _, y, _ = signal.lsim((b, a), x - x0, fine)
        y += x0
        ts = np.arange(rng.uniform(0, 1 / FS), t_hold + duration - 0.01, 1 / FS)
        xs = np.interp(ts, fine, y) + rng.normal(0, SIGMA, ts.size)
        with open(os.path.join(args.out, f"{tid}.csv"), "w") as f:
            f.write("time_s,disp_mm\n")
            f.writelines(f"{t:.5f},{v:.3f}\n" for t, v in zip(ts, xs))
        manifest += [
            "[[test]]", f'id = "{tid}"', f'file = "{tid}.csv"',
            f'acquisition = {{ filter = "bessel", order = 4, cutoff_hz = {fc:.6g} }}',
            f"imposed_displacement_mm = {x0}", "exclude_from_mean = false", "",
        ]
    with open(os.path.join(args.out, "campaign.toml"), "w") as f:
        f.write("\n".join(manifest))
    truth = {"generator": "tools/filtered_replay_campaign.py (scipy solve_ivp rigid block, scipy.signal.bessel analog, lsim on a 20x grid)",
             "e": E, "fs_Hz": FS, "cutoff_hz": fc, "sigma_mm": SIGMA, "seed": args.seed}
    with open(os.path.join(args.out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)


if __name__ == "__main__":
    main()
