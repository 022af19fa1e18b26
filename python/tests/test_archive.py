"""rocklab.archive: the tables of `rocklab archive add` as DataFrames (polars when
installed, else pandas through pyarrow), equal to the reductions' summary.json."""

import builtins
import json

import pytest

import rocklab
from conftest import ONE_SIDED, TWO_SIDED, run_cli


@pytest.fixture(scope="module")
def archive(cli, tmp_path_factory):
    tmp = tmp_path_factory.mktemp("archive")
    docs = []
    for name, manifest in [("one", ONE_SIDED), ("two", TWO_SIDED)]:
        run_cli(cli, "reduce", manifest, "--out", tmp / name, "--no-plots")
        docs.append(json.loads((tmp / name / "summary.json").read_text()))
    for _ in range(2):  # twice: the second add replaces the first's rows
        run_cli(cli, "archive", "add", tmp / "one", tmp / "two", "--to", tmp / "arc")
    return tmp / "arc", docs


def _rows(df):
    """A DataFrame (polars or pandas) as a list of dicts."""
    return df.to_dicts() if hasattr(df, "to_dicts") else df.to_dict("records")


def _check(tests, impacts, docs):
    rows = _rows(tests)
    assert len(rows) == 10
    assert len({(r["manifest_sha256"], r["test"]) for r in rows}) == 10
    for doc in docs:
        for t in doc["tests"]:
            (row,) = [r for r in rows if r["campaign"] == doc["campaign"] and r["test"] == t["id"]]
            assert row["manifest_sha256"] == doc["manifest_sha256"]
            for k in ["r", "r_plus", "r_minus", "r_plus_u", "r_minus_u", "e", "r1", "r2"]:
                assert row[k] == t[k], (t["id"], k)
    # Every impact of summary.json with a coefficient (side, e, r) is a row, value for value.
    listed = sorted(
        (doc["campaign"], t["id"], i["k"], i["side"], i["e"], i["r_u"])
        for doc in docs
        for t in doc["tests"]
        for i in t["impacts"]
        if "side" in i
    )
    got = sorted((r["campaign"], r["test"], r["k"], r["side"], r["e"], r["r_u"]) for r in _rows(impacts))
    assert len(listed) >= 50
    assert got == listed


def test_archive_tables_equal_summary(archive):
    path, docs = archive
    tests, impacts = rocklab.archive(path)
    _check(tests, impacts, docs)


def test_archive_with_pandas_when_polars_is_missing(archive, monkeypatch):
    pytest.importorskip("pandas")
    pytest.importorskip("pyarrow")
    real_import = builtins.__import__

    def no_polars(name, *args, **kwargs):
        if name == "polars" or name.startswith("polars."):
            raise ImportError("polars hidden by the test")
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_polars)
    path, docs = archive
    tests, impacts = rocklab.archive(path)
    assert type(tests).__module__.startswith("pandas")
    _check(tests, impacts, docs)


def test_archive_missing_is_an_error(tmp_path):
    with pytest.raises(rocklab.RocklabError, match="no archive here"):
        rocklab.archive(tmp_path / "nothing")
