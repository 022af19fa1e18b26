"""Shared fixtures: the repository's fixture files and the CLI binary the Python
results are compared with."""

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FIXTURES = ROOT / "fixtures"
ONE_SIDED = FIXTURES / "campaigns" / "one-sided-demo" / "campaign.toml"
TWO_SIDED = FIXTURES / "campaigns" / "two-sided-demo" / "campaign.toml"
BLOCK = FIXTURES / "facade" / "block.toml"
STUDY = FIXTURES / "facade" / "study.toml"
ESM = FIXTURES / "ground-motions" / "esm-central-italy-2016"
NRC_1030 = ESM / "IT.NRC..HGE.D.20161030.064018.C.ACC.ASC"


@pytest.fixture(scope="session")
def cli():
    """Path of the `rocklab` binary: $ROCKLAB_BIN, else target/debug/rocklab
    (built here with `cargo build --bin rocklab` when missing)."""
    if os.environ.get("ROCKLAB_BIN"):
        return Path(os.environ["ROCKLAB_BIN"])
    target = Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    exe = target / "debug" / "rocklab"
    if not exe.exists():
        subprocess.run(["cargo", "build", "--quiet", "--bin", "rocklab"], cwd=ROOT, check=True)
    return exe


def run_cli(cli, *args, ok=True):
    """Run the CLI; returns the CompletedProcess (exit code checked when ok)."""
    p = subprocess.run([str(cli), *map(str, args)], capture_output=True, text=True, cwd=ROOT)
    if ok:
        assert p.returncode == 0, p.stderr
    return p
