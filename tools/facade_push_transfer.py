#!/usr/bin/env python3
"""The façade study's sensitivity to how a one-sided wall's outward law is carried
from the test wall to the façade (docs/facade.md, "Where the laws reach beyond
their data"; not run by CI).

The outward side of a one-sided law has the push's shape, r = r∞ − c/a: an
impact that ends a push into the transverse walls, whose speed is ω⁻ = Ω a α
with Ω the push's angular frequency. The law's a therefore carries the test
wall's restraint: on a façade with a stiffer restraint the same dimensionless
impact speed ω⁻/(p α) is a smaller a. This script measures Ω/p on the campaign
(each outward impact's speed before over a α p, from impacts.csv) and on the
façade's nominal block (Ω² = k_θ/I₀ with k_θ = K'_c h³/3), and writes the law
with its outward side carried by that speed instead of by a:
c' = c/q, observed outward amplitudes /q, with q = (Ω/p)_façade/(Ω/p)_test,
beside a study that runs both laws. Then:

    cargo run --release -- demo
    python3 tools/facade_push_transfer.py --out /tmp/transfer
    target/release/rocklab facade /tmp/transfer/study.toml --out /tmp/transfer/out \
        --samples 200 --scales 0.2:2.0:10
"""

import argparse
import csv
import json
import math
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
G = 9.81


def test_wall_q(reduced: Path, manifest: Path):
    """Ω/p of the campaign's pushes: median over its outward impacts, with the range."""
    m = tomllib.loads(manifest.read_text())
    wall = m["wall"]
    alpha = math.atan(wall["thickness_m"] / wall["height_m"])
    r = 0.5 * math.hypot(wall["height_m"], wall["thickness_m"])
    p = math.sqrt(3 * G / (4 * r))
    lever = m["channels"]["displacement"]["height_m"] - wall.get("hinge_height_m", 0.0)
    qs = []
    with open(reduced / "impacts.csv") as f:
        for row in csv.DictReader(f):
            if row["side"] == "out":
                omega = float(row["speed_before_mm_s"]) / 1000.0 / lever
                qs.append(omega / (float(row["amplitude_over_alpha"]) * alpha) / p)
    qs.sort()
    return qs[len(qs) // 2], qs[0], qs[-1]


def facade_q(block: Path):
    """Ω/p of the façade's nominal block: rectangular I₀ = 4/3 m R², p² = 3g/(4R)."""
    b = tomllib.loads(block.read_text())
    blk, res = b["block"], b["restraint"]
    mass = blk["unit_weight_kn_m3"] * 1e3 / G * blk["height_m"] * blk["thickness_m"] * blk["width_m"]
    i0 = 4.0 / 3.0 * mass * blk["r_m"] ** 2
    k = res["unit_stiffness_mn_m2"] * 1e6 * res["contact_height_m"] ** 3 / 3.0
    return math.sqrt(k / i0) / math.sqrt(3 * G / (4 * blk["r_m"]))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reduced", default=str(ROOT / "reports/demo/mujoco-public-one-sided"))
    ap.add_argument("--manifest", default=str(ROOT / "fixtures/campaigns/mujoco-public-one-sided/campaign.toml"))
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    qt, lo, hi = test_wall_q(Path(a.reduced), Path(a.manifest))
    qf = facade_q(ROOT / "fixtures/facade/block.toml")
    q = qf / qt
    print(f"Ω/p of the campaign's pushes: median {qt:.1f} (range {lo:.1f}–{hi:.1f}); façade {qf:.1f}; q = {q:.2f}")
    law = json.loads((Path(a.reduced) / "summary.json").read_text())["restitution_law"]
    par = json.loads(json.dumps(law["parameters"]))
    side = par["out"]
    side["c"] /= q
    side["cov"][0][1] /= q
    side["cov"][1][0] /= q
    side["cov"][1][1] /= q * q
    lo_o, hi_o = par["observed"]["out"]
    par["observed"]["out"] = [lo_o / q, hi_o / q]
    par["amplitude_min"] = min(par["amplitude_min"], lo_o / q)
    (out / "speed-law.json").write_text(json.dumps({"restitution_law": {"form": law["form"], "parameters": par}}, indent=1))
    study = (ROOT / "fixtures/facade/study.toml").read_text()
    study = study.replace('block = "block.toml"', f'block = "{ROOT / "fixtures/facade/block.toml"}"')
    study = study.replace('file = "../ground-motions', f'file = "{ROOT / "fixtures/ground-motions"}')
    study = study[: study.index("[[coefficients]]")]
    study += f'[[coefficients]]\nname = "mujoco law"\nlaw = "{Path(a.reduced).resolve() / "summary.json"}"\n\n'
    study += f'[[coefficients]]\nname = "mujoco law, speed transfer"\nlaw = "{(out / "speed-law.json").resolve()}"\n'
    (out / "study.toml").write_text(study)
    print(f"wrote {out / 'speed-law.json'} and {out / 'study.toml'}")


if __name__ == "__main__":
    main()
