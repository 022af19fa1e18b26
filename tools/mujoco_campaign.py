#!/usr/bin/env python3
"""Make a free-rocking campaign with the MuJoCo physics engine (compliant contacts).

Not run by CI: it makes hold-out campaigns of walls the estimator has not been tuned on
(issue 18): a rigid box on a compliant bedding (MuJoCo soft contacts, so impacts last
several ms and begin before theta = 0) and, one-sided, two fixed transverse-wall blocks
with a damped compliant contact (a lossy inward restraint). Same engine set-up as the
`mujoco-public-*` campaigns (`sim` blocks of their truth.json), other walls and rates.

    pip install mujoco numpy
    python3 tools/mujoco_campaign.py --preset holdout-one-sided --out fixtures/campaigns/mujoco-holdout-one-sided
    python3 tools/mujoco_campaign.py --preset holdout-two-sided --out fixtures/campaigns/mujoco-holdout-two-sided
    python3 tools/mujoco_campaign.py --preset fresh-one-sided --seed 11 --out /tmp/fresh-one-11

`--seed` replaces the preset's seed (other beddings, restraints, noise and drift for the
same wall and tests); a draw whose wall stops rocking before peak 6 is refused.
`--noise-mm S` keeps every draw of the seed but sets the logger's noise to S mm and
drops the 0.01 mm quantisation (the file keeps 6 decimals): what the readings' model
form costs without the noise (docs/restitution-law.md, "Where the pushes' low readings
come from").

`--resimulate TEST` runs one test of the campaign in `--out` again from the draws stored
in its truth.json `sim` block (the preset must be the one that made it) and writes the
engine's trajectory at every 0.1 ms step to `--trace`, on the log's time axis: time_s,
x_mm (sensor point, rest subtracted), v_mm_s, theta_rad. It checks that the peaks come
out as in truth.json. Compare it with the global fit's curve (`ENGINE_CURVE=DIR` in
`tests/truth.rs`'s `engine_campaigns`, docs/accuracy.md):

    python3 tools/mujoco_campaign.py --preset holdout-one-sided \
        --out fixtures/campaigns/mujoco-holdout-one-sided --resimulate H1_150_1 --trace /tmp/H1_150_1.txt

Truth: peaks[k] is the extreme of the sensor point's horizontal velocity within
half-cycle k (between zero crossings k-1 and k of theta), from the engine's state at
every 0.1 ms step; the table values are computed from those peaks (paper Eqs. 3-6).
The sensor reads the horizontal displacement of a point of the outward face at height L
(L sin theta plus the bedding's own small motion), plus Gaussian noise, a linear drift
and 0.01 mm quantisation, sampled at fs with a random phase. The truth, the tables, the logger and the files are
tools/campaign_common.py's, shared with tools/penalty_campaign.py (a second engine).
"""
import math

import mujoco
import numpy as np

from campaign_common import cli, stored_test, write_campaign, write_trace

PRESETS = {
    # A slenderer wall than the public campaigns, stiff bedding, lossy transverse walls.
    "holdout-one-sided": dict(
        rocking="one-sided", H=2.60, b=0.36, w=1.60, density=1900.0, L=2.50,
        bed_tc=(0.002, 0.005), bed_solimp=[0.05, 0.8, 0.0005, 0.5, 2.0],
        K_in=(1000.0, 3000.0), zeta_in=(0.03, 0.08),
        tests=[("H1_160_1", 160, 200), ("H1_160_2", 160, 500), ("H1_140_1", 140, 1000),
               ("H1_140_2", 140, 200), ("H1_130_1", 130, 500), ("H1_150_1", 150, 100)],
        seed=18_1,
    ),
    # A squatter wall on a soft bedding: long contacts that begin well before theta = 0.
    "holdout-two-sided": dict(
        rocking="two-sided", H=2.20, b=0.40, w=1.20, density=2000.0, L=2.10,
        bed_tc=(0.010, 0.025), bed_solimp=[0.1, 0.4, 0.001, 0.5, 2.0],
        tests=[("H2_110_1", 110, 200), ("H2_110_2", 110, 1000), ("H2_90_1", 90, 500),
               ("H2_80_1", 80, 100), ("H2_70_1", 70, 200)],
        seed=18_2,
    ),
    # The public campaigns' wall, bedding and transverse walls (their truth.json `sim`
    # blocks: H 3.00 m, b 0.40 m, LVDT at 2.90 m; one-sided bedding time constant
    # 2.9-3.3 ms, transverse walls K 1300-2400 s^-2; two-sided bedding 13.8-16.9 ms),
    # drawn anew with other tests: the closest stand-in for campaigns made like the
    # public ones that the estimator has never seen (session 14). The public blocks
    # state damping ratios 0.14-0.20 in MuJoCo's (timeconst, dampratio) form, but that
    # form with this geometry loses far more than the public tests do (P1_150_1
    # replayed: v1 252 mm/s at 0.07, public 442); the direct form with 0.05-0.09
    # gives the public's decay (P1_150_1 at 0.07: 428, -407, 282 against 442, -421,
    # 279; P1_90_1 at 0.084: 338, -315, 208 against 312, -292, 173).
    "public-like-one-sided": dict(
        rocking="one-sided", H=3.00, b=0.40, w=2.00, density=1961.4, L=2.90,
        bed_tc=(0.0028, 0.0034), bed_solimp=[0.05, 0.8, 0.0005, 0.5, 2.0],
        K_in=(1300.0, 2400.0), zeta_in=(0.05, 0.09),
        tests=[("Q1_170_1", 170, 200), ("Q1_160_1", 160, 500), ("Q1_150_1", 150, 1000),
               ("Q1_140_1", 140, 200), ("Q1_155_1", 155, 100)],
        seed=14_1,
    ),
    "public-like-two-sided": dict(
        rocking="two-sided", H=3.00, b=0.40, w=2.00, density=1998.5, L=2.90,
        bed_tc=(0.0135, 0.0170), bed_solimp=[0.1, 0.4, 0.001, 0.5, 2.0],
        tests=[("Q2_150_1", 150, 200), ("Q2_130_1", 130, 1000), ("Q2_110_1", 110, 100),
               ("Q2_90_1", 90, 500), ("Q2_70_1", 70, 200)],
        seed=14_2,
    ),
    # Generalisation checks of the per-impact readings (issue 20), never tuned on: a
    # slender tall wall on a medium bedding, two-sided, and a squat short wall with
    # soft, very lossy transverse walls, one-sided.
    "fresh-two-sided": dict(
        rocking="two-sided", H=3.40, b=0.30, w=1.40, density=1850.0, L=3.20,
        bed_tc=(0.004, 0.012), bed_solimp=[0.08, 0.6, 0.0008, 0.5, 2.0],
        tests=[("F2_180_1", 180, 200), ("F2_150_1", 150, 500), ("F2_120_1", 120, 1000),
               ("F2_100_1", 100, 100), ("F2_160_1", 160, 200)],
        seed=20_2,
    ),
    "fresh-one-sided": dict(
        rocking="one-sided", H=1.90, b=0.32, w=1.20, density=2050.0, L=1.80,
        bed_tc=(0.003, 0.010), bed_solimp=[0.06, 0.7, 0.0006, 0.5, 2.0],
        K_in=(500.0, 1500.0), zeta_in=(0.05, 0.12),
        tests=[("F1_190_1", 190, 200), ("F1_170_1", 170, 500), ("F1_160_1", 160, 1000),
               ("F1_180_1", 180, 100), ("F1_150_1", 150, 200)],
        seed=20_1,
    ),
    # A third one-sided wall between the other two, kept as a check that the estimator
    # was not tuned on (issue 18/20, session O1): medium slenderness, medium bedding,
    # transverse walls from stiff to soft.
    "check-one-sided": dict(
        rocking="one-sided", H=2.30, b=0.34, w=1.40, density=1950.0, L=2.20,
        bed_tc=(0.003, 0.008), bed_solimp=[0.06, 0.7, 0.0006, 0.5, 2.0],
        K_in=(600.0, 2500.0), zeta_in=(0.04, 0.10),
        tests=[("C1_170_1", 170, 200), ("C1_150_1", 150, 500), ("C1_140_1", 140, 1000),
               ("C1_160_1", 160, 100), ("C1_130_1", 130, 200)],
        seed=20_3,
    ),
}

DT = 1e-4


def build(p, rng):
    H, b, w = p["H"], p["b"], p["w"]
    tc = rng.uniform(*p["bed_tc"])
    mu = rng.uniform(0.8, 1.0)
    bed = " ".join(f"{v:g}" for v in p["bed_solimp"])
    obst = ""
    extra = {}
    if p["rocking"] == "one-sided":
        K = rng.uniform(*p["K_in"])
        zeta = rng.uniform(*p["zeta_in"])
        # Direct stiffness and damping of the constraint (MuJoCo's negative solref):
        # a_ref = -K r - 2 zeta sqrt(K) r', a linear spring-dashpot in the contact's
        # acceleration space (the public campaigns' (timeconst, dampratio) form made the
        # restraint's stiffness depend on zeta here).
        tco, dmp = -K, -2.0 * zeta * math.sqrt(K)
        extra = dict(obst_K_target_per_s2=K, obst_zeta=zeta, obst_solref=[tco, dmp])
        for s in (-1, 1):
            y = s * (w / 2 - 0.125)
            obst += (
                f'<geom type="box" size="0.5 0.125 {0.35 * H:g}" pos="{-b / 2 - 0.5:g} {y:g} {0.65 * H:g}" '
                f'condim="1" solref="{tco:g} {dmp:g}" solimp="0.9 0.95 0.001 0.5 2" contype="2" conaffinity="2" rgba="0.5 0.5 0.5 1"/>'
            )
    xml = f"""
<mujoco>
  <option timestep="{DT}" integrator="implicitfast" cone="elliptic" impratio="10" solver="Newton" iterations="100" tolerance="1e-10"/>
  <worldbody>
    <geom name="floor" type="plane" size="20 20 0.1" condim="3" friction="{mu:g} 0.005 0.0001"
          solref="{tc:g} 1" solimp="{bed}" contype="1" conaffinity="1"/>
    {obst}
    <body name="wall" pos="0 0 {H / 2:g}">
      <freejoint/>
      <geom type="box" size="{b / 2:g} {w / 2:g} {H / 2:g}" density="{p['density']:g}" contype="3" conaffinity="3"/>
      <site name="sensor" pos="{b / 2:g} 0 {p['L'] - H / 2:g}"/>
      <site name="top" pos="{b / 2:g} 0 {H / 2:g}"/>
    </body>
  </worldbody>
  <equality>
    <connect name="hold" body1="wall" anchor="{b / 2:g} 0 {H / 2:g}" active="true"/>
  </equality>
</mujoco>"""
    m = mujoco.MjModel.from_xml_string(xml)
    return m, dict(floor_solref=[tc, 1.0], friction_mu=mu, **extra)


def set_tilt(m, d, p, theta):
    """Pose of the wall rotated by theta about its outward toe (theta > 0 outward)."""
    H, b = p["H"], p["b"]
    c, s = math.cos(theta), math.sin(theta)
    # Rotation about +y by theta moves +z toward +x.
    toe = np.array([b / 2, 0.0, 0.0])
    centre0 = np.array([0.0, 0.0, H / 2])
    r = centre0 - toe
    centre = toe + np.array([c * r[0] + s * r[2], 0.0, -s * r[0] + c * r[2]])
    d.qpos[:3] = centre
    d.qpos[3:7] = [math.cos(theta / 2), 0.0, math.sin(theta / 2), 0.0]
    d.qvel[:] = 0.0
    mujoco.mj_forward(m, d)
    # The hold: anchor the top's outward corner where it is now.
    m.eq_data[0, 3:6] = d.site_xpos[1]


def theta_of(d):
    R = d.xmat[1].reshape(3, 3)
    return math.atan2(R[0, 2], R[2, 2])


def simulate(p, x0_mm, rng):
    m, sim = build(p, rng)
    d = mujoco.MjData(m)
    theta0 = math.asin(x0_mm / 1000.0 / p["L"])
    set_tilt(m, d, p, theta0)
    settle = 1.0
    t_rel = settle
    rec = []
    n_steps = int((settle + 30.0) / DT)
    sensor_id = 0
    released = False
    still = 0
    for i in range(n_steps):
        t = i * DT
        if not released and t >= t_rel:
            d.eq_active[0] = 0
            released = True
        mujoco.mj_step(m, d)
        th = theta_of(d)
        vel = np.zeros(6)
        mujoco.mj_objectVelocity(m, d, mujoco.mjtObj.mjOBJ_SITE, sensor_id, vel, 0)
        R = d.xmat[1].reshape(3, 3)
        z_toes = [d.xpos[1][2] + R[2, 0] * sx * p["b"] / 2 - R[2, 2] * p["H"] / 2 for sx in (1, -1)]
        rec.append((d.time, d.site_xpos[sensor_id][0], vel[3], th, max(z_toes)))
        if released and abs(th) < 2e-5 and abs(d.qvel[4]) < 2e-4:
            still += 1
            if still > 20000:
                break
        else:
            still = 0
    a = np.array(rec)
    return a, theta0, t_rel, sim


class Replay:
    """The stored draws of a test's `sim` block, handed out in the order `build` draws them."""

    def __init__(self, sim):
        self.values = [sim["floor_solref"][0], sim["friction_mu"]]
        if "obst_K_target_per_s2" in sim:
            self.values += [sim["obst_K_target_per_s2"], sim["obst_zeta"]]

    def uniform(self, a, b):
        return self.values.pop(0)


def resimulate(p, out, tid, trace):
    """Run test `tid` of the campaign in `out` again (module docs) and write its trajectory."""
    test = stored_test(out, tid)
    sim = test["sim"]
    a, _, t_rel, _ = simulate(p, sim["x0_mm_nominal"], Replay(sim))
    write_trace(a, t_rel, test, trace)


def make(p, out, how, rng):
    header = [f"# Hold-out campaign made with MuJoCo {mujoco.__version__} by tools/mujoco_campaign.py {how}",
              "# (rigid wall, compliant finite-duration contacts); truth in truth.json."]
    write_campaign(p, out, how, rng, simulate, dict(engine=f"MuJoCo {mujoco.__version__}", timestep_s=DT),
                   "tools/mujoco_campaign.py", header)


if __name__ == "__main__":
    cli(PRESETS, make, resimulate)
