//! `rocklab._rocklab`: the Python extension of rocklab (PyO3).
//!
//! A thin layer over the library: every function calls the same library code as
//! the CLI and returns the CLI's JSON document as text (the Python package parses
//! it into dicts and DataFrames) and time series as little-endian f64 bytes (the
//! package wraps them in NumPy arrays without a copy). Errors are raised as
//! `rocklab.RocklabError` (a `ValueError`) with the message the CLI prints; a Rust
//! panic is caught and raised the same way, never crashing the interpreter. Every
//! computation runs with the GIL released.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{anyhow, bail, Context};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};
use rayon::prelude::*;
use serde_json::{json, Value};

use rocklab::facade::{fragility_by_set, run_ensembles, run_ida, run_ida_samples, run_study, Study};
use rocklab::ground_motion::{Format, ReadOptions, Record, Units};
use rocklab::ingest::block::BlockSpec;
use rocklab::ingest::{Campaign, LogData};
use rocklab::peaks::{Method, PeakOptions};
use rocklab::reduce::{campaign_result, reduce_campaign, reduce_loaded, CampaignResult};
use rocklab::report::{docs, summary::summary, tables};
use rocklab::restitution_law::{LawReading, RestitutionLaw};
use rocklab::signal::savgol::SavGol;
use rocklab::solver::block::ImpactDefaults;
use rocklab::study::{run, RunSpec};
use rocklab::wall::Side;

pyo3::create_exception!(
    _rocklab,
    RocklabError,
    pyo3::exceptions::PyValueError,
    "Bad input or a failed computation; the message is the one the rocklab CLI prints (file, line, column where it applies)."
);

/// Named f64 series returned to Python as bytes.
type Series = Vec<(String, Vec<f64>)>;

/// Run `f` with the GIL released; an error becomes `RocklabError` with the CLI's
/// message (`{e:#}`: the context chain), a panic becomes `RocklabError` too.
fn guarded<T: Send>(py: Python<'_>, f: impl FnOnce() -> anyhow::Result<T> + Send) -> PyResult<T> {
    match py.detach(move || catch_unwind(AssertUnwindSafe(f))) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(e)) => Err(RocklabError::new_err(format!("{e:#}"))),
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_else(|| "unknown panic".into());
            Err(RocklabError::new_err(format!("internal error in rocklab (please report it): {what}")))
        }
    }
}

/// (JSON text, {name: f64 little-endian bytes}) for Python.
fn to_python<'py>(py: Python<'py>, doc: Value, series: Series) -> PyResult<(String, Bound<'py, PyDict>)> {
    let d = PyDict::new(py);
    for (name, v) in series {
        let bytes: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        d.set_item(name, PyBytes::new(py, &bytes))?;
    }
    Ok((doc.to_string(), d))
}

/// f64 values from little-endian bytes (the package sends `ndarray.tobytes()`).
fn f64s(name: &str, b: &[u8]) -> anyhow::Result<Vec<f64>> {
    if !b.len().is_multiple_of(8) {
        bail!("{name}: {} bytes is not a whole number of float64 values", b.len());
    }
    Ok(b.chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))).collect())
}

/// Every value finite, or the first that is not, by name and index.
fn finite(name: &str, v: &[f64]) -> anyhow::Result<()> {
    match v.iter().position(|x| !x.is_finite()) {
        Some(i) => bail!("{name}[{i}] = {}: expected finite numbers", v[i]),
        None => Ok(()),
    }
}

/// The estimator settings, as `rocklab reduce --method --window --order`.
fn peak_options(method: &str, window: usize, order: usize) -> anyhow::Result<PeakOptions> {
    let method = match method {
        "segments" => Method::Segments,
        "savgol" => Method::SavGol(SavGol::new(window, order).map_err(anyhow::Error::msg)?),
        other => bail!("method = {other:?}: expected \"segments\" or \"savgol\""),
    };
    Ok(PeakOptions {
        method,
        ..PeakOptions::default()
    })
}

/// The reduce result for Python: `summary` (exactly the CLI's summary.json),
/// `tables` (name, caption, the CLI's CSV text), and per-test series.
fn reduce_doc(res: &CampaignResult, with_series: bool) -> anyhow::Result<(Value, Series)> {
    let tabs = tables::tables(res)
        .iter()
        .map(|t| {
            let csv = String::from_utf8(tables::to_csv(t)?)?;
            Ok(json!({"name": t.name, "caption": t.caption, "csv": csv}))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let mut series = Series::new();
    if with_series {
        for t in &res.tests {
            if let Ok(r) = &t.result {
                let a = &r.analysis;
                let id = &t.spec.id;
                series.push((format!("{id}/t_s"), r.log.time_s.clone()));
                series.push((format!("{id}/displacement_mm"), a.displacement_mm.clone()));
                series.push((format!("{id}/velocity_mm_s"), a.velocity_mm_s.clone()));
                series.push((format!("{id}/fit_t_s"), a.fit_curve.iter().map(|p| p.0).collect()));
                series.push((format!("{id}/fit_displacement_mm"), a.fit_curve.iter().map(|p| p.1).collect()));
                series.push((format!("{id}/fit_velocity_mm_s"), a.fit_curve.iter().map(|p| p.2).collect()));
            }
        }
    }
    Ok((json!({"summary": summary(res)?, "tables": tabs}), series))
}

/// `rocklab reduce MANIFEST` without writing files.
#[pyfunction]
#[pyo3(signature = (manifest, method="segments", window=11, order=3, series=false))]
fn reduce<'py>(
    py: Python<'py>,
    manifest: PathBuf,
    method: &str,
    window: usize,
    order: usize,
    series: bool,
) -> PyResult<(String, Bound<'py, PyDict>)> {
    let method = method.to_string();
    let (doc, s) = guarded(py, move || {
        let opts = peak_options(&method, window, order)?;
        let campaign = Campaign::load(&manifest)?;
        reduce_doc(&reduce_campaign(campaign, opts), series)
    })?;
    to_python(py, doc, s)
}

/// One test given as arrays: `manifest_json` is a campaign manifest (SPEC) as JSON
/// with one `[[test]]`; `t` and `x` are the log's time and displacement columns in
/// the units of its channels.
#[pyfunction]
#[pyo3(signature = (manifest_json, t, x, method="segments", window=11, order=3))]
fn reduce_log<'py>(
    py: Python<'py>,
    manifest_json: &str,
    t: &[u8],
    x: &[u8],
    method: &str,
    window: usize,
    order: usize,
) -> PyResult<(String, Bound<'py, PyDict>)> {
    let (manifest_json, t, x, method) = (manifest_json.to_string(), t.to_vec(), x.to_vec(), method.to_string());
    let (doc, s) = guarded(py, move || {
        let opts = peak_options(&method, window, order)?;
        let value: Value = serde_json::from_str(&manifest_json)?;
        let text = toml::to_string(&value).context("the manifest as TOML")?;
        let campaign = Campaign::parse(&text, Path::new("<reduce_log>"))?;
        let spec = campaign.tests.first().ok_or_else(|| anyhow!("no test"))?.clone();
        let (t, x) = (f64s("t", &t)?, f64s("x", &x)?);
        if t.len() != x.len() {
            bail!("t has {} values and x {}: expected one displacement per time", t.len(), x.len());
        }
        finite("t", &t)?;
        finite("x", &x)?;
        if let Some(i) = t.windows(2).position(|w| w[1] <= w[0]) {
            bail!("t[{}] = {} after t[{i}] = {}: expected strictly increasing time", i + 1, t[i + 1], t[i]);
        }
        let (to_s, to_mm) = (spec.time.unit.to_s(), spec.displacement.unit.to_mm() * spec.outward_sign);
        let log = LogData {
            time_s: t.iter().map(|v| v * to_s).collect(),
            disp_mm: x.iter().map(|v| v * to_mm).collect(),
            notes: vec!["arrays passed from Python".into()],
            warnings: Vec::new(),
        };
        let outcome = reduce_loaded(&campaign, &spec, log, &opts);
        reduce_doc(&campaign_result(campaign, opts, vec![outcome]), true)
    })?;
    to_python(py, doc, s)
}

/// A block: a BLOCK.toml path, or the same tables as JSON (validated alike).
fn load_block(path: Option<PathBuf>, json_text: Option<String>) -> anyhow::Result<BlockSpec> {
    match (path, json_text) {
        (Some(p), None) => Ok(BlockSpec::load(&p)?),
        (None, Some(j)) => {
            let v: Value = serde_json::from_str(&j)?;
            Ok(BlockSpec::parse(
                &toml::to_string(&v).context("the block as TOML")?,
                Path::new("<block>"),
            )?)
        }
        _ => bail!("give the block as a path or as a dict"),
    }
}

/// A record: a file (any format the CLI reads), or an acceleration array with dt
/// and units.
fn load_record(
    path: Option<PathBuf>,
    acc: Option<Vec<u8>>,
    format: Option<String>,
    dt: Option<f64>,
    units: Option<String>,
) -> anyhow::Result<(String, Record)> {
    let units = units
        .as_deref()
        .map(|u| Units::parse(u).ok_or_else(|| anyhow!("units = {u:?}: expected g, m/s2 or cm/s2")))
        .transpose()?;
    match (path, acc) {
        (Some(p), None) => {
            let format = Format::from_name(format.as_deref().unwrap_or("auto"))?;
            let rec = rocklab::ingest::record::read(&p, &ReadOptions { format, dt, units })?;
            Ok((p.display().to_string(), rec))
        }
        (None, Some(bytes)) => {
            let acc = f64s("acceleration", &bytes)?;
            finite("acceleration", &acc)?;
            if acc.len() < 2 {
                bail!("the acceleration array has {} values: expected at least 2", acc.len());
            }
            let dt = dt.ok_or_else(|| anyhow!("dt is missing: an acceleration array needs its time step (s)"))?;
            if !(dt.is_finite() && dt > 0.0) {
                bail!("dt = {dt}: expected a positive time step (s)");
            }
            let units = units.ok_or_else(|| anyhow!("units is missing: an acceleration array needs units g, m/s2 or cm/s2"))?;
            let k = units.to_m_s2();
            let rec = Record {
                path: PathBuf::from("<array>"),
                format: Format::OneColumn,
                units,
                t0: 0.0,
                dt,
                acc_m_s2: acc.iter().map(|a| a * k).collect(),
                notes: Vec::new(),
            };
            Ok(("<array>".into(), rec))
        }
        _ => bail!("give the record as a path or as an acceleration array"),
    }
}

fn check_e(name: &str, e: f64) -> anyhow::Result<f64> {
    if e > 0.0 && e <= 1.0 {
        Ok(e)
    } else {
        bail!("{name} = {e}: expected 0 < e ≤ 1")
    }
}

/// `rocklab simulate` without writing files: (summary.json, history).
#[pyfunction]
#[pyo3(signature = (block_path=None, block_json=None, record_path=None, acc=None, format=None, dt=None, units=None,
                    scale=1.0, polarity=1, e=None, e_in=None, e_out=None, calibration=None, overturn_limit=None,
                    t_extra=0.0, rtol=1e-8, atol=1e-10, history=true, law_path=None, law_json=None, e_h=None,
                    law_reading=None))]
#[allow(clippy::too_many_arguments)]
fn simulate<'py>(
    py: Python<'py>,
    block_path: Option<PathBuf>,
    block_json: Option<String>,
    record_path: Option<PathBuf>,
    acc: Option<&[u8]>,
    format: Option<String>,
    dt: Option<f64>,
    units: Option<String>,
    scale: f64,
    polarity: i32,
    e: Option<f64>,
    e_in: Option<f64>,
    e_out: Option<f64>,
    calibration: Option<PathBuf>,
    overturn_limit: Option<f64>,
    t_extra: f64,
    rtol: f64,
    atol: f64,
    history: bool,
    law_path: Option<PathBuf>,
    law_json: Option<String>,
    e_h: Option<f64>,
    law_reading: Option<String>,
) -> PyResult<(String, Bound<'py, PyDict>)> {
    let acc = acc.map(|a| a.to_vec());
    let (doc, s) = guarded(py, move || {
        let block = load_block(block_path, block_json)?;
        let (record_name, record) = load_record(record_path, acc, format, dt, units)?;
        let d = block.impact;
        let law = load_law(law_path, law_json, e_h, block.block.alpha)?;
        let law_reading = law_reading_of(law_reading.as_deref(), law.as_ref().map(|l| &l.0))?;
        if law.is_some() && (calibration.is_some() || e.is_some() || e_in.is_some() || e_out.is_some()) {
            bail!("give a law, or e, or e_in with e_out, or calibration: not several");
        }
        let (e_in, e_out) = match (law, calibration, e, e_in, e_out) {
            (Some((l, e_h)), ..) => (l.e(Side::Inward, 1.0, e_h), l.e(Side::Outward, 1.0, e_h)),
            (None, calibration, e, e_in, e_out) => simulate_pair(&d, calibration, e, e_in, e_out)?,
        };
        let (e_in, e_out) = (check_e("e_in", e_in)?, check_e("e_out", e_out)?);
        let spec = RunSpec {
            e_in,
            e_out,
            law,
            law_reading,
            scale,
            polarity: polarity as f64,
            overturn_limit: overturn_limit.or(d.overturn_limit_rad).unwrap_or(block.block.alpha),
            t_extra,
            rtol,
            atol,
            keep_history: history,
        };
        spec.check(|k| k.to_string()).map_err(anyhow::Error::msg)?;
        let (summary, sim) = run(&block, &record, &spec)?;
        let mut doc = docs::simulate_summary(&block, &record_name, &record, &spec, &summary, &sim)?;
        if let Some((l, e_h)) = law {
            // e_in and e_out of the document are then the law's e at a = 1.
            doc["law"] = json!({"law": l, "e_housner": e_h, "reading": law_reading.as_str()});
        }
        let alpha = block.block.alpha;
        let h = &sim.history;
        let series: Series = vec![
            ("t_s".into(), h.iter().map(|s| s.t).collect()),
            ("theta_rad".into(), h.iter().map(|s| s.theta).collect()),
            ("theta_over_alpha".into(), h.iter().map(|s| s.theta / alpha).collect()),
            ("theta_dot_rad_s".into(), h.iter().map(|s| s.omega).collect()),
            ("ag_m_s2".into(), h.iter().map(|s| s.ag).collect()),
        ];
        Ok((doc, series))
    })?;
    to_python(py, doc, s)
}

/// A restitution law for `simulate`: a law file (summary.json or the law alone) or
/// the law's JSON, with e_H as given or by Eq. 2 with the block's α.
fn load_law(path: Option<PathBuf>, json_text: Option<String>, e_h: Option<f64>, alpha: f64) -> anyhow::Result<Option<(RestitutionLaw, f64)>> {
    let law = match (path, json_text) {
        (Some(p), None) => rocklab::ingest::law::read(&p)?,
        (None, Some(t)) => serde_json::from_str::<RestitutionLaw>(&t).context("law")?,
        (None, None) => {
            if let Some(e) = e_h {
                bail!("e_h = {e}: e_h is for a law");
            }
            return Ok(None);
        }
        (Some(_), Some(_)) => bail!("give the law as a file or as a dict, not both"),
    };
    let e_h = match e_h {
        Some(e) if e > 0.0 && e <= 1.0 => e,
        Some(e) => bail!("e_h = {e}: expected 0 < e_H ≤ 1"),
        None => rocklab::wall::housner_e(alpha),
    };
    Ok(Some((law, e_h)))
}

/// Where `simulate` reads a law: "amplitude" (default) or "speed" (a law whose
/// outward side ends pushes needs the campaign's Ω/p for it).
fn law_reading_of(reading: Option<&str>, law: Option<&RestitutionLaw>) -> anyhow::Result<LawReading> {
    let r = match reading.map(|r| (r, LawReading::parse(r))) {
        None => LawReading::Amplitude,
        Some((_, Some(r))) => r,
        Some((o, None)) => bail!("law_reading = {o:?}: expected \"amplitude\" or \"speed\""),
    };
    match law {
        None if reading.is_some() => bail!("law_reading is for a law"),
        Some(l) if r == LawReading::Speed => l
            .readable_by_speed()
            .map_err(|why| anyhow::anyhow!("law_reading = \"speed\": the law: {why}"))?,
        _ => {}
    }
    Ok(r)
}

/// The constant pair of `simulate`: a calibration, e, e_in with e_out, or the
/// block's `[impact]`.
fn simulate_pair(
    d: &ImpactDefaults,
    calibration: Option<PathBuf>,
    e: Option<f64>,
    e_in: Option<f64>,
    e_out: Option<f64>,
) -> anyhow::Result<(f64, f64)> {
    Ok(match (calibration, e, e_in, e_out) {
        (Some(file), None, None, None) => rocklab::ingest::calibration::read_coefficients(&file)?,
        (Some(_), ..) => bail!("give calibration, or e, or e_in with e_out: not several"),
        (None, Some(e), None, None) => (e, e),
        (None, None, Some(i), Some(o)) => (i, o),
        (None, None, None, None) => match (d.e, d.e_in, d.e_out) {
            (Some(e), _, _) => (e, e),
            (None, Some(i), Some(o)) => (i, o),
            _ => bail!("no coefficient of restitution: pass e=E, e_in=X with e_out=Y or calibration=FILE (or set [impact] in the block)"),
        },
        _ => bail!("pass e=E, or both e_in and e_out"),
    })
}

/// `rocklab calibrate MANIFEST` without writing files: the summary.json it writes
/// (the reduce summary with `"calibration"`), the tables and calibration.toml.
#[pyfunction]
#[pyo3(signature = (manifest, impacts=6))]
fn calibrate(py: Python<'_>, manifest: PathBuf, impacts: usize) -> PyResult<String> {
    let doc = guarded(py, move || {
        rocklab::limits::CALIBRATION_IMPACTS
            .check("impacts", impacts as f64)
            .map_err(anyhow::Error::msg)?;
        let campaign = Campaign::load(&manifest)?;
        let res = reduce_campaign(campaign, PeakOptions::default());
        let start = Instant::now();
        let (cal, law) = rocklab::law_replay::calibrate_with_law(&res.calibration_input(), impacts);
        let wall = start.elapsed().as_secs_f64();
        let (mut doc, _) = reduce_doc(&res, false)?;
        doc["summary"]["calibration"] = docs::calibration_summary(&cal, Some(&law), wall)?;
        docs::gather_timing(&mut doc["summary"]);
        doc["calibration_toml"] = json!(rocklab::calibrate::to_toml(&cal)?);
        Ok(doc)
    })?;
    Ok(doc.to_string())
}

/// `rocklab facade STUDY [--scales]` without writing files: the summary.json it
/// writes, and the IDA points (ida.csv) when scales are given.
#[pyfunction]
#[pyo3(signature = (study, scales=None))]
fn facade(py: Python<'_>, study: PathBuf, scales: Option<Vec<f64>>) -> PyResult<String> {
    let doc = guarded(py, move || {
        let study = Study::load(&study)?;
        if let Some(sc) = &scales {
            rocklab::facade::check_scale_list(sc).map_err(anyhow::Error::msg)?;
        }
        let start = Instant::now();
        let runs = run_study(&study, 1.0, false, &|| {})?;
        let wall = start.elapsed().as_secs_f64();
        let ida = scales.map(|sc| run_ida(&study, &sc, &|| {})).transpose()?;
        Ok(json!({"summary": docs::facade_summary(&study, &runs, wall, None, None)?, "ida": ida}))
    })?;
    Ok(doc.to_string())
}

/// The fragility fits of `runs` as summary.json writes them, each law set's with
/// `beyond_the_data`, the share behind the report's ‡ (`LawReach::beyond_share`).
fn fragility_sets(study: &Study, runs: &[rocklab::facade::SampleRun]) -> Vec<serde_json::Value> {
    fragility_by_set(study, runs)
        .into_iter()
        .map(|f| {
            let beyond = f.law_reach.map(|x| x.beyond_share());
            let mut v = json!(f);
            if let (Some(b), Some(o)) = (beyond, v.as_object_mut()) {
                o.insert("beyond_the_data".into(), json!(b));
            }
            v
        })
        .collect()
}

/// The façade's ensembles and fragility, as `rocklab facade` computes them
/// (without the nominal runs): the ensemble rows and samples at scale 1 (when the
/// study has samples), and a lognormal fragility per set fitted to the IDA's
/// samples (with `scales`) or to the ensemble's (≥ 2 records), as the CLI does.
/// `samples`, `seed` and `ida_samples` override the study's.
#[pyfunction]
#[pyo3(signature = (study, samples=None, seed=None, scales=None, ida_samples=None))]
fn facade_ensembles(
    py: Python<'_>,
    study: PathBuf,
    samples: Option<usize>,
    seed: Option<u64>,
    scales: Option<Vec<f64>>,
    ida_samples: Option<usize>,
) -> PyResult<String> {
    let doc = guarded(py, move || {
        let mut study = Study::load(&study)?;
        study.samples = samples.unwrap_or(study.samples);
        study.seed = seed.unwrap_or(study.seed);
        study.ida_samples = ida_samples.unwrap_or(study.ida_samples).max(1);
        rocklab::facade::check_samples("samples", study.samples).map_err(anyhow::Error::msg)?;
        rocklab::facade::check_samples("ida_samples", study.ida_samples).map_err(anyhow::Error::msg)?;
        if let Some(sc) = &scales {
            rocklab::facade::check_scale_list(sc).map_err(anyhow::Error::msg)?;
        }
        let (rows, ens) = if study.samples > 0 {
            run_ensembles(&study, study.samples, &|| {})?
        } else {
            (Vec::new(), Vec::new())
        };
        let fragility = match &scales {
            Some(sc) => {
                let ida = run_ida_samples(&study, sc, study.ida_samples, &|| {})?;
                Some(json!({"source": "ida", "scales": sc, "sets": fragility_sets(&study, &ida), "samples": ida}))
            }
            None if !ens.is_empty() && study.records.len() >= 2 => Some(json!({"source": "ensemble", "sets": fragility_sets(&study, &ens)})),
            None => None,
        };
        Ok(json!({
            "samples_per_row": study.samples,
            "seed": study.seed,
            "ida_samples": study.ida_samples,
            "rows": rows,
            "samples": ens,
            "fragility": fragility,
        }))
    })?;
    Ok(doc.to_string())
}

/// The two table files of an archive (`rocklab archive`), an interrupted change
/// finished or discarded first.
#[pyfunction]
fn archive_tables(py: Python<'_>, archive: PathBuf) -> PyResult<Vec<String>> {
    guarded(py, move || {
        let paths = rocklab::archive::open(&archive)?;
        Ok(paths.iter().map(|p| p.display().to_string()).collect())
    })
}

/// Scale factors of `--scales FROM:TO:N`.
#[pyfunction]
fn parse_scales(py: Python<'_>, text: &str) -> PyResult<Vec<f64>> {
    let text = text.to_string();
    guarded(py, move || Ok(rocklab::facade::parse_scales(&text)?))
}

/// The records, coefficient sets and polarities of a study (in the order of its
/// combinations), to plan runs.
#[pyfunction]
fn study_info(py: Python<'_>, study: PathBuf) -> PyResult<String> {
    let doc = guarded(py, move || {
        let s = Study::load(&study)?;
        Ok(json!({
            "study": s.name,
            "records": s.records.iter().map(|r| r.name.clone()).collect::<Vec<_>>(),
            "coefficient_sets": s.sets,
            "polarities": s.polarities.iter().map(|p| *p as i32).collect::<Vec<_>>(),
            "magnification": s.magnification,
        }))
    })?;
    Ok(doc.to_string())
}

/// Selected runs of a study: `runs_json` is a list of [record, set, polarity,
/// scale]. Each run is one combination of the library's own study functions on a
/// one-combination copy of the study: with `sensitivity`, `run_study` (the
/// façade table's run, repeated at rtol × 100 and / 100 for `well_conditioned`),
/// without it `run_ida` (one integration, the IDA's point). Runs go over the
/// rayon pool when `parallel`, else one after the other (one Dask worker thread).
#[pyfunction]
#[pyo3(signature = (study, runs_json, sensitivity=true, parallel=true))]
fn facade_runs(py: Python<'_>, study: PathBuf, runs_json: &str, sensitivity: bool, parallel: bool) -> PyResult<String> {
    let runs_json = runs_json.to_string();
    let doc = guarded(py, move || {
        let study = Study::load(&study)?;
        let runs: Vec<(String, String, i64, f64)> =
            serde_json::from_str(&runs_json).context("runs: expected a list of [record, set, polarity, scale]")?;
        let mut subs = std::collections::HashMap::new();
        let mut jobs = Vec::with_capacity(runs.len());
        for (rec, set, pol, scale) in &runs {
            let r = study.records.iter().position(|x| &x.name == rec).ok_or_else(|| {
                anyhow!(
                    "record {rec:?} is not in the study (records: {})",
                    study.records.iter().map(|x| x.name.as_str()).collect::<Vec<_>>().join(", ")
                )
            })?;
            let s = study.sets.iter().position(|x| &x.name == set).ok_or_else(|| {
                anyhow!(
                    "coefficient set {set:?} is not in the study (sets: {})",
                    study.sets.iter().map(|x| x.name.as_str()).collect::<Vec<_>>().join(", ")
                )
            })?;
            if *pol != 1 && *pol != -1 {
                bail!("polarity {pol}: expected 1 or -1");
            }
            rocklab::limits::MAGNIFICATION.check("scale", *scale).map_err(anyhow::Error::msg)?;
            subs.entry((r, s, *pol)).or_insert_with(|| Study {
                records: vec![study.records[r].clone()],
                sets: vec![study.sets[s].clone()],
                polarities: vec![*pol as f64],
                ..study.clone()
            });
            jobs.push(((r, s, *pol), *scale));
        }
        let one = |(key, scale): &((usize, usize, i64), f64)| -> anyhow::Result<Value> {
            let sub = &subs[key];
            Ok(if sensitivity {
                serde_json::to_value(&run_study(sub, *scale, false, &|| {})?[0])?
            } else {
                serde_json::to_value(&run_ida(sub, &[*scale], &|| {})?[0])?
            })
        };
        let out: Vec<Value> = if parallel {
            jobs.par_iter().map(one).collect::<anyhow::Result<_>>()?
        } else {
            jobs.iter().map(one).collect::<anyhow::Result<_>>()?
        };
        Ok(Value::Array(out))
    })?;
    Ok(doc.to_string())
}

/// Deliberately panics (tests check that a panic becomes `RocklabError`).
#[pyfunction]
fn _panic_for_tests(py: Python<'_>) -> PyResult<()> {
    guarded(py, || -> anyhow::Result<()> { panic!("test panic") })
}

/// The extension module.
#[pymodule]
fn _rocklab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("RocklabError", m.py().get_type::<RocklabError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_function(wrap_pyfunction!(reduce, m)?)?;
    m.add_function(wrap_pyfunction!(reduce_log, m)?)?;
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(facade, m)?)?;
    m.add_function(wrap_pyfunction!(parse_scales, m)?)?;
    m.add_function(wrap_pyfunction!(archive_tables, m)?)?;
    m.add_function(wrap_pyfunction!(study_info, m)?)?;
    m.add_function(wrap_pyfunction!(facade_runs, m)?)?;
    m.add_function(wrap_pyfunction!(facade_ensembles, m)?)?;
    m.add_function(wrap_pyfunction!(_panic_for_tests, m)?)?;
    Ok(())
}
