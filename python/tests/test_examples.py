"""The README's Python snippet and the example notebook run as shown."""

import os
import re
import subprocess
import sys

import pytest

from conftest import ROOT


def test_readme_python_snippets_run(monkeypatch, capsys):
    """Both snippets of the README's Python section (the API, then Dask), as a user
    pastes them into a script run from the repository root."""
    text = (ROOT / "README.md").read_text()
    section = text[text.index("## Python") : text.index("\n## ", text.index("## Python") + 1)]
    snippets = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(snippets) == 2
    monkeypatch.chdir(ROOT)
    for i, snippet in enumerate(snippets):
        exec(compile(snippet, f"README.md (Python snippet {i + 1})", "exec"), {"__name__": "__main__"})
    printed = capsys.readouterr().out
    assert "150_1" in printed and "max θ/α" in printed
    assert "overturned" in printed and "max_theta_over_alpha" in printed


def test_example_notebook_runs_and_plots(tmp_path):
    pytest.importorskip("matplotlib")
    env = {**os.environ, "MPLBACKEND": "Agg"}
    p = subprocess.run(
        [sys.executable, "python/examples/notebook.py", "--out", str(tmp_path), "--runs", "12"],
        cwd=ROOT, capture_output=True, text=True, env=env,
    )
    assert p.returncode == 0, p.stderr
    for name in ["velocity_peaks.png", "facade_ensemble.png"]:
        png = tmp_path / name
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        assert png.stat().st_size > 20_000, name  # a drawn figure, not an empty canvas
    # The notebook's 150_1 is the campaign's 150_1: the same r⁺ as `reduce` gives.
    import rocklab

    want = rocklab.reduce(ROOT / "fixtures/campaigns/one-sided-demo/campaign.toml").test("150_1")["r_plus"]
    assert f"r+ = {want:.3f}" in p.stdout, p.stdout
