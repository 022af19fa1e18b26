"""Issue 20: simulate with a restitution law, and the façade's ensembles and
fragility from Python, against the CLI."""

import json
import shutil

import numpy as np
import pandas as pd
import pytest

import rocklab
from conftest import BLOCK, FIXTURES, NRC_1030, STUDY, run_cli

LAW = FIXTURES / "facade" / "law.json"


def _constant_law(r_in, r_out):
    side = lambda r: {"r_inf": r, "c": 0.0, "cov": [[0.0, 0.0], [0.0, 0.0]]}
    return {
        "form": "constant",
        "parameters": {"in": side(r_in), "out": side(r_out), "shared": False, "amplitude_min": 1e-6, "amplitude_max": 1.0},
    }


def test_constant_law_is_the_pair_bit_for_bit():
    """A constant law (r_in, r_out) with e_H gives the history of the pair
    (r_in e_H, r_out e_H), bit for bit."""
    r_in, r_out, e_h = 0.61, 0.7, 0.98
    law = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=_constant_law(r_in, r_out), e_h=e_h)
    pair = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, e_in=r_in * e_h, e_out=r_out * e_h)
    assert law["impacts"] > 5
    for k in ("t_s", "theta_rad", "theta_dot_rad_s"):
        np.testing.assert_array_equal(law.history[k], pair.history[k])
    assert law["law"]["e_housner"] == e_h
    # A summary dict holding the law is accepted as well.
    wrapped = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law={"restitution_law": _constant_law(r_in, r_out)}, e_h=e_h, history=False)
    assert (wrapped["impacts"], wrapped["max_theta_over_alpha"]) == (law["impacts"], law["max_theta_over_alpha"])


def test_law_file_and_errors():
    res = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=LAW, history=False)
    alpha = res["alpha_rad"]
    assert res["law"]["e_housner"] == pytest.approx(1 - 1.5 * np.sin(alpha) ** 2, abs=1e-15)
    assert res["law"]["law"]["form"] == "speed-loss"
    with pytest.raises(rocklab.RocklabError, match="not several"):
        rocklab.simulate(BLOCK, NRC_1030, law=LAW, e=0.9)
    with pytest.raises(rocklab.RocklabError, match="e_h = 1.5"):
        rocklab.simulate(BLOCK, NRC_1030, law=LAW, e_h=1.5)
    with pytest.raises(rocklab.RocklabError, match="law"):
        rocklab.simulate(BLOCK, NRC_1030, law={"form": "speed-loss"})


def test_facade_ensembles_equal_cli(cli, tmp_path):
    """The ensembles and fragility fits equal the CLI's for the same seed, with a
    law set in the study (its parameters drawn in each sample)."""
    study_dir = tmp_path / "study"
    shutil.copytree(FIXTURES / "facade", study_dir)
    text = STUDY.read_text().replace("../ground-motions", str(FIXTURES / "ground-motions"))
    text += '\n[[coefficients]]\nname = "law"\nlaw = "law.json"\n'
    study = study_dir / "study.toml"
    study.write_text(text)
    out = tmp_path / "out"
    run_cli(cli, "facade", study, "--out", out, "--samples", "4", "--seed", "7", "--scales", "0.5:1.5:3", "--ida-samples", "2")
    expected = json.loads((out / "summary.json").read_text())
    res = rocklab.facade_ensembles(study, samples=4, seed=7, scales="0.5:1.5:3", ida_samples=2)
    assert res.doc["rows"] == expected["ensemble"]["rows"]
    assert [s["fit"] for s in res.doc["fragility"]["sets"]] == [s["fit"] for s in expected["fragility"]["sets"]]
    assert res.fragility_source == "ida"
    assert list(res.fragility["coefficients"]) == ["housner", "calibrated", "law"]
    # The law set's fragility says where its runs, every scale included, read the
    # law against its data, as the CLI's summary does; the pairs carry nothing.
    reach = [s.get("law_reach") for s in res.doc["fragility"]["sets"]]
    assert reach == [s.get("law_reach") for s in expected["fragility"]["sets"]]
    assert reach[0] is None and reach[1] is None and reach[2]["outward"]["impacts"] > 0
    beyond = list(res.fragility["beyond_the_data"])
    assert pd.isna(beyond[0]) and pd.isna(beyond[1]) and 0.0 <= beyond[2] <= 1.0
    assert len(res.rows) == 3 * 2 * 3 and len(res.samples) == 3 * 2 * 3 * 4
    law_samples = res.samples[res.samples["coefficients"] == "law"]
    assert law_samples["e_out"].nunique() > 1, "the law's parameters are drawn per sample"


def test_an_energy_term_of_zero_is_the_speed_loss_law_bit_for_bit():
    """Thirty-seventh session: a law whose sides carry the energy term
    (form "speed-and-energy-loss") runs from Python; with c2 = 0 and no spread it
    gives the speed-loss law's history bit for bit, and with c2 > 0 the history
    changes (the term is read, not dropped; its values are checked in Rust,
    tests/solver.rs)."""
    base = json.loads(LAW.read_text())

    def with_energy(c2):
        law = json.loads(json.dumps(base))
        law["form"] = "speed-and-energy-loss"
        for side in ("in", "out"):
            p = law["parameters"][side]
            c = p["cov"]
            p["energy"] = {
                "c2": c2,
                "cov": [[c[0][0], c[0][1], 0.0], [c[1][0], c[1][1], 0.0], [0.0, 0.0, 0.0]],
                "g_lo": 1.05,
                "g_hi": 30.0,
            }
        return law

    plain = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=base)
    zero = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=with_energy(0.0))
    assert plain["impacts"] > 5
    for k in ("t_s", "theta_rad", "theta_dot_rad_s"):
        np.testing.assert_array_equal(zero.history[k], plain.history[k])
    assert zero["law"]["law"]["form"] == "speed-and-energy-loss"
    lossy = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=with_energy(1e-3))
    assert not np.array_equal(lossy.history["theta_rad"], plain.history["theta_rad"])


def test_a_law_read_by_speed():
    """law_reading="speed": each impact reads the law at the amplitude of the
    campaign's impacts of its speed. A law whose outward side ends pushes needs
    the campaign's Ω/p (push_speed); the summary says how the law was read, and
    each impact event the amplitude it was read at: the apex's by amplitude, and
    with Ω/p = 10⁹ an outward impact's ŵ/10⁹ (below 1e-8 here), by speed."""
    law = json.loads(LAW.read_text())
    # Sides fitted apart, a free-arc outward curve and no Ω/p: whether its outward
    # impacts end pushes cannot be told, so it is not read by speed.
    with pytest.raises(rocklab.RocklabError, match="shared = false"):
        rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=law, law_reading="speed")
    law["parameters"]["out"]["g"] = "push"
    with pytest.raises(rocklab.RocklabError, match="push_speed"):
        rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=law, law_reading="speed")
    with pytest.raises(rocklab.RocklabError, match="expected"):
        rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=law, law_reading="sideways")
    with pytest.raises(rocklab.RocklabError, match="law_reading is for a law"):
        rocklab.simulate(BLOCK, NRC_1030, scale=1.27, e=0.9, law_reading="speed")
    law["parameters"]["push_speed"] = {"median": 1e9, "range": [1e9, 1e9], "impacts": 1}
    by_a = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=law, history=False)
    by_w = rocklab.simulate(BLOCK, NRC_1030, scale=1.27, law=law, law_reading="speed", history=False)
    assert (by_a["law"]["reading"], by_w["law"]["reading"]) == ("amplitude", "speed")
    impacts = lambda res, side: [e for e in res["events"] if e["kind"] == "impact" and e["entering"] == side]
    assert len(impacts(by_a, 1)) > 2 and len(impacts(by_w, 1)) > 2
    assert all(e["law_amplitude_over_alpha"] == e["amplitude_over_alpha"] for e in impacts(by_a, 1) + impacts(by_a, -1))
    outward = impacts(by_w, 1)
    assert all(e["law_amplitude_over_alpha"] < 1e-8 for e in outward)
    assert max(e["amplitude_over_alpha"] for e in outward) > 1e-6
