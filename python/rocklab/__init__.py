"""rocklab from Python: the CLI's commands as functions returning Python data.

Coefficients of restitution of rocking masonry walls from free-vibration tests and
a rocking solver (Giresini & Croce, COMPDYN 2021). Every function calls the same
Rust library code as the ``rocklab`` command line:

- :func:`reduce` (``rocklab reduce``), :func:`reduce_log` (one test given as arrays),
- :func:`simulate` (``rocklab simulate``), :func:`calibrate` (``rocklab calibrate``),
- :func:`archive` (the tables of ``rocklab archive``),
- :func:`facade` (``rocklab facade``), :func:`facade_ensembles` (its uncertainty
  ensembles and fragility curves) and :func:`facade_runs` (any selection of a
  study's runs; :mod:`rocklab.dask` spreads them over a Dask cluster).

Each result's ``summary`` is exactly the JSON document the CLI writes as
``summary.json`` (parsed with :mod:`json`), so every field the CLI gains appears
here too. Tables are pandas DataFrames when pandas is installed, else lists of
dicts; time series are NumPy float64 arrays.

Conventions (SPEC): rotation θ > 0 and displacement > 0 are OUTWARD (away from
the transverse walls); ratios are fractions (0.57), not percents.

Errors: bad input raises :class:`RocklabError` (a ``ValueError``) with the message
the CLI prints (file, line and column where they apply); a failure inside Rust is
raised the same way and never crashes the interpreter. The computations release
the GIL, so threads can run them side by side.
"""

from __future__ import annotations

import csv
import io
import json
import os
import re
from dataclasses import dataclass, field
from typing import Any, Iterable, Mapping, Optional, Sequence, Union

import numpy as np

from . import _rocklab
from ._rocklab import RocklabError

__version__ = _rocklab.__version__

__all__ = [
    "RocklabError",
    "GroundMotion",
    "ReduceResult",
    "SimulationResult",
    "CalibrationResult",
    "FacadeResult",
    "EnsembleResult",
    "reduce",
    "reduce_log",
    "impacts",
    "restitution_law",
    "simulate",
    "calibrate",
    "facade",
    "facade_runs",
    "facade_ensembles",
    "plan_facade",
    "study_info",
    "parse_scales",
    "read_csv",
    "archive",
]

PathLike = Union[str, "os.PathLike[str]"]

try:  # pandas is optional: plain lists of dicts without it
    import pandas as _pd
except ImportError:  # pragma: no cover - exercised only where pandas is missing
    _pd = None


def _frame(rows: list, columns: Optional[Sequence[str]] = None):
    """A DataFrame of `rows` (dicts) when pandas is installed, else the list."""
    if _pd is None:
        return rows
    return _pd.DataFrame(rows, columns=columns)


_NUMBER = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?|[+-]?(inf|NaN|nan)")


def read_csv(source, **kwargs):
    """``pandas.read_csv`` with exact (round-trip) float parsing on every pandas
    version (pandas < 3 needs ``float_precision="round_trip"`` for it)."""
    if int(_pd.__version__.split(".")[0]) < 3:
        kwargs.setdefault("float_precision", "round_trip")
    return _pd.read_csv(source, **kwargs)


def _read_csv(text: str):
    """A CSV table written by the CLI: a DataFrame (exact float parsing), or a list
    of dicts with floats where a cell is a number."""
    if _pd is not None:
        return read_csv(io.StringIO(text))
    rows = []
    for r in csv.DictReader(io.StringIO(text)):
        rows.append({k: (float(v) if _NUMBER.fullmatch(v) else (None if v == "" else v)) for k, v in r.items()})
    return rows


def _arrays(raw: Mapping[str, bytes]) -> dict:
    """{name: float64 bytes} from the extension as NumPy arrays (no copy)."""
    return {k: np.frombuffer(v, dtype="<f8") for k, v in raw.items()}


def _f64_bytes(name: str, a) -> bytes:
    arr = np.asarray(a)
    if arr.ndim != 1:
        raise RocklabError(f"{name}: expected a one-dimensional array, got shape {arr.shape}")
    try:
        arr = arr.astype("<f8", copy=False)
    except (TypeError, ValueError) as e:
        raise RocklabError(f"{name}: expected numbers ({e})") from None
    return np.ascontiguousarray(arr).tobytes()


def _floats(d):
    """Integers to floats in a user's table (TOML wants 3.0 where a float is read)."""
    if isinstance(d, Mapping):
        return {k: _floats(v) for k, v in d.items()}
    if isinstance(d, (list, tuple)):
        return [_floats(v) for v in d]
    if isinstance(d, (bool, np.bool_)):
        return bool(d)
    if isinstance(d, (int, np.integer)):
        return float(d)
    if isinstance(d, np.floating):
        return float(d)
    return d


def _scalar_columns(items: Iterable[Mapping[str, Any]], skip: Sequence[str] = ()) -> list:
    """Rows of the scalar fields of each item (lists and dicts left out)."""
    return [{k: v for k, v in it.items() if k not in skip and not isinstance(v, (list, dict))} for it in items]


# ---------------------------------------------------------------------------
# reduce


@dataclass
class ReduceResult:
    """A reduced campaign (``rocklab reduce``).

    Attributes:
        summary: the CLI's ``summary.json`` as a dict (SPEC's output contract).
        tests: one row per test: id, status, every coefficient and ratio (and any
            field the summary gains, e.g. uncertainties), error where it failed.
        peaks: one row per velocity peak: test, k, time_s, velocity_mm_s (and any
            field a peak gains in the summary).
        tables: ``table1``..``table3`` as the CLI writes them (``tableN.csv``).
        captions: the caption of each table.
        series: per test id, NumPy arrays ``t_s``, ``displacement_mm`` (zero at the
            final rest line), ``velocity_mm_s`` and the fitted curve ``fit_t_s``,
            ``fit_displacement_mm``, ``fit_velocity_mm_s`` (with ``series=True``,
            always for :func:`reduce_log`).
    """

    summary: dict
    tests: Any
    peaks: Any
    tables: dict
    captions: dict
    series: dict = field(default_factory=dict)

    @property
    def mean(self) -> Optional[dict]:
        """Campaign means (SPEC ``mean``), None when no test could be averaged."""
        return self.summary.get("mean")

    @property
    def left_out(self) -> list:
        """Tests the means leave out, with why: [{"id", "why"}]."""
        return self.summary.get("mean_left_out", [])

    @property
    def statuses(self) -> dict:
        """{test id: status} ("ok", "error", or any status the summary gains)."""
        return {t["id"]: t.get("status") for t in self.summary["tests"]}

    @property
    def failed(self) -> dict:
        """{test id: error message} of the tests that could not be reduced."""
        return {t["id"]: t["error"] for t in self.summary["tests"] if t.get("status") == "error"}

    def test(self, test_id: str) -> dict:
        """The summary entry of one test."""
        for t in self.summary["tests"]:
            if t["id"] == test_id:
                return t
        raise KeyError(test_id)

    def __getitem__(self, key):
        return self.summary[key]


def _reduce_result(doc: dict, raw: Mapping[str, bytes]) -> ReduceResult:
    summary = doc["summary"]
    tests = _frame(_scalar_columns(summary["tests"]))
    peak_rows = [{"test": t["id"], "k": k, **p} for t in summary["tests"] for k, p in enumerate(t.get("peaks", []))]
    # Every field a peak carries (time_s, velocity_mm_s, and any the summary gains).
    peaks = _frame(peak_rows, columns=None if peak_rows else ["test", "k", "time_s", "velocity_mm_s"])
    tables = {t["name"]: _read_csv(t["csv"]) for t in doc["tables"]}
    captions = {t["name"]: t["caption"] for t in doc["tables"]}
    series: dict = {}
    for name, arr in _arrays(raw).items():
        test_id, key = name.rsplit("/", 1)
        series.setdefault(test_id, {})[key] = arr
    return ReduceResult(summary, tests, peaks, tables, captions, series)


def reduce(manifest: PathLike, *, method: str = "segments", window: int = 11, order: int = 3, series: bool = False) -> ReduceResult:
    """Reduce a campaign, as ``rocklab reduce MANIFEST`` (no files written).

    Args:
        manifest: the campaign manifest (TOML, SPEC).
        method: ``"segments"`` (default, the impact-resolved fit) or ``"savgol"``.
        window, order: Savitzky–Golay window and order with ``method="savgol"``.
        series: also return each test's displacement, velocity and fitted curve.

    A test that cannot be reduced is listed with ``status == "error"`` (see
    :attr:`ReduceResult.failed`), as in the CLI; a bad manifest raises
    :class:`RocklabError`.
    """
    text, raw = _rocklab.reduce(os.fspath(manifest), method, window, order, series)
    return _reduce_result(json.loads(text), raw)


def impacts(result: ReduceResult):
    """Every impact of every reduced test with its coefficient (issue 20): one row per
    impact of the summary's ``tests[].impacts`` that carries ``r``, with columns
    ``test``, ``status`` and every field the impact has (``k``, ``side``,
    ``amplitude_over_alpha``, ``speed_before_mm_s``, ``speed_after_mm_s``, ``e``,
    ``e_u``, ``r``, ``r_u``, the time and signed speeds of the analysis, and on a
    one-sided wall's impacts kept out of the law ``not_in_law``, why). A DataFrame
    where pandas is installed, else a list of dicts."""
    rows = [
        {"test": t["id"], "status": t.get("status"), **i}
        for t in result.summary["tests"]
        for i in t.get("impacts", [])
        if "r" in i
    ]
    return _frame(rows)


def restitution_law(result: ReduceResult) -> dict:
    """The campaign's restitution law as the summary gives it (``restitution_law``:
    ``form``, ``parameters`` per side with their covariance, ``curve`` with ``r_in``,
    ``r_out`` and their u, the test against the constant); ``{"error": why}`` where
    no law could be fitted."""
    return result.summary["restitution_law"]


def reduce_log(
    t,
    x_mm,
    *,
    wall: Mapping[str, float],
    sensor_height_m: float,
    rocking: str = "one-sided",
    test_id: str = "log",
    outward_sign: int = 1,
    time_unit: str = "s",
    displacement_unit: str = "mm",
    exclude_from_mean: bool = False,
    campaign: str = "reduce_log",
    method: str = "segments",
    window: int = 11,
    order: int = 3,
) -> ReduceResult:
    """Reduce one test given as arrays (any reader: pandas, TDMS, MATLAB, ...).

    The same as :func:`reduce` on a one-test manifest whose log holds these two
    columns: ``wall`` is the manifest's ``[wall]`` table (``height_m``,
    ``thickness_m``, optional ``hinge_height_m``, ``alpha_rad``, ``e_housner``, ...),
    ``sensor_height_m`` the displacement sensor's height above the base,
    ``time_unit`` ``"s"`` or ``"ms"``, ``displacement_unit`` ``"mm"`` or ``"m"``,
    ``outward_sign`` -1 when a positive reading means inward.
    """
    manifest = {
        "campaign": {"name": campaign, "rocking": rocking},
        "wall": _floats(dict(wall)),
        "channels": {
            "time": {"column": "t", "unit": time_unit},
            "displacement": {"column": "x", "unit": displacement_unit, "height_m": float(sensor_height_m)},
            "outward_sign": int(outward_sign),
        },
        "test": [{"id": test_id, "file": f"<{test_id}: arrays>", "exclude_from_mean": bool(exclude_from_mean)}],
    }
    text, raw = _rocklab.reduce_log(json.dumps(manifest), _f64_bytes("t", t), _f64_bytes("x_mm", x_mm), method, window, order)
    return _reduce_result(json.loads(text), raw)


# ---------------------------------------------------------------------------
# simulate


@dataclass
class GroundMotion:
    """A ground-motion record given as an array: uniformly sampled acceleration
    from t = 0 with time step ``dt`` (s), in ``units`` ``"g"``, ``"m/s2"`` or ``"cm/s2"``."""

    acc: Any
    dt: float
    units: str


@dataclass
class SimulationResult:
    """A run of ``rocklab simulate``.

    Attributes:
        summary: the CLI's ``summary.json`` (max/min θ/α, overturning, impacts, PGA,
            PGV of the scaled input, the block's properties, every event).
        history: NumPy arrays ``t_s``, ``theta_rad``, ``theta_over_alpha``,
            ``theta_dot_rad_s``, ``ag_m_s2`` (the CLI's ``history.csv``); empty with
            ``history=False``.
    """

    summary: dict
    history: dict

    def history_frame(self):
        """The history as a DataFrame (the columns of ``history.csv``)."""
        if _pd is None:
            raise ImportError("history_frame needs pandas; use .history (NumPy arrays)")
        return _pd.DataFrame(self.history)

    def __getitem__(self, key):
        return self.summary[key]


def _block_args(block) -> tuple:
    if isinstance(block, (str, os.PathLike)):
        return os.fspath(block), None
    if isinstance(block, Mapping):
        tables = dict(block) if "block" in block else {"block": dict(block)}
        return None, json.dumps(_floats(tables))
    raise RocklabError("block: expected a BLOCK.toml path or a dict (the file's tables, or the [block] table alone)")


def _record_args(record) -> tuple:
    if isinstance(record, (str, os.PathLike)):
        return os.fspath(record), None, None, None
    if isinstance(record, Mapping):
        record = GroundMotion(record["acc"], record["dt"], record["units"])
    if isinstance(record, GroundMotion):
        return None, _f64_bytes("acc", record.acc), float(record.dt), record.units
    raise RocklabError("record: expected a path or a GroundMotion(acc, dt, units)")


def simulate(
    block,
    record,
    *,
    scale: float = 1.0,
    polarity: int = 1,
    e: Optional[float] = None,
    e_in: Optional[float] = None,
    e_out: Optional[float] = None,
    calibration: Optional[PathLike] = None,
    format: Optional[str] = None,
    dt: Optional[float] = None,
    units: Optional[str] = None,
    overturn_limit: Optional[float] = None,
    t_extra: float = 0.0,
    rtol: float = 1e-8,
    atol: float = 1e-10,
    history: bool = True,
    law: Union[None, PathLike, Mapping] = None,
    e_h: Optional[float] = None,
    law_reading: Optional[str] = None,
) -> SimulationResult:
    """Rocking response of a block to a record, as ``rocklab simulate``.

    Args:
        block: a BLOCK.toml path, or a dict with its tables (``{"block": {...},
            "restraint": {...}, "tie_rod": [...], "impact": {...}}``) or only the
            ``[block]`` table (``height_m``, ``thickness_m``, ``width_m``,
            ``unit_weight_kn_m3``, optional ``r_m``, ``alpha_rad``, ...).
        record: a record file (ESM, AT2, COSMOS, one or two columns; ``format``,
            ``dt``, ``units`` as the CLI's flags) or a :class:`GroundMotion`.
        scale, polarity: magnification and ±1.
        e or e_in/e_out or calibration: coefficients of restitution (default: the
            block's ``[impact]``).
        history: return the time history (False saves memory in large batches).
        law: a restitution law instead of e: a summary.json written by ``reduce``
            (its ``restitution_law``), a law file, or the law as a dict (``{"form",
            "parameters"}``, or a summary dict holding ``restitution_law``). At each
            impact e = min(1, r(side, a)·e_H), a the apex |θ|/α of the half-cycle
            that ends; ``summary["law"]`` holds it, and ``e_in``/``e_out`` are then
            the law's e at a = 1.
        e_h: the e_H a law's r is multiplied by (default: Eq. 2 with the block's α).
        law_reading: ``"amplitude"`` (default: the apex, as above) or ``"speed"``:
            each impact reads the law at the amplitude of the campaign's impacts of
            its dimensionless speed ŵ = |θ'|/(p α) (docs/facade.md, "Reading the
            law by the impact's speed"); ``summary["law"]["reading"]`` says which.
    """
    law_path, law_json = _law_args(law)
    block_path, block_json = _block_args(block)
    record_path, acc, rec_dt, rec_units = _record_args(record)
    text, raw = _rocklab.simulate(
        block_path=block_path,
        block_json=block_json,
        record_path=record_path,
        acc=acc,
        format=format,
        dt=rec_dt if rec_dt is not None else dt,
        units=rec_units if rec_units is not None else units,
        scale=float(scale),
        polarity=int(polarity),
        e=e,
        e_in=e_in,
        e_out=e_out,
        calibration=os.fspath(calibration) if calibration is not None else None,
        overturn_limit=overturn_limit,
        t_extra=float(t_extra),
        rtol=float(rtol),
        atol=float(atol),
        history=history,
        law_path=law_path,
        law_json=law_json,
        e_h=e_h,
        law_reading=law_reading,
    )
    return SimulationResult(json.loads(text), _arrays(raw) if history else {})


def _law_args(law) -> tuple:
    if law is None:
        return None, None
    if isinstance(law, (str, os.PathLike)):
        return os.fspath(law), None
    if isinstance(law, Mapping):
        law = law.get("restitution_law", law)
        return None, json.dumps(law)
    raise RocklabError("law: expected a summary.json or law file path, or the law as a dict")


# ---------------------------------------------------------------------------
# calibrate


@dataclass
class CalibrationResult:
    """``rocklab calibrate``: the reduction, and e_in/e_out fitted by replaying each
    test with the solver.

    Attributes:
        summary: the CLI's ``summary.json`` (the reduce summary with ``calibration``).
        calibration: ``summary["calibration"]``: means, joint fit, per-test fits.
        fits: one row per test fit (e_in, e_out, standard errors, RMS, ...).
        calibration_toml: the text of the CLI's ``calibration.toml``.
        reduction: the :class:`ReduceResult` it started from.
    """

    summary: dict
    calibration: dict
    fits: Any
    calibration_toml: str
    reduction: ReduceResult

    def __getitem__(self, key):
        return self.summary[key]


def calibrate(manifest: PathLike, *, impacts: int = 6) -> CalibrationResult:
    """Reduce a campaign and fit e_in/e_out, as ``rocklab calibrate MANIFEST``."""
    doc = json.loads(_rocklab.calibrate(os.fspath(manifest), impacts))
    red = _reduce_result(doc, {})
    cal = doc["summary"]["calibration"]
    return CalibrationResult(doc["summary"], cal, _frame(_scalar_columns(cal["tests"])), doc["calibration_toml"], red)


# ---------------------------------------------------------------------------
# façade studies


@dataclass
class FacadeResult:
    """``rocklab facade``: every record × coefficient set × polarity.

    Attributes:
        summary: the CLI's ``summary.json`` (settings and ``runs``).
        runs: one row per run (record, coefficients, polarity, scale, max/min θ/α,
            overturned, overturn_time_s, well_conditioned, ...).
        ida: with ``scales``, one row per (record, set, polarity, scale) of the
            incremental dynamic analysis (the CLI's ``ida.csv``), else None.
    """

    summary: dict
    runs: Any
    ida: Any = None

    def __getitem__(self, key):
        return self.summary[key]


def parse_scales(text: str) -> list:
    """Scale factors of ``--scales FROM:TO:N`` (inclusive)."""
    return _rocklab.parse_scales(text)


def _scales(scales) -> Optional[list]:
    if scales is None:
        return None
    if isinstance(scales, str):
        return parse_scales(scales)
    return [float(s) for s in scales]


def facade(study: PathLike, *, scales: Union[None, str, Sequence[float]] = None) -> FacadeResult:
    """Run a façade study, as ``rocklab facade STUDY [--scales FROM:TO:N]``.

    ``scales`` ("FROM:TO:N" or a list of factors) adds the incremental dynamic
    analysis.
    """
    doc = json.loads(_rocklab.facade(os.fspath(study), _scales(scales)))
    summary = doc["summary"]
    ida = _frame(doc["ida"]) if doc["ida"] is not None else None
    return FacadeResult(summary, _frame(_run_rows(summary["runs"])), ida)


@dataclass
class EnsembleResult:
    """The façade's ensembles and fragility, as ``rocklab facade`` computes them.

    Attributes:
        rows: one row per record × polarity row × coefficient set (samples,
            overturned, p_overturn with its 95 % Wilson interval, verdict, max θ/α
            median and 5–95 %, median overturning time): the CLI's ``ensemble.csv``.
        samples: one row per sample (its drawn inputs and outcome); for a law set
            ``e_in``/``e_out`` are the drawn law's e at a = 1.
        fragility: one row per set (``median``, ``beta`` and their intervals, or
            ``error`` when no fit is possible; for a law set ``beyond_the_data``,
            the largest share of one side's impact energy its runs met at
            amplitudes the campaign did not observe, the report's ‡ above 0.5,
            None for other sets; the counts in ``doc``'s ``law_reach``), or None
            when there is nothing to fit.
        fragility_source: "ida" (fitted to the IDA's samples) or "ensemble".
        doc: the whole document.
    """

    rows: Any
    samples: Any
    fragility: Any
    fragility_source: Optional[str]
    doc: dict


def facade_ensembles(
    study: PathLike,
    *,
    samples: Optional[int] = None,
    seed: Optional[int] = None,
    scales: Union[None, str, Sequence[float]] = None,
    ida_samples: Optional[int] = None,
) -> EnsembleResult:
    """The uncertainty ensembles and fragility curves of a façade study (what
    :func:`facade` leaves out), with the same numbers as the CLI for the same seed.

    ``samples``, ``seed`` and ``ida_samples`` override the study's; ``scales``
    ("FROM:TO:N" or factors) fits the fragility to an IDA with ``ida_samples``
    samples per point, else to the ensemble (two records or more). A coefficient
    set with a restitution law (``law = FILE`` in the study) draws its parameters
    from their covariance in each sample.
    """
    doc = json.loads(
        _rocklab.facade_ensembles(
            os.fspath(study),
            None if samples is None else int(samples),
            None if seed is None else int(seed),
            _scales(scales),
            None if ida_samples is None else int(ida_samples),
        )
    )
    frag = doc["fragility"]
    fits = None
    if frag is not None:
        fits = _frame([dict(coefficients=s["coefficients"], **s["fit"], beyond_the_data=s.get("beyond_the_data")) for s in frag["sets"]])
    return EnsembleResult(
        rows=_frame(_scalar_columns(doc["rows"])),
        samples=_frame(_scalar_columns(doc["samples"])),
        fragility=fits,
        fragility_source=None if frag is None else frag["source"],
        doc=doc,
    )


def _run_rows(runs: list) -> list:
    """Flat rows of study runs: ``sensitivity`` [loose, tight] as two columns."""
    rows = []
    for r in runs:
        row = dict(r)
        if isinstance(row.get("sensitivity"), list):
            loose, tight = row.pop("sensitivity")
            row["max_theta_over_alpha_loose"] = loose
            row["max_theta_over_alpha_tight"] = tight
        rows.append(row)
    return rows


def study_info(study: PathLike) -> dict:
    """Records, coefficient sets and polarities of a study file."""
    return json.loads(_rocklab.study_info(os.fspath(study)))


def plan_facade(study: PathLike, scales: Union[str, Sequence[float]] = (1.0,)) -> list:
    """Every run of a study at each scale: [(record, set, polarity, scale)], scales
    outermost, then records, sets and polarities in the study's order (the order
    of the CLI's IDA)."""
    info = study_info(study)
    return [
        (rec, s["name"], p, sc)
        for sc in _scales(scales)
        for rec in info["records"]
        for s in info["coefficient_sets"]
        for p in info["polarities"]
    ]


def facade_runs(
    study: PathLike,
    runs: Optional[Sequence[Sequence]] = None,
    *,
    scales: Union[str, Sequence[float]] = (1.0,),
    sensitivity: bool = True,
    parallel: bool = True,
):
    """Run selected runs of a façade study on this machine.

    Args:
        study: the study file.
        runs: [(record, set, polarity, scale)], default :func:`plan_facade` with ``scales``.
        sensitivity: True: each run as in the study's table (repeated at 100×
            looser and tighter tolerances for ``well_conditioned``); False: one
            integration, as an IDA point (max θ/α and overturned).
        parallel: spread the runs over this machine's cores (rayon); False runs
            them one after the other (what a Dask worker does).

    Returns a DataFrame (list of dicts without pandas), one row per run, in order.
    Every run is computed by the library's own study functions, so a run gives the
    same numbers here, in :func:`facade`, in the CLI and on any Dask worker.
    """
    if runs is None:
        runs = plan_facade(study, scales)
    payload = json.dumps([[str(r), str(s), int(p), float(sc)] for r, s, p, sc in runs])
    out = json.loads(_rocklab.facade_runs(os.fspath(study), payload, sensitivity, parallel))
    return _frame(_run_rows(out))


def archive(path: PathLike):
    """The tables of a lab archive (``rocklab archive add … --to PATH``) as
    ``(tests, impacts)`` DataFrames: polars when it is installed, else pandas (which
    reads Parquet through pyarrow). An interrupted ``archive add`` is finished or
    discarded first, as the CLI does. Columns: ``docs/archive.md``."""
    tests_path, impacts_path = _rocklab.archive_tables(os.fspath(path))
    try:
        import polars as pl
    except ImportError:
        pl = None
    if pl is not None:
        return pl.read_parquet(tests_path), pl.read_parquet(impacts_path)
    if _pd is None:
        raise RocklabError("rocklab.archive needs polars, or pandas with pyarrow: pip install polars")
    return _pd.read_parquet(tests_path), _pd.read_parquet(impacts_path)
