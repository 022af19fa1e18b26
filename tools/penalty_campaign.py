#!/usr/bin/env python3
"""Make a free-rocking campaign with a second, independent engine: penalty contacts.

Not run by CI. Every other engine check is MuJoCo (tools/mujoco_campaign.py), whose
soft constraints have their own quirks (docs/accuracy.md); this engine has other
contact physics, to tell whether the reducer is tuned to MuJoCo's contacts.

The wall is a rigid rectangle in the plane (x, z, theta: 3 degrees of freedom; theta > 0
outward, about +y) on a compliant bedding modelled as penalty contacts at points of its
base (the two toes, or `base_points` points evenly spaced from toe to toe):
- normal force, Hunt-Crossley's form with a constant loss factor: F = k d^n (1 + lam d'),
  d the point's penetration (n 1-1.5), F >= 0 (no pull); k is set by the static
  penetration delta_s of one toe under half the weight (shared evenly by the points);
- tangential force, a stiff spring to where the point touched (stick) capped at mu F
  (slip moves the anchor): the toe does not slide;
- one-sided walls: the transverse walls are a penalty contact on the wall's inward face
  at height h_r, gap 0 at theta = 0: F = k_r d_ref (d/d_ref)^m + c_r d' >= 0 (d_ref
  5 mm, m 1-1.5), frictionless; the restraint's stiffness in theta (about k_r h_r^2)
  follows from h_r and the wall.
Integrated with semi-implicit (symplectic) Euler at a fixed step DT (1e-5 s; checked
with --check: energy with the damping off, Housner's e_H in the stiff plastic limit,
and the peaks at DT/2). The wall is held still at theta0 (theta locked, x and z free
on the bedding) for 1 s, then released, as mujoco_campaign.py does; the sensor point's
horizontal position and velocity are recorded every 0.1 ms.

Output in exactly the format of tools/mujoco_campaign.py (tools/campaign_common.py:
campaign.toml, one CSV per test, truth.json with peaks, zero crossings, lift fractions
and the table values), so that tests/truth.rs's engine_campaigns,
tests/local_readings.rs's fresh_engine_campaigns and tests/law.rs's
holdout_law_from_readings read it unchanged. numpy only (pure-Python stepping: about
17 s of wall time for a campaign of five tests; --check about 20 s).

    python3 tools/penalty_campaign.py --preset penalty-two-sided --seed 1 --out /tmp/pen2-s1
    python3 tools/penalty_campaign.py --preset penalty-one-sided --seed 1 --out /tmp/pen1-s1
    python3 tools/penalty_campaign.py --check

`--resimulate TEST --trace FILE` runs one test of the campaign in `--out` again from the
draws stored in its truth.json `sim` block (the preset must be the one that made it),
checks its peaks against truth.json and writes the trajectory every 0.1 ms on the log's
time axis (time_s, x_mm, v_mm_s, theta_rad), as mujoco_campaign.py's does:

    python3 tools/penalty_campaign.py --preset penalty-one-sided --out /tmp/pen1-s3 \
        --resimulate E1_140_1 --trace /tmp/E1_140_1.txt
"""
import math

import numpy as np

from campaign_common import cli, stored_test, truth_peaks, write_campaign, write_trace

G = 9.81
DT = 1e-5
REC_EVERY = 10  # record every 0.1 ms, as mujoco_campaign.py

PRESETS = {
    # The public campaigns' wall (H 3.00 m, b 0.40 m, LVDT at 2.90 m) and the tests of
    # mujoco_campaign.py's public-like presets (same amplitudes and rates), on this
    # engine's contacts: the comparison with the MuJoCo stand-ins is the engine's alone.
    # Two-sided: a soft, lossy bedding of five points along the base (first-impact
    # contacts 12-30 ms, v1/v0 0.85-0.95).
    "penalty-two-sided": dict(
        rocking="two-sided", H=3.00, b=0.40, w=2.00, density=1998.5, L=2.90,
        base_points=5, n=(1.0, 1.5), delta_s=(0.15e-3, 0.4e-3), lam=(15.0, 60.0),
        tests=[("E2_150_1", 150, 200), ("E2_130_1", 130, 1000), ("E2_110_1", 110, 100),
               ("E2_90_1", 90, 500), ("E2_70_1", 70, 200)],
        seed=14_21,
    ),
    # One-sided: a stiff bedding of three points (toes and middle; contacts 4-9 ms) and
    # transverse walls at 0.70-0.95 H whose secant stiffness at 5 mm is 1.5-8 MN/m
    # (inward half-cycles 50-130 ms).
    "penalty-one-sided": dict(
        rocking="one-sided", H=3.00, b=0.40, w=2.00, density=1961.4, L=2.90,
        base_points=3, n=(1.0, 1.5), delta_s=(0.08e-3, 0.2e-3), lam=(30.0, 120.0),
        k_r=(1.5e6, 8e6), h_r=(0.70, 0.95), m_r=(1.0, 1.5), zeta_r=(0.03, 0.10),
        tests=[("E1_170_1", 170, 200), ("E1_160_1", 160, 500), ("E1_150_1", 150, 1000),
               ("E1_140_1", 140, 200), ("E1_155_1", 155, 100)],
        seed=14_11,
    ),
}
# Diagnostic variants (docs/accuracy.md, "A second engine: penalty contacts"): each
# wall on its two toes only, and the one-sided wall with linear transverse walls (m = 1). The first test's draws are the preset's; later tests' differ, as the
# logger's noise draws depend on the length of the trajectory before them.
PRESETS["penalty-two-sided-toes"] = dict(PRESETS["penalty-two-sided"], base_points=2, seed=14_23)
PRESETS["penalty-one-sided-linear"] = dict(PRESETS["penalty-one-sided"], m_r=(1.0, 1.0), seed=14_13)
PRESETS["penalty-one-sided-toes"] = dict(PRESETS["penalty-one-sided"], base_points=2, seed=14_14)
D_REF = 5e-3  # m: the restraint's k_r is its secant stiffness at this penetration


def draw(p, rng):
    """The test's bedding, friction and (one-sided) restraint, drawn from the preset's ranges."""
    q = dict(bed_exponent_n=rng.uniform(*p["n"]), bed_static_penetration_m=rng.uniform(*p["delta_s"]),
             bed_loss_lambda_s_per_m=rng.uniform(*p["lam"]), friction_mu=rng.uniform(0.7, 1.0),
             base_points=p["base_points"])
    if p["rocking"] == "one-sided":
        q.update(restraint_k_N_per_m=rng.uniform(*p["k_r"]), restraint_height_m=rng.uniform(*p["h_r"]) * p["H"],
                 restraint_exponent_m=rng.uniform(*p["m_r"]), restraint_zeta=rng.uniform(*p["zeta_r"]))
    return q


def model(p, q):
    """Constants of the equations of motion for wall `p` and draws `q`."""
    H, b = p["H"], p["b"]
    m = p["density"] * H * b * p["w"]
    n = q["bed_exponent_n"]
    npts = q["base_points"]
    # Half the weight on one toe sinks it by delta_s (toes only); with more points the
    # same total stiffness is shared evenly.
    k_toe = 0.5 * m * G / q["bed_static_penetration_m"] ** n
    k_pt = k_toe * 2.0 / npts
    # Tangential stick spring: the normal contact's linear stiffness at the static load,
    # critically damped on half the mass.
    kt = k_pt * n * q["bed_static_penetration_m"] ** (n - 1)
    c = dict(m=m, I=m * (H * H + b * b) / 12.0, hb=b / 2, hh=H / 2, n=n, k=k_pt, kt=kt,
             ct=q.get("tangential_damping", 1.0) * 2.0 * math.sqrt(kt * m / npts),
             hc=q["bed_loss_lambda_s_per_m"], mu=q["friction_mu"],
             px=[(-b / 2 + b * i / (npts - 1)) for i in range(npts)], L=p["L"])
    if "restraint_k_N_per_m" in q:
        hr = q["restraint_height_m"]
        mr = q["restraint_exponent_m"]
        c.update(kr=q["restraint_k_N_per_m"] * D_REF ** (1.0 - mr), mr=mr, pzr=hr - H / 2)
        # zeta of the linear restraint on the wall's mass seen at h_r about the inward toe.
        m_eff = m * (H * H + b * b) / 3.0 / (hr * hr)
        c["cr"] = 2.0 * q["restraint_zeta"] * math.sqrt(q["restraint_k_N_per_m"] * m_eff)
    return c


def run(c, theta0, t_hold, t_max, dt=DT, rec_every=REC_EVERY, energy=False):
    """Hold at theta0 for t_hold, release, step until still or t_max.

    Rows: time, sensor x, sensor vx, theta, height of the higher toe; with energy=True
    also the total mechanical energy (gravity, kinetic, the springs' stored energy).
    """
    m, I, hb, hh, n, k, kt, ct, hc, mu, L = (c[s] for s in ("m", "I", "hb", "hh", "n", "k", "kt", "ct", "hc", "mu", "L"))
    pxs = c["px"]
    npt = len(pxs)
    restr = "kr" in c
    if restr:
        kr, mr, cr, pzr = c["kr"], c["mr"], c["cr"], c["pzr"]
    sin, cos = math.sin, math.cos
    # Start: resting on the outward toe at its static penetration under the full weight.
    th, thd = theta0, 0.0
    s0, c0 = sin(th), cos(th)
    d0 = (m * G / k) ** (1.0 / n)
    z = hb * s0 + hh * c0 - d0
    x = hb - hb * c0 + hh * s0
    xd = zd = 0.0
    touching = [False] * npt
    anchor = [0.0] * npt
    es = [0.0] * npt  # tangential spring energy (for energy=True)
    rows = []
    steps = int(round((t_hold + t_max) / dt))
    i_rel = int(round(t_hold / dt))
    still = 0
    n_still = int(round(2.0 / dt))
    for i in range(steps + 1):
        s, co = sin(th), cos(th)
        fx = 0.0
        fz = -m * G
        mom = 0.0
        epot = 0.0
        for j in range(npt):
            px = pxs[j]
            rx = px * co - hh * s
            rz = -px * s - hh * co
            Z = z + rz
            if Z < 0.0:
                X = x + rx
                Xd = xd + thd * (-px * s - hh * co)
                Zd = zd + thd * (-px * co + hh * s)
                d = -Z
                if not touching[j]:
                    touching[j] = True
                    anchor[j] = X
                dn = d ** n
                fn = k * dn * (1.0 - hc * Zd)
                if fn < 0.0:
                    fn = 0.0
                ft = -kt * (X - anchor[j]) - ct * Xd
                cap = mu * fn
                if ft > cap:
                    ft = cap
                    anchor[j] = X + cap / kt
                elif ft < -cap:
                    ft = -cap
                    anchor[j] = X - cap / kt
                fx += ft
                fz += fn
                mom += rz * ft - rx * fn
                if energy:
                    u = X - anchor[j]
                    epot += k * dn * d / (n + 1.0) + 0.5 * kt * u * u
            else:
                touching[j] = False
        if restr:
            rx = -hb * co + pzr * s
            X = x + rx
            d = -hb - X
            if d > 0.0:
                rz = hb * s + pzr * co
                Xd = xd + thd * (hb * s + pzr * co)
                fr = kr * d ** mr - cr * Xd
                if fr < 0.0:
                    fr = 0.0
                fx += fr
                mom += rz * fr
                if energy:
                    epot += kr * d ** (mr + 1.0) / (mr + 1.0)
        xd += fx / m * dt
        zd += fz / m * dt
        if i >= i_rel:
            thd += mom / I * dt
        x += xd * dt
        z += zd * dt
        th += thd * dt
        if i % rec_every == 0:
            lift = max(z - px * sin(th) - hh * cos(th) for px in (hb, -hb))
            xs = x + hb * cos(th) + (L - hh) * sin(th)
            vs = xd + thd * (-hb * sin(th) + (L - hh) * cos(th))
            row = [(i + 1) * dt, xs, vs, th, lift]
            if energy:
                row.append(0.5 * m * (xd * xd + zd * zd) + 0.5 * I * thd * thd + m * G * z + epot)
            rows.append(row)
        if i >= i_rel:
            if abs(th) < 2e-5 and abs(thd) < 2e-4:
                still += 1
                if still > n_still:
                    break
            else:
                still = 0
    return np.array(rows)


def simulate(p, x0_mm, rng):
    q = draw(p, rng)
    theta0 = math.asin(x0_mm / 1000.0 / p["L"])
    t_rel = 1.0
    a = run(model(p, q), theta0, t_rel, 30.0)
    q.update(first_impact_contact_s=first_contact(a, t_rel))
    return a, theta0, t_rel, q


def resimulate(p, out, tid, trace):
    """Run test `tid` of the campaign in `out` again from its `sim` block's draws and
    write its trajectory (as mujoco_campaign.py's --resimulate)."""
    test = stored_test(out, tid)
    sim = test["sim"]
    q = {k: sim[k] for k in draw(p, np.random.default_rng(0))}
    a = run(model(p, q), sim["theta0_rad"], 1.0, 30.0)
    write_trace(a, 1.0, test, trace)


def first_contact(a, t_rel):
    """Duration of the first impact: from the inward toe's touch-down (the higher toe
    reaching the bedding after the release) to the first crossing of theta = 0 after
    which the outward toe has lifted (the higher toe's height rising above 0 again)."""
    t, lift = a[:, 0], a[:, 4]
    i = int(np.searchsorted(t, t_rel))
    while i < len(t) and lift[i] > 0.0:
        i += 1
    j = i
    while j < len(t) and lift[j] <= 0.0:
        j += 1
    return float(t[j] - t[i]) if j < len(t) else None


def check():
    """The engine's checks (docs/accuracy.md, "A second engine: penalty contacts")."""
    p2 = PRESETS["penalty-two-sided"]
    H, b = p2["H"], p2["b"]
    e_h = 1 - 1.5 * math.sin(math.atan(b / H)) ** 2
    theta0 = math.asin(0.100 / p2["L"])
    base = dict(bed_exponent_n=1.0, friction_mu=0.9, base_points=2)
    # 1. Energy with the damping off (lam = 0, no tangential damping): drift over 6 s
    # of free rocking on the two toes (each impact hands energy to the bedding's
    # vibration, which no damping takes out).
    for dt in (2e-5, 1e-5):
        q = dict(base, bed_static_penetration_m=3e-4, bed_loss_lambda_s_per_m=0.0, tangential_damping=0.0)
        a = run(model(p2, q), theta0, 0.5, 6.0, dt=dt, energy=True)
        e = a[a[:, 0] > 0.5, 5]
        # The rocking energy: the centre of mass's rise at theta0 above the rest.
        rr = math.hypot(H, b) / 2
        rock = model(p2, q)["m"] * G * rr * (math.cos(math.atan(b / H) - theta0) - math.cos(math.atan(b / H)))
        print(f"energy, damping off, dt {dt:g} s, delta_s 0.3 mm: max |E - E0| over 6 s after the release "
              f"{np.max(np.abs(e - e[0])):.4f} J = {np.max(np.abs(e - e[0])) / rock:.2e} of the rocking energy "
              f"{rock:.1f} J; at the end {e[-1] - e[0]:+.4f} J")
    # 2. Housner: the speed ratio across the first impact, two toes, as the bedding
    # stiffens, lossless (lam 0) and lossy.
    print(f"Housner e_H = {e_h:.4f} (H {H} m, b {b} m)")
    for lam in (0.0, 100.0):
        for ds in (1e-3, 1e-4, 1e-5, 1e-6):
            q = dict(base, bed_static_penetration_m=ds, bed_loss_lambda_s_per_m=lam)
            dt = 1e-5 if ds >= 1e-4 else (2e-6 if ds >= 1e-5 else 5e-7)
            a = run(model(p2, q), theta0, 0.2, 2.2, dt=dt, rec_every=max(1, int(round(1e-4 / dt))))
            pk, _ = truth_peaks(a, 0.2)
            v = [x["velocity_mm_s"] for x in pk[:3]]
            print(f"  lam {lam:g} s/m, delta_s {ds * 1e3:g} mm: v1/v0 {abs(v[1] / v[0]):.4f} "
                  f"({abs(v[1] / v[0]) / e_h:.4f} e_H), v2/v1 {abs(v[2] / v[1]):.4f}; first contact "
                  f"{1e3 * first_contact(a, 0.2):.2f} ms")
    # 3. Time step: a preset draw at DT and DT/2.
    for name in ("penalty-two-sided", "penalty-one-sided"):
        p = PRESETS[name]
        q = draw(p, np.random.default_rng(p["seed"]))
        th0 = math.asin(0.150 / p["L"])
        out = []
        for dt in (DT, DT / 2):
            a = run(model(p, q), th0, 0.2, 4.5, dt=dt, rec_every=int(round(1e-4 / dt)))
            out.append([x["velocity_mm_s"] for x in truth_peaks(a, 0.2)[0][:6]])
        rel = max(abs(u / w - 1) for u, w in zip(*out))
        print(f"{name}: peaks at dt {DT:g} {[round(float(v), 1) for v in out[0]]}, at dt/2 "
              f"{[round(float(v), 1) for v in out[1]]}: largest difference {100 * rel:.3f} %")


def make(p, out, how, rng):
    header = [f"# Check campaign made with penalty contacts by tools/penalty_campaign.py {how}",
              "# (rigid wall, Hunt-Crossley bedding at points of the base, penalty transverse walls); truth in truth.json."]
    write_campaign(p, out, how, rng, simulate, dict(engine="penalty contacts (tools/penalty_campaign.py)", timestep_s=DT),
                   "tools/penalty_campaign.py", header)


if __name__ == "__main__":
    cli(PRESETS, make, resimulate, check)
