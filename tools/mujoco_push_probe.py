#!/usr/bin/env python3
"""Where a one-sided wall's push ends: the transverse walls letting go, the outward toe's bedding, the peak.

Not run by CI: a probe of the engine behind `tools/mujoco_campaign.py` (docs/restitution-law.md,
"Where the pushes' low readings come from"). It releases one wall, with one fixed draw of
its bedding and transverse walls, and prints for every push (a half-cycle on the inward
side, theta < 0, that ends at a crossing k odd) the times, relative to the crossing, of:
- the velocity peak (the extreme of the sensor's horizontal velocity, as the truth's);
- the last engine step at which the transverse walls still push;
- the first step at which the outward toe's bedding carries a force,
with the speeds there, at every 0.1 ms engine step.

    pip install mujoco numpy
    python3 tools/mujoco_push_probe.py --preset public-like-one-sided --draw 0.0031,0.9,1800,0.07 --release 150

`--draw` is what `build` would draw, in its order: the bedding's time constant (s), the
friction coefficient, the transverse walls' stiffness K (s^-2) and damping ratio.
"""
import argparse
import math

import mujoco
import numpy as np

import mujoco_campaign as mc
from mujoco_release_probe import fixed


def run(p, draw, x0_mm, seconds):
    """Rows (t, sensor velocity mm/s, theta, transverse walls' force N, outward toe's bedding force N)."""
    m, _ = mc.build(p, fixed(draw))
    d = mujoco.MjData(m)
    mc.set_tilt(m, d, p, math.asin(x0_mm / 1000.0 / p["L"]))
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    t_rel, rows = 1.0, []
    for _ in range(int((t_rel + seconds) / mc.DT)):
        if d.time >= t_rel:
            d.eq_active[0] = 0
        mujoco.mj_step(m, d)
        vel = np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, 0, vel, 0)
        walls = toe = 0.0
        for c in range(d.ncon):
            con, f = d.contact[c], np.zeros(6)
            mujoco.mj_contactForce(m, d, c, f)
            if floor in (con.geom1, con.geom2):
                toe += f[0] if con.pos[0] > 0 else 0.0
            else:
                walls += f[0]
        rows.append((d.time, 1000.0 * vel[3], mc.theta_of(d), walls, toe))
    return np.array(rows), t_rel


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", required=True, choices=sorted(k for k in mc.PRESETS if "one-sided" in k))
    ap.add_argument("--draw", required=True, help="bedding time constant, friction, K, damping ratio")
    ap.add_argument("--release", type=float, default=150.0, help="release displacement (mm)")
    ap.add_argument("--seconds", type=float, default=7.0, help="how long after the release")
    args = ap.parse_args()
    a, t_rel = run(mc.PRESETS[args.preset], [float(x) for x in args.draw.split(",")], args.release, args.seconds)
    t, v, th, walls, toe = a.T
    i0 = int(np.searchsorted(t, t_rel))
    cross = [i for i in range(i0 + 1, len(t)) if th[i - 1] * th[i] < 0]
    for n, ic in enumerate(cross[:12]):
        if th[ic - 1] >= 0:
            continue

        def ms(i, ic=ic):
            return 1000.0 * (t[i] - t[ic])

        seg = range(cross[n - 1] if n > 0 else i0, ic + 1)
        peak = max(seg, key=lambda j: v[j])
        held = [j for j in seg if walls[j] > 0]
        bed = [j for j in seg if toe[j] > 0]
        line = f"k{n:<2} peak {v[peak]:8.2f} mm/s at {ms(peak):+6.1f} ms"
        if held:
            line += f"; walls let go {ms(held[-1]):+6.1f} ms at {v[held[-1]]:8.2f} mm/s"
        if bed:
            line += f"; outward toe's bedding from {ms(bed[0]):+6.1f} ms"
        print(line)


if __name__ == "__main__":
    main()
