# %% [markdown]
# # rocklab from Python: a log, its coefficients of restitution, a façade ensemble
#
# A notebook in the "percent" format (cells start with `# %%`: VS Code, Spyder and
# Jupytext open it as a notebook); `python python/examples/notebook.py` runs it
# whole and writes its figures to `python/examples/out/` (or `--out DIR`).
#
# Needs `pip install ./python pandas matplotlib`, run from the repository root
# (it reads the fixtures).

# %%
import argparse
import pathlib

import matplotlib

matplotlib.use("Agg")  # files only; drop this line in a notebook
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd

import rocklab

parser = argparse.ArgumentParser(description=__doc__)
parser.add_argument("--out", default="python/examples/out", help="folder for the figures")
parser.add_argument("--runs", type=int, default=200, help="size of the façade ensemble")
args, _ = parser.parse_known_args()
out = pathlib.Path(args.out)
out.mkdir(parents=True, exist_ok=True)
fixtures = pathlib.Path("fixtures")

# %% [markdown]
# ## 1. Read a log with pandas
# Any reader will do (Excel, TDMS, MATLAB files): rocklab only needs the time and
# the displacement as arrays. Here, a CSV export with `#` metadata lines.

# %%
log = pd.read_csv(fixtures / "campaigns/one-sided-demo/150_1.csv", comment="#")
print(log.head())

# %% [markdown]
# ## 2. Reduce it
# The wall is the manifest's `[wall]` table; the sensor sits 2.56 m above the base.

# %%
wall = {"height_m": 2.70, "thickness_m": 0.36, "width_m": 1.68, "hinge_height_m": 0.23}
res = rocklab.reduce_log(
    log["time_s"].to_numpy(),
    log["disp_mm"].to_numpy(),
    wall=wall,
    sensor_height_m=2.56,
    rocking="one-sided",
    test_id="150_1",
)
test = res.test("150_1")
print(f"α = {res['alpha_rad']:.4f} rad ({res['alpha_source']}), e_H = {res['e_housner']:.4f}")
print(f"r = {test['r']:.3f}, r+ = {test['r_plus']:.3f}, r- = {test['r_minus']:.3f}, r1 = {test['r1']:.3f}")
print(res.peaks)
print(res.tables["table1"])

# %% [markdown]
# ## 3. Plot the velocity and its peaks (paper Fig. 3/4)

# %%
s = res.series["150_1"]
t0, t1 = test["release_time_s"] - 0.2, test["peaks"][-1]["time_s"] + 0.6
shown = (s["t_s"] >= t0) & (s["t_s"] <= t1)
fit = (s["fit_t_s"] >= t0) & (s["fit_t_s"] <= t1)
fig, (ax_x, ax_v) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
ax_x.plot(s["t_s"][shown], s["displacement_mm"][shown], ".", ms=3, color="0.5", label="measured, 200 Hz (zero: final rest)")
ax_x.plot(s["fit_t_s"][fit], s["fit_displacement_mm"][fit], color="tab:red", lw=1, label="free-rocking fit")
ax_x.set_ylabel("displacement (mm)")
ax_x.legend(loc="upper right")
ax_v.plot(s["t_s"][shown], s["velocity_mm_s"][shown], ".", ms=3, color="0.5", label="velocity at each sample")
ax_v.plot(s["fit_t_s"][fit], s["fit_velocity_mm_s"][fit], color="tab:blue", lw=1, label="fit")
ax_v.plot(res.peaks["time_s"], res.peaks["velocity_mm_s"], "o", color="tab:red", label="peaks $v_k$")
for k, p in res.peaks.iterrows():
    ax_v.annotate(f"$v_{k}$", (p["time_s"], p["velocity_mm_s"]), textcoords="offset points", xytext=(4, 4))
ax_v.axhline(0, color="0.8", lw=0.8)
ax_v.set_xlabel("time (s)")
ax_v.set_ylabel("velocity (mm/s)")
ax_v.legend(loc="lower right")
fig.suptitle(f"Test 150_1: r⁺ = {test['r_plus']:.0%}, r⁻ = {test['r_minus']:.0%}, r = {test['r']:.0%}")
fig.tight_layout()
fig.savefig(out / "velocity_peaks.png", dpi=110)
print("wrote", out / "velocity_peaks.png")

# %% [markdown]
# ## 4. A small façade ensemble
# The paper's façade (`fixtures/facade/block.toml`) under the 30 Oct 2016 Norcia
# record ×1.27, polarity −1, with e_in and e_out drawn around the calibrated pair
# (0.59 / 0.68, standard deviation 0.03): how far does the wall rock, and how
# often does it overturn? (`rocklab.dask.simulate_many` runs the same list of
# calls on a Dask cluster.)

# %%
rng = np.random.default_rng(2021)
record = fixtures / "ground-motions/esm-central-italy-2016/IT.NRC..HGE.D.20161030.064018.C.ACC.ASC"
block = fixtures / "facade/block.toml"
draws = np.clip(rng.normal([0.59, 0.68], 0.03, size=(args.runs, 2)), 0.05, 1.0)
rows = []
for e_in, e_out in draws:
    run = rocklab.simulate(block, record, scale=1.27, polarity=-1, e_in=e_in, e_out=e_out, history=False)
    rows.append({"e_in": e_in, "e_out": e_out, **{k: run[k] for k in ["max_theta_over_alpha", "overturned", "impacts"]}})
ensemble = pd.DataFrame(rows)
print(ensemble.describe())
print(f"overturned in {int(ensemble['overturned'].sum())} of {len(ensemble)} runs")

# The mean pair's time history, for the figure.
mean_run = rocklab.simulate(block, record, scale=1.27, polarity=-1, e_in=0.59, e_out=0.68)
h = mean_run.history
fig, (ax_h, ax_d) = plt.subplots(1, 2, figsize=(12, 4), gridspec_kw={"width_ratios": [2, 1]})
ax_h.plot(h["t_s"], h["theta_over_alpha"], color="tab:red", lw=0.8)
ax_h.set_xlabel("time (s)")
ax_h.set_ylabel("θ/α")
ax_h.set_title("e_in 0.59, e_out 0.68: θ/α under 20161030_NRC ×1.27, polarity −1")
ax_h.set_xlim(0, 30)
stands = ensemble[~ensemble["overturned"]]
pts = ax_d.scatter(stands["e_out"], stands["max_theta_over_alpha"], c=stands["e_in"], cmap="viridis", s=12, label="stands")
fell = ensemble[ensemble["overturned"]]
ax_d.scatter(fell["e_out"], np.ones(len(fell)), s=30, marker="x", color="tab:red", label="overturns (θ/α = 1)")
fig.colorbar(pts, ax=ax_d, label="e_in")
ax_d.set_xlabel("e_out")
ax_d.set_ylabel("max θ/α")
ax_d.set_title(f"{len(ensemble)} draws of (e_in, e_out)")
ax_d.legend()
fig.tight_layout()
fig.savefig(out / "facade_ensemble.png", dpi=110)
print("wrote", out / "facade_ensemble.png")

# %% [markdown]
# ## 5. The paper's façade study (`rocklab facade`)

# %%
study = rocklab.facade(fixtures / "facade/study.toml")
print(study.runs[["record", "coefficients", "polarity", "max_theta_over_alpha", "overturned", "overturn_time_s", "well_conditioned"]])
