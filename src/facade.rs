//! The façade study (paper §5): one block, several records, several coefficient
//! sets, both polarities; optionally over a range of scale factors (incremental
//! dynamic analysis). The study file format is documented in the README and in
//! `fixtures/facade/study.toml`.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Deserialize;

use crate::ground_motion::{self, Format, ReadOptions, Record, Units};
use crate::ingest::block::BlockSpec;
use crate::study::{run, RunSpec, RunSummary};
use crate::wall::housner_e;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawStudy {
    study: RawHead,
    #[serde(default)]
    record: Vec<RawRecord>,
    #[serde(default)]
    coefficients: Vec<RawSet>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawHead {
    name: Option<String>,
    block: String,
    #[serde(default = "one")]
    magnification: f64,
    polarities: Option<Vec<i64>>,
    overturn_limit_rad: Option<f64>,
    #[serde(default)]
    t_extra_s: f64,
    rtol: Option<f64>,
}

fn one() -> f64 {
    1.0
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRecord {
    name: String,
    file: String,
    format: Option<String>,
    units: Option<String>,
    dt: Option<f64>,
    component: Option<String>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSet {
    name: String,
    /// One e both ways.
    e: Option<f64>,
    e_in: Option<f64>,
    e_out: Option<f64>,
    /// "eq2": Housner's Eq. 2 with the block's α.
    housner: Option<String>,
    /// A calibration.toml written by `rocklab calibrate`.
    calibration: Option<String>,
}

/// A coefficient set of the study.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CoefficientSet {
    pub name: String,
    pub e_in: f64,
    pub e_out: f64,
    /// Where the values came from.
    pub source: String,
}

/// A record of the study.
#[derive(Debug, Clone)]
pub struct StudyRecord {
    pub name: String,
    pub component: Option<String>,
    pub record: Record,
}

/// A validated study.
#[derive(Debug, Clone)]
pub struct Study {
    pub name: String,
    pub path: PathBuf,
    pub block: BlockSpec,
    pub magnification: f64,
    pub polarities: Vec<f64>,
    pub overturn_limit: f64,
    pub t_extra: f64,
    pub rtol: f64,
    pub records: Vec<StudyRecord>,
    pub sets: Vec<CoefficientSet>,
    /// e_H by Eq. 2 with the block's α (reported next to any given Housner value).
    pub e_housner_eq2: f64,
}

fn bad(path: &Path, msg: impl std::fmt::Display) -> anyhow::Error {
    anyhow::anyhow!("{}: {msg}", path.display())
}

fn check_e(path: &Path, set: &str, key: &str, e: f64) -> anyhow::Result<f64> {
    if e > 0.0 && e <= 1.0 {
        Ok(e)
    } else {
        Err(bad(path, format!("[[coefficients]] {set:?}: {key} = {e}: expected 0 < e ≤ 1")))
    }
}

/// e_in and e_out of a calibration.toml (`[calibration] e_in, e_out`).
pub fn read_calibration(path: &Path) -> anyhow::Result<(f64, f64)> {
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, format!("cannot read calibration: {e}")))?;
    let v: toml::Value = toml::from_str(&text).map_err(|e| bad(path, e.to_string().trim_end()))?;
    let c = v.get("calibration").ok_or_else(|| bad(path, "no [calibration] table"))?;
    let get = |k: &str| {
        c.get(k)
            .and_then(|x| x.as_float())
            .ok_or_else(|| bad(path, format!("[calibration].{k} missing or not a number")))
    };
    Ok((get("e_in")?, get("e_out")?))
}

impl Study {
    pub fn load(path: &Path) -> anyhow::Result<Study> {
        let text = std::fs::read_to_string(path).map_err(|e| bad(path, format!("cannot read study: {e}")))?;
        let raw: RawStudy = toml::from_str(&text).map_err(|e| bad(path, e.to_string().trim_end()))?;
        let base = path.parent().unwrap_or_else(|| Path::new("."));
        let block = BlockSpec::load(&base.join(&raw.study.block))?;
        let h = &raw.study;
        if !(h.magnification.is_finite() && h.magnification > 0.0) {
            return Err(bad(
                path,
                format!("[study].magnification = {}: expected a positive number", h.magnification),
            ));
        }
        let polarities = match &h.polarities {
            None => vec![1.0, -1.0],
            Some(p) if !p.is_empty() && p.iter().all(|x| *x == 1 || *x == -1) => p.iter().map(|x| *x as f64).collect(),
            Some(p) => return Err(bad(path, format!("[study].polarities = {p:?}: expected a list of 1 and/or -1"))),
        };
        if raw.record.is_empty() {
            return Err(bad(path, "no [[record]]: expected at least one record"));
        }
        if raw.coefficients.is_empty() {
            return Err(bad(path, "no [[coefficients]]: expected at least one coefficient set"));
        }
        let e_eq2 = housner_e(block.block.alpha);
        let mut sets = Vec::new();
        for s in &raw.coefficients {
            let (e_in, e_out, source) = match (s.e, s.e_in, s.e_out, s.housner.as_deref(), s.calibration.as_deref()) {
                (Some(e), None, None, None, None) => (e, e, "given".to_string()),
                (None, Some(i), Some(o), None, None) => (i, o, "given".to_string()),
                (None, None, None, Some("eq2"), None) => (e_eq2, e_eq2, format!("Eq. 2 with α = {}", block.block.alpha)),
                (None, None, None, None, Some(file)) => {
                    let (i, o) = read_calibration(&base.join(file))?;
                    (i, o, format!("calibration {file}"))
                }
                (None, None, None, Some(other), None) => {
                    return Err(bad(path, format!("[[coefficients]] {:?}: housner = {other:?}: expected \"eq2\"", s.name)))
                }
                _ => {
                    return Err(bad(
                        path,
                        format!(
                            "[[coefficients]] {:?}: give e, or e_in with e_out, or housner = \"eq2\", or calibration = FILE",
                            s.name
                        ),
                    ))
                }
            };
            sets.push(CoefficientSet {
                name: s.name.clone(),
                e_in: check_e(path, &s.name, "e_in", e_in)?,
                e_out: check_e(path, &s.name, "e_out", e_out)?,
                source,
            });
        }
        let mut records = Vec::new();
        for r in &raw.record {
            let format = match r.format.as_deref() {
                None | Some("auto") => None,
                Some("esm") => Some(Format::Esm),
                Some("at2") => Some(Format::At2),
                Some("cosmos") => Some(Format::Cosmos),
                Some("two-column") => Some(Format::TwoColumn),
                Some("one-column") => Some(Format::OneColumn),
                Some(other) => {
                    return Err(bad(
                        path,
                        format!(
                            "[[record]] {:?}: format = {other:?}: expected auto, esm, at2, cosmos, two-column or one-column",
                            r.name
                        ),
                    ))
                }
            };
            let units = r
                .units
                .as_deref()
                .map(|u| Units::parse(u).ok_or_else(|| bad(path, format!("[[record]] {:?}: units = {u:?}: expected g, m/s2 or cm/s2", r.name))))
                .transpose()?;
            let file = base.join(&r.file);
            let record = ground_motion::read(&file, &ReadOptions { format, dt: r.dt, units })
                .map_err(|e| bad(path, format!("[[record]] {:?}: {e}", r.name)))?;
            records.push(StudyRecord {
                name: r.name.clone(),
                component: r.component.clone(),
                record,
            });
        }
        let overturn_limit = h.overturn_limit_rad.unwrap_or(block.block.alpha);
        if overturn_limit.is_nan() || overturn_limit <= 0.0 {
            return Err(bad(
                path,
                format!("[study].overturn_limit_rad = {overturn_limit}: expected a positive angle"),
            ));
        }
        Ok(Study {
            name: h.name.clone().unwrap_or_else(|| block.name.clone()),
            path: path.to_path_buf(),
            magnification: h.magnification,
            polarities,
            overturn_limit,
            t_extra: h.t_extra_s,
            rtol: h.rtol.unwrap_or(1e-8),
            records,
            sets,
            e_housner_eq2: e_eq2,
            block,
        })
    }

    fn spec(&self, set: &CoefficientSet, polarity: f64, scale: f64, rtol: f64, history: bool) -> RunSpec {
        RunSpec {
            e_in: set.e_in,
            e_out: set.e_out,
            scale: self.magnification * scale,
            polarity,
            overturn_limit: self.overturn_limit,
            t_extra: self.t_extra,
            rtol,
            atol: rtol * 1e-2,
            keep_history: history,
        }
    }

    /// Every (record, set, polarity) combination.
    pub fn combinations(&self) -> Vec<(usize, usize, f64)> {
        let mut v = Vec::new();
        for r in 0..self.records.len() {
            for s in 0..self.sets.len() {
                for &p in &self.polarities {
                    v.push((r, s, p));
                }
            }
        }
        v
    }
}

/// One run of the study, with its sensitivity check.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StudyRun {
    pub record: String,
    pub coefficients: String,
    pub polarity: i8,
    pub scale: f64,
    #[serde(flatten)]
    pub summary: RunSummary,
    /// Same outcome and peak (within 5 % of max(|peak|, 0.05)) at rtol × 100 and
    /// rtol / 100.
    pub well_conditioned: bool,
    /// max θ/α at the looser and the tighter tolerance.
    pub sensitivity: [f64; 2],
    #[serde(skip)]
    pub history: Vec<crate::solver::run::Sample>,
}

/// Run the combinations at one scale (with histories for the plots when asked),
/// each at three tolerances; `tick` is called after each combination.
pub fn run_study(study: &Study, scale: f64, with_history: bool, tick: &(dyn Fn() + Sync)) -> Vec<StudyRun> {
    study
        .combinations()
        .par_iter()
        .map(|&(r, s, p)| {
            let rec = &study.records[r];
            let set = &study.sets[s];
            let (sum, sim) = run(&study.block, &rec.record, &study.spec(set, p, scale, study.rtol, with_history));
            let loose = run(&study.block, &rec.record, &study.spec(set, p, scale, study.rtol * 100.0, false)).0;
            let tight = run(&study.block, &rec.record, &study.spec(set, p, scale, study.rtol / 100.0, false)).0;
            let close = |o: &RunSummary| {
                o.overturned == sum.overturned
                    && (o.max_theta_over_alpha - sum.max_theta_over_alpha).abs() <= 0.05 * sum.max_theta_over_alpha.abs().max(0.05)
            };
            tick();
            StudyRun {
                record: rec.name.clone(),
                coefficients: set.name.clone(),
                polarity: p as i8,
                scale,
                well_conditioned: close(&loose) && close(&tight),
                sensitivity: [loose.max_theta_over_alpha, tight.max_theta_over_alpha],
                summary: sum,
                history: sim.history,
            }
        })
        .collect()
}

/// Scale factors FROM:TO:N (inclusive, N ≥ 2).
pub fn parse_scales(s: &str) -> anyhow::Result<Vec<f64>> {
    let parts: Vec<&str> = s.split(':').collect();
    let err = || anyhow::anyhow!("--scales {s}: expected FROM:TO:N with 0 < FROM < TO and N ≥ 2 (e.g. 0.1:2.0:50)");
    if parts.len() != 3 {
        return Err(err());
    }
    let from: f64 = parts[0].parse().map_err(|_| err())?;
    let to: f64 = parts[1].parse().map_err(|_| err())?;
    let n: usize = parts[2].parse().map_err(|_| err())?;
    if !(from > 0.0 && to > from && n >= 2 && from.is_finite() && to.is_finite()) {
        return Err(err());
    }
    Ok((0..n).map(|i| from + (to - from) * i as f64 / (n - 1) as f64).collect())
}

/// One IDA point: max θ/α (∞-free: an overturned run reports its peak, 1 at the
/// default limit) and whether it overturned.
#[derive(Debug, Clone, serde::Serialize)]
pub struct IdaPoint {
    pub record: String,
    pub coefficients: String,
    pub polarity: i8,
    pub scale: f64,
    pub max_theta_over_alpha: f64,
    pub overturned: bool,
}

/// Incremental dynamic analysis: every combination at every scale (single
/// tolerance, no history), in parallel.
pub fn run_ida(study: &Study, scales: &[f64], tick: &(dyn Fn() + Sync)) -> Vec<IdaPoint> {
    let mut jobs = Vec::new();
    for &sc in scales {
        for c in study.combinations() {
            jobs.push((sc, c));
        }
    }
    jobs.par_iter()
        .map(|&(sc, (r, s, p))| {
            let rec = &study.records[r];
            let set = &study.sets[s];
            let (sum, _) = run(&study.block, &rec.record, &study.spec(set, p, sc, study.rtol, false));
            tick();
            IdaPoint {
                record: rec.name.clone(),
                coefficients: set.name.clone(),
                polarity: p as i8,
                scale: sc,
                max_theta_over_alpha: sum.max_theta_over_alpha,
                overturned: sum.overturned,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales() {
        assert_eq!(parse_scales("0.5:1.5:3").unwrap(), vec![0.5, 1.0, 1.5]);
        for bad in ["1:0.5:3", "0.5:1", "a:b:c", "0:1:3", "0.1:1:1"] {
            assert!(parse_scales(bad).is_err(), "{bad}");
        }
    }
}
