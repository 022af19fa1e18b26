#!/usr/bin/env python3
"""Does a one-sided wall's inward r depend on the amplitude alone, or on the impact's place in the test?

Not run by CI: a probe of the engine behind `tools/mujoco_campaign.py` (issue 20, the
inward side of a one-sided wall, docs/restitution-law.md). It releases one wall, with
one fixed draw of its bedding and transverse walls, from several displacements, and
prints the engine's own r_k = |v_{k+1}/v_k| / e_H of the inward impacts (k = 0, 2, 4, 6;
`--outward`: k = 1, 3, 5, 7, the ends of the pushes) with the amplitude
a_k = apex |theta| / alpha of the half-cycle each ends: the truth's peaks and crossings
exactly as the campaigns' truth.json (`campaign_common.truth_peaks`).
A release from a smaller displacement puts its first impact (the release's, k = 0) at
the amplitude of a later impact of a larger release, so the two can be compared at the
same amplitude, which a campaign's tests, all released from 130-170 mm, never allow.

    pip install mujoco numpy
    python3 tools/mujoco_release_probe.py --preset public-like-one-sided \
        --draw 0.0031,0.9,1800,0.07 --releases 170,140,110,80,60,45

`--draw` is what `build` would draw, in its order: the bedding's time constant (s),
the friction coefficient, the transverse walls' stiffness K (s^-2) and damping ratio.
"""
import argparse
import math

import mujoco_campaign as mc
from campaign_common import truth_peaks


def fixed(draw):
    """The draws of `build` as a stored `sim` block replays them (`mujoco_campaign.Replay`)."""
    tc, mu, k, zeta = draw
    return mc.Replay(dict(floor_solref=[tc, 1.0], friction_mu=mu, obst_K_target_per_s2=k, obst_zeta=zeta))


def impacts_r(p, draw, x0_mm, side):
    """(k, a_k, r_k) of the inward impacts k = 0, 2, 4, 6 (side 0) or the outward ones
    k = 1, 3, 5, 7 (side 1) of a release from x0_mm."""
    traj, _, t_rel, _ = mc.simulate(p, x0_mm, fixed(draw))
    peaks, _ = truth_peaks(traj, t_rel)
    alpha = math.atan(p["b"] / p["H"])
    e_h = 1 - 1.5 * math.sin(alpha) ** 2
    t, th = traj[:, 0], traj[:, 3]
    rows = []
    start = int(t.searchsorted(t_rel))
    for k in range(side, min(len(peaks) - 1, 8 + side), 2):
        # Impact k ends half-cycle k; its apex lies between peak k - 1 (just before
        # crossing k - 1) and peak k (the release for k = 0).
        lo = start if k == 0 else peaks[k - 1]["i"]
        apex = max(abs(x) for x in th[lo : peaks[k]["i"] + 1]) / alpha
        r = abs(peaks[k + 1]["velocity_mm_s"] / peaks[k]["velocity_mm_s"]) / e_h
        rows.append((k, apex, r))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--preset", required=True, choices=sorted(mc.PRESETS))
    ap.add_argument("--draw", required=True, help="bedding time constant, friction, K, damping ratio")
    ap.add_argument("--releases", required=True, help="release displacements in mm, comma-separated")
    ap.add_argument("--outward", action="store_true", help="the outward impacts (k odd, the pushes' ends) instead")
    args = ap.parse_args()
    p = mc.PRESETS[args.preset]
    if p["rocking"] != "one-sided":
        ap.error("the probe asks about a one-sided wall (its inward or, with --outward, its outward impacts)")
    draw = [float(v) for v in args.draw.split(",")]
    for x0 in [float(v) for v in args.releases.split(",")]:
        rows = impacts_r(p, draw, x0, 1 if args.outward else 0)
        print(f"x0 {x0:5.0f} mm  " + "  ".join(f"k{k} a {a:.3f} r {r:.4f}" for k, a, r in rows), flush=True)


if __name__ == "__main__":
    main()
