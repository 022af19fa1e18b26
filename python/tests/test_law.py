"""Issue 20: the impacts table and the restitution law against the CLI's summary."""

import json

import rocklab
from conftest import TWO_SIDED, run_cli


def test_impacts_and_law_equal_cli(cli, tmp_path):
    run_cli(cli, "reduce", TWO_SIDED, "--out", tmp_path, "--no-plots")
    expected = json.loads((tmp_path / "summary.json").read_text())
    res = rocklab.reduce(TWO_SIDED)
    table = rocklab.impacts(res)
    want = [(t["id"], i["k"], i["r"]) for t in expected["tests"] for i in t["impacts"] if "r" in i]
    assert list(zip(table["test"], table["k"], table["r"])) == want
    assert set(table["side"]) == {"in", "out"}
    assert (table["r_u"] > 0).all()
    # impacts.csv beside the tables has the same rows.
    csv = rocklab.read_csv(tmp_path / "impacts.csv")
    assert len(csv) == len(table)
    law = rocklab.restitution_law(res)
    assert law == expected["restitution_law"]
    assert len(law["curve"]) >= 20
    # The idealised two-sided demo draws e independently of the amplitude.
    assert law["rejects_constant"] is False and law["form"] == "constant"
    # What the law vouches for: the constant, over the amplitudes it was fitted on.
    (note,) = law["notes"]
    assert note.startswith("side both: constant") and "not vouched for" in note
    assert law["fits"][0]["amplitude_min"] <= law["fits"][0]["amplitude_max"]
