"""The Python snippets of README.md and docs/python.md, and the example notebook run as shown."""

import os
import re
import subprocess
import sys

import pytest

from conftest import ROOT


def python_snippets(path, heading=None):
    """The ```python blocks of a Markdown file, or of its section under `heading`."""
    text = (ROOT / path).read_text()
    if heading is not None:
        start = text.index(heading)
        end = text.find("\n## ", start + 1)
        text = text[start : end if end >= 0 else len(text)]
    return re.findall(r"```python\n(.*?)```", text, re.S)


def test_readme_python_snippets_run(monkeypatch, capsys):
    """The Python snippets of README.md and docs/python.md, and both of docs/python.md (the API, then Dask), as a
    user pastes them into a script run from the repository root."""
    readme = python_snippets("README.md", "## Python")
    docs = python_snippets("docs/python.md")
    assert len(readme) == 1 and len(docs) == 2
    monkeypatch.chdir(ROOT)
    for name, snippets in [("README.md", readme), ("docs/python.md", docs)]:
        for i, snippet in enumerate(snippets):
            code = compile(snippet, f"{name} (Python snippet {i + 1})", "exec")
            exec(code, {"__name__": "__main__"})
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
