"""What the engine-campaign scripts share (tools/mujoco_campaign.py, tools/penalty_campaign.py).

An engine script simulates one test at a time and hands back its trajectory: an array
with one row per recorded step, (time_s, sensor x in m, sensor horizontal velocity in
m/s, theta in rad, height of the higher toe above the bedding in m). This module turns
those into a campaign: the truth's velocity peaks (the extreme of the sensor's
horizontal velocity within each half-cycle between zero crossings of theta), the
tables' values (paper Eqs. 3-6), the logger (random phase, Gaussian noise, linear
drift, 0.01 mm quantisation unless `--noise-mm` sets the noise, sampled at fs) and the files (campaign.toml, one CSV per
test, truth.json), in the format the Rust tests read (tests/truth.rs,
tests/local_readings.rs, tests/law.rs).
"""
import argparse
import json
import math
import os

import numpy as np


def truth_peaks(a, t_rel):
    """Velocity peaks of half-cycles 0..11 and the zero crossings of theta after t_rel."""
    t, v, th = a[:, 0], a[:, 2], a[:, 3]
    i0 = np.searchsorted(t, t_rel)
    cross = []
    for i in range(i0 + 1, len(t)):
        if th[i - 1] * th[i] < 0 or (th[i] == 0 and th[i - 1] != 0):
            cross.append(i)
    peaks = []
    start = i0
    for k, ic in enumerate(cross[:12]):
        seg = slice(start, ic + 1)
        want = -1.0 if k % 2 == 0 else 1.0
        j = start + int(np.argmax(want * v[seg]))
        lifted = float(np.mean(a[seg, 4] > 0.0))
        peaks.append(dict(k=k, i=j, velocity_mm_s=1000.0 * v[j], lift_fraction=lifted))
        start = ic
    return peaks, [t[i] for i in cross[:12]]


def tables(v, e_h):
    loc = [abs(v[k + 1] / v[k]) for k in range(5)]
    ss = lambda k: math.sqrt(abs(v[k + 2] / v[k]))
    e = sum(loc) / 5
    e_minus = 0.5 * (ss(0) + ss(2))
    e_plus = 0.5 * (ss(1) + ss(3))
    return dict(e=e, e_plus=e_plus, e_minus=e_minus, r=e / e_h, r_plus=e_plus / e_h,
                r_minus=e_minus / e_h, r1=loc[0] / e_h, r1_plus=ss(1) / e_h, r1_minus=ss(0) / e_h,
                r2=0.5 * (loc[0] + loc[1]) / e_h)


def write_campaign(p, out, how, rng, simulate, engine, script, toml_header):
    """Simulate every test of preset `p` (draws from `rng`, in order: the engine's, then
    the logger's), refuse a test whose wall stops rocking before peak 6, write the files.

    simulate(p, x0_mm, rng) -> (trajectory, theta0, t_release, sim block);
    engine: dict of the `sim` block's first engine keys (its name as `engine`, then e.g. the
    time step); script: the script's path for the generator line; toml_header: the
    comment lines that open campaign.toml.
    """
    os.makedirs(out, exist_ok=True)
    name = os.path.basename(os.path.normpath(out))
    H, b = p["H"], p["b"]
    alpha = math.atan(b / H)
    e_h = 1 - 1.5 * math.sin(alpha) ** 2
    mass = p["density"] * H * b * p["w"]
    toml = list(toml_header) + [
        "", "[campaign]", f'name = "{name}"', f'rocking = "{p["rocking"]}"', "", "[wall]",
        f"height_m = {H:.2f}", f"thickness_m = {b:.2f}", f"width_m = {p['w']:.2f}",
        f"weight_kN = {mass * 9.81 / 1000:.1f}", "hinge_height_m = 0.00", "", "[channels]",
        'time = { column = "time_s", unit = "s" }',
        f'displacement = {{ column = "disp_mm", unit = "mm", height_m = {p["L"]:.2f} }}',
        "outward_sign = 1", "", "[format]", 'delimiter = ","', 'decimal = "."']
    tests = []
    for tid, x0, fs in p["tests"]:
        a, theta0, t_rel, sim = simulate(p, x0, rng)
        peaks, cross = truth_peaks(a, t_rel)
        # As the public campaigns: a test is only made if its wall still rocks (one
        # edge off the bedding for most of each half-cycle) through the six peaks the
        # tables use; below that the "half-cycles" are the bedding's own wobble.
        lift = [q["lift_fraction"] for q in peaks]
        if len(peaks) < 6 or min(lift[:6]) < 0.5:
            raise SystemExit(f"{tid}: the wall stops rocking before peak 6 (lift fractions {lift})")
        # Logger: a random phase, from 1 s before the release to 3 s after the motion ends.
        sigma = rng.uniform(0.01, 0.04)
        drift = rng.uniform(-0.2, 0.2)
        # --noise-mm: the same draws (the stream is unchanged), another noise and no
        # quantisation: what the readings' model form costs without the logger's noise.
        quant = 0.01
        if p.get("noise_mm") is not None:
            sigma, quant = p["noise_mm"], None
        t_start = t_rel - 1.0 + rng.uniform(0, 1 / fs)
        t_end = min(a[-1, 0], cross[-1] + 3.0)
        ts = np.arange(t_start, t_end, 1 / fs)
        x_rest = a[-1, 1]
        xs = np.interp(ts, a[:, 0], a[:, 1]) - x_rest
        xs = 1000.0 * xs
        xs += rng.normal(0, sigma, len(ts)) + drift * (ts - ts[0]) / (ts[-1] - ts[0])
        if quant is not None:
            xs = np.round(xs / quant) * quant
        t_file = ts - ts[0]
        with open(os.path.join(out, f"{tid}.csv"), "w") as f:
            f.write(f"# campaign: {name}\n# test: {tid}\n# sampling_rate_Hz: {fs}\n")
            f.write(f"# channels: time_s [s]; disp_mm [mm] LVDT at {p['L']:.2f} m, positive = outward\n")
            f.write("time_s,disp_mm\n")
            for ti, xi in zip(t_file, xs):
                f.write(f"{ti:.6f},{xi:.2f}\n" if quant is not None else f"{ti:.6f},{xi:.6f}\n")
        pk = [dict(k=q["k"], time_s=a[q["i"], 0] - ts[0], velocity_mm_s=q["velocity_mm_s"]) for q in peaks]
        v = [q["velocity_mm_s"] for q in pk]
        tab = tables(v, e_h)
        sim.update(**engine, fs_Hz=fs, sigma_mm=sigma, drift_mm=drift,
                   quant_mm=quant, x0_mm_nominal=x0, theta0_rad=theta0, t_release_s=t_rel - ts[0],
                   zero_crossings_s=[c - ts[0] for c in cross], rocking_mass_kg=mass,
                   lift_fraction_per_half_cycle=lift)
        tests.append(dict(id=tid, file=f"{tid}.csv", exclude_from_mean=False, sim=sim, peaks=pk,
                          **{k: tab[k] for k in ("r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2")},
                          e=tab["e"], e_plus=tab["e_plus"], e_minus=tab["e_minus"]))
        toml += ["", "[[test]]", f'id = "{tid}"', f'file = "{tid}.csv"', f"imposed_displacement_mm = {x0}",
                 "exclude_from_mean = false"]
        print(tid, fs, " ".join(f"{x:.1f}" for x in v[:8]), {k: round(tab[k], 4) for k in ("r", "r1")})
    with open(os.path.join(out, "campaign.toml"), "w") as f:
        f.write("\n".join(toml) + "\n")
    truth = dict(campaign=name, rocking=p["rocking"], generator=f"{engine['engine']}, {script} {how}",
                 conventions="as mujoco-public-*: peaks[k] = extreme of the sensor's horizontal velocity within half-cycle k (mm/s, outward positive); r.. divided by e_H",
                 alpha_rad=alpha, e_housner=e_h, e_H=e_h, wall=dict(height_m=H, thickness_m=b, width_m=p["w"], sensor_height_m=p["L"]),
                 tests=tests)
    with open(os.path.join(out, "truth.json"), "w") as f:
        json.dump(truth, f, indent=1)


def stored_test(out, tid):
    """Test `tid`'s entry in the truth.json of the campaign in `out`."""
    truth = json.load(open(os.path.join(out, "truth.json")))
    return next(x for x in truth["tests"] if x["id"] == tid)


def write_trace(a, t_rel, test, trace):
    """Check that a re-simulated test's peaks are truth.json's, then write its trajectory.

    a: the trajectory (rows as `truth_peaks` reads them); test: its truth.json entry.
    Writes time_s (on the log's time axis), x_mm (sensor point, rest subtracted),
    v_mm_s, theta_rad at every recorded step.
    """
    tid, sim = test["id"], test["sim"]
    peaks, _ = truth_peaks(a, t_rel)
    got = [q["velocity_mm_s"] for q in peaks[:6]]
    want = [q["velocity_mm_s"] for q in test["peaks"][:6]]
    if max(abs(g - w) for g, w in zip(got, want)) > 1e-3:
        raise SystemExit(f"{tid}: peaks {got} differ from truth.json's {want}: another preset or engine?")
    shift = t_rel - sim["t_release_s"]
    with open(trace, "w") as f:
        f.write("time_s x_mm v_mm_s theta_rad\n")
        for row in a:
            f.write(f"{row[0] - shift:.6f} {1000.0 * (row[1] - a[-1, 1]):.5f} {1000.0 * row[2]:.4f} {row[3]:.8f}\n")
    print(f"{tid}: peaks as in truth.json; {len(a)} steps written to {trace}")


def cli(presets, make, resimulate, check=None):
    """The engine scripts' command line: --preset/--out [--seed] makes a campaign with
    make(preset, out, how, rng); --resimulate TEST --trace FILE runs
    resimulate(preset, out, TEST, FILE); --check (where the script has one) runs check()."""
    ap = argparse.ArgumentParser()
    ap.add_argument("--preset", required=check is None, choices=sorted(presets))
    ap.add_argument("--out", required=check is None)
    ap.add_argument("--seed", type=int, default=None,
                    help="seed of the random draws (default: the preset's); another seed draws "
                         "other beddings, restraints, noise and drift for the same wall and tests")
    if check is not None:
        ap.add_argument("--check", action="store_true", help="the engine's own checks")
    ap.add_argument("--noise-mm", type=float, default=None,
                    help="the logger's noise (mm) in place of the drawn one, and no 0.01 mm "
                         "quantisation; every other draw as without it")
    ap.add_argument("--resimulate", metavar="TEST", help="run TEST of the campaign in --out again")
    ap.add_argument("--trace", help="where --resimulate writes the trajectory")
    args = ap.parse_args()
    if check is not None and args.check:
        return check()
    if not args.preset or not args.out:
        raise SystemExit("--preset and --out, or --check")
    p = presets[args.preset]
    if args.resimulate:
        if not args.trace:
            raise SystemExit("--resimulate needs --trace FILE")
        return resimulate(p, args.out, args.resimulate, args.trace)
    seed = p["seed"] if args.seed is None else args.seed
    rng = np.random.default_rng(seed)
    how = f"--preset {args.preset}" + ("" if args.seed is None else f" --seed {args.seed}")
    if args.noise_mm is not None:
        p = dict(p, noise_mm=args.noise_mm)
        how += f" --noise-mm {args.noise_mm:g}"
    make(p, args.out, how, rng)
