//! The façade study (paper §5): one block, several records, several coefficient
//! sets, both polarities; optionally over a range of scale factors (incremental
//! dynamic analysis). The study file format is documented in the README and in
//! `fixtures/facade/study.toml`.

use std::path::{Path, PathBuf};

use rayon::prelude::*;
use serde::Deserialize;

use crate::calibrate::Spread;
use crate::ensemble::{self, CoefficientDist, Dist, Inputs, Nominal, Outcome, PolarityMode, SampleKey, Uncertainty};
use crate::fragility::{fit_lognormal, Fragility, FragilityError, Trial};
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
    /// Distributions of the shared inputs (see [`parse_uncertainty`]).
    uncertainty: Option<toml::Table>,
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
    /// Ensemble size per record × coefficient set (× polarity); 0 or absent: none.
    samples: Option<usize>,
    seed: Option<u64>,
    /// "each" (one ensemble per polarity, default) or "random".
    polarity: Option<String>,
    /// Intensity measure of the fragility curves: "pga" (default) or "pgv".
    im: Option<String>,
    /// Samples per record × polarity × set at each scale of an IDA.
    ida_samples: Option<usize>,
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
    /// Standard deviations of a normal spread of e (e), or of e_in and e_out.
    sd_e: Option<f64>,
    sd_e_in: Option<f64>,
    sd_e_out: Option<f64>,
    /// With a calibration: "tests" (default: the test-to-test spread and the
    /// fits' standard errors), "mean" (the standard error of the mean) or "none".
    spread: Option<String>,
}

/// A coefficient set of the study.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CoefficientSet {
    pub name: String,
    pub e_in: f64,
    pub e_out: f64,
    /// Where the values came from.
    pub source: String,
    /// What an ensemble draws e from.
    pub dist: CoefficientDist,
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
    /// The block file as the study named it, resolved against the study's folder.
    pub block_path: PathBuf,
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
    /// The overturning limit as given (None: α, which a sample may vary).
    pub overturn_limit_given: Option<f64>,
    /// Ensemble size (0: deterministic runs only).
    pub samples: usize,
    pub seed: u64,
    pub polarity_mode: PolarityMode,
    pub uncertainty: Uncertainty,
    pub im: Im,
    /// Samples per point of an IDA (1 without uncertainty).
    pub ida_samples: usize,
}

/// The intensity measure of the fragility curves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Im {
    /// Peak ground acceleration of the scaled record (g).
    Pga,
    /// Peak ground velocity of the scaled record (cm/s).
    Pgv,
}

impl Im {
    pub fn label(self) -> &'static str {
        match self {
            Im::Pga => "PGA (g)",
            Im::Pgv => "PGV (cm/s)",
        }
    }
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

/// A calibration.toml with the spread an ensemble draws from (absent in files
/// written before it was added: then None).
#[derive(Debug, Clone)]
pub struct CalibrationFile {
    pub e_in: f64,
    pub e_out: f64,
    pub rocking: Option<String>,
    pub spread: Option<Spread>,
}

/// Read a calibration.toml in full.
pub fn read_calibration_file(path: &Path) -> anyhow::Result<CalibrationFile> {
    let (e_in, e_out) = read_calibration(path)?;
    let text = std::fs::read_to_string(path).map_err(|e| bad(path, format!("cannot read calibration: {e}")))?;
    let v: toml::Value = toml::from_str(&text).map_err(|e| bad(path, e.to_string().trim_end()))?;
    let c = &v["calibration"];
    let spread = match c.get("spread") {
        None => None,
        Some(sp) => {
            let f = |k: &str| {
                sp.get(k)
                    .and_then(|x| x.as_float().or_else(|| x.as_integer().map(|i| i as f64)))
                    .ok_or_else(|| bad(path, format!("[calibration.spread].{k} missing or not a number")))
            };
            Some(Spread {
                n_tests: f("n_tests")? as usize,
                sd_e_in_tests: f("sd_e_in_tests")?,
                sd_e_out_tests: f("sd_e_out_tests")?,
                se_e_in_mean: f("se_e_in_mean")?,
                se_e_out_mean: f("se_e_out_mean")?,
                se_e_in_fit: f("se_e_in_fit")?,
                se_e_out_fit: f("se_e_out_fit")?,
            })
        }
    };
    Ok(CalibrationFile {
        e_in,
        e_out,
        rocking: c.get("rocking").and_then(|r| r.as_str()).map(String::from),
        spread,
    })
}

/// The coefficient set of a calibration: normal spreads of e_in and e_out as
/// `spread` says: "tests" (√(sd_tests² + se_fit²): how e varies from one
/// wall or test to the next, plus the fits' own error), "mean" (the standard error
/// of the means) or "none".
pub fn calibration_set(name: &str, file: &str, cal: &CalibrationFile, spread: &str) -> Result<CoefficientSet, String> {
    let (sd_in, sd_out) = match (spread, &cal.spread) {
        ("none", _) => (0.0, 0.0),
        (_, None) => {
            return Err(format!(
                "calibration {file} has no [calibration.spread] (written by an older rocklab): re-run calibrate, or set spread = \"none\""
            ))
        }
        ("tests", Some(sp)) => (sp.sd_e_in_tests.hypot(sp.se_e_in_fit), sp.sd_e_out_tests.hypot(sp.se_e_out_fit)),
        ("mean", Some(sp)) => (sp.se_e_in_mean, sp.se_e_out_mean),
        (other, _) => return Err(format!("spread = {other:?}: expected \"tests\", \"mean\" or \"none\"")),
    };
    let single = cal.rocking.as_deref() == Some("two-sided");
    let dist = if single {
        CoefficientDist::Single(normal_or_fixed(cal.e_in, sd_in))
    } else {
        CoefficientDist::Pair {
            e_in: normal_or_fixed(cal.e_in, sd_in),
            e_out: normal_or_fixed(cal.e_out, sd_out),
        }
    };
    Ok(CoefficientSet {
        name: name.to_string(),
        e_in: cal.e_in,
        e_out: cal.e_out,
        source: format!(
            "calibration {file}{}",
            if spread == "none" {
                String::new()
            } else {
                format!(", spread \"{spread}\"")
            }
        ),
        dist,
    })
}

fn normal_or_fixed(mean: f64, sd: f64) -> Dist {
    if sd > 0.0 && sd.is_finite() {
        Dist::Normal { mean, sd }
    } else {
        Dist::Fixed { value: mean }
    }
}

/// One distribution of `[uncertainty]`: a number (fixed), `{ normal = [mean, sd] }`
/// or `{ uniform = [lo, hi] }`.
fn parse_dist(path: &Path, key: &str, v: &toml::Value) -> anyhow::Result<Dist> {
    let num = |x: &toml::Value| x.as_float().or_else(|| x.as_integer().map(|i| i as f64));
    let expected = || {
        bad(
            path,
            format!("[uncertainty].{key} = {v}: expected a number, {{ normal = [mean, sd] }} or {{ uniform = [lo, hi] }}"),
        )
    };
    if let Some(x) = num(v) {
        return Ok(Dist::Fixed { value: x });
    }
    let t = v.as_table().ok_or_else(expected)?;
    if t.len() != 1 {
        return Err(expected());
    }
    let (kind, pair) = t.iter().next().ok_or_else(expected)?;
    let pair: Vec<f64> = pair
        .as_array()
        .ok_or_else(expected)?
        .iter()
        .map(num)
        .collect::<Option<Vec<_>>>()
        .ok_or_else(expected)?;
    match (kind.as_str(), pair.as_slice()) {
        ("normal", &[m, sd]) if m.is_finite() && sd.is_finite() && sd >= 0.0 => Ok(Dist::Normal { mean: m, sd }),
        ("uniform", &[lo, hi]) if lo.is_finite() && hi.is_finite() && lo <= hi => Ok(Dist::Uniform { lo, hi }),
        ("normal", _) => Err(bad(path, format!("[uncertainty].{key}: normal = [mean, sd] with sd ≥ 0"))),
        ("uniform", _) => Err(bad(path, format!("[uncertainty].{key}: uniform = [lo, hi] with lo ≤ hi"))),
        _ => Err(expected()),
    }
}

/// `[uncertainty]`: magnification, r_m, alpha_rad, i0_kg_m2, unit_stiffness_mn_m2,
/// contact_height_m; unknown keys are rejected by name.
fn parse_uncertainty(path: &Path, t: &toml::Table, block: &BlockSpec) -> anyhow::Result<Uncertainty> {
    let mut u = Uncertainty::default();
    for (k, v) in t {
        let d = Some(parse_dist(path, k, v)?);
        match k.as_str() {
            "magnification" => u.magnification = d,
            "r_m" => u.r_m = d,
            "alpha_rad" => u.alpha_rad = d,
            "i0_kg_m2" => u.i0_kg_m2 = d,
            "unit_stiffness_mn_m2" | "contact_height_m" => {
                if block.spring_bed.is_none() {
                    return Err(bad(
                        path,
                        format!("[uncertainty].{k}: the block file gives no spring bed ([restraint] unit_stiffness_mn_m2 with contact_height_m)"),
                    ));
                }
                if k == "contact_height_m" {
                    u.contact_height_m = d;
                } else {
                    u.unit_stiffness_mn_m2 = d;
                }
            }
            other => {
                return Err(bad(
                    path,
                    format!(
                    "[uncertainty].{other}: unknown input (expected magnification, r_m, alpha_rad, i0_kg_m2, unit_stiffness_mn_m2, contact_height_m)"
                ),
                ))
            }
        }
    }
    Ok(u)
}

/// The spread of e declared on a [[coefficients]] set (sd_e, or sd_e_in/sd_e_out).
fn set_dist(path: &Path, s: &RawSet, e_in: f64, e_out: f64, single: bool) -> anyhow::Result<CoefficientDist> {
    for (k, v) in [("sd_e", s.sd_e), ("sd_e_in", s.sd_e_in), ("sd_e_out", s.sd_e_out)] {
        if let Some(v) = v {
            if !(v.is_finite() && v >= 0.0) {
                return Err(bad(
                    path,
                    format!("[[coefficients]] {:?}: {k} = {v}: expected a standard deviation ≥ 0", s.name),
                ));
            }
        }
    }
    Ok(match (single, s.sd_e, s.sd_e_in, s.sd_e_out) {
        (true, sd, None, None) => CoefficientDist::Single(normal_or_fixed(e_in, sd.unwrap_or(0.0))),
        (false, None, si, so) => CoefficientDist::Pair {
            e_in: normal_or_fixed(e_in, si.unwrap_or(0.0)),
            e_out: normal_or_fixed(e_out, so.unwrap_or(0.0)),
        },
        (false, Some(sd), None, None) => CoefficientDist::Pair {
            e_in: normal_or_fixed(e_in, sd),
            e_out: normal_or_fixed(e_out, sd),
        },
        _ => {
            return Err(bad(
                path,
                format!(
                    "[[coefficients]] {:?}: give sd_e with e, sd_e_in/sd_e_out with e_in/e_out (or sd_e for both)",
                    s.name
                ),
            ))
        }
    })
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
            if s.spread.is_some() && s.calibration.is_none() {
                return Err(bad(
                    path,
                    format!("[[coefficients]] {:?}: spread is for a set read from a calibration file", s.name),
                ));
            }
            let (e_in, e_out, source, single) = match (s.e, s.e_in, s.e_out, s.housner.as_deref(), s.calibration.as_deref()) {
                (Some(e), None, None, None, None) => (e, e, "given".to_string(), true),
                (None, Some(i), Some(o), None, None) => (i, o, "given".to_string(), false),
                (None, None, None, Some("eq2"), None) => (e_eq2, e_eq2, format!("Eq. 2 with α = {}", block.block.alpha), true),
                (None, None, None, None, Some(file)) => {
                    if s.sd_e.or(s.sd_e_in).or(s.sd_e_out).is_some() {
                        return Err(bad(path, format!("[[coefficients]] {:?}: a calibration set takes its spread from the file (spread = \"tests\", \"mean\" or \"none\"), not sd_e*", s.name)));
                    }
                    let cal = read_calibration_file(&base.join(file))?;
                    let set = calibration_set(&s.name, file, &cal, s.spread.as_deref().unwrap_or("tests"))
                        .map_err(|e| bad(path, format!("[[coefficients]] {:?}: {e}", s.name)))?;
                    check_e(path, &s.name, "e_in", set.e_in)?;
                    check_e(path, &s.name, "e_out", set.e_out)?;
                    sets.push(set);
                    continue;
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
            let dist = set_dist(path, s, e_in, e_out, single)?;
            sets.push(CoefficientSet {
                name: s.name.clone(),
                e_in: check_e(path, &s.name, "e_in", e_in)?,
                e_out: check_e(path, &s.name, "e_out", e_out)?,
                source,
                dist,
            });
        }
        if let Some(dup) = sets.iter().enumerate().find(|(i, a)| sets[..*i].iter().any(|b| b.name == a.name)) {
            return Err(bad(path, format!("[[coefficients]] {:?}: the name is used twice", dup.1.name)));
        }
        let mut records = Vec::new();
        for r in &raw.record {
            let format = match Format::from_name(r.format.as_deref().unwrap_or("auto")) {
                Ok(f) => f,
                Err(e) => return Err(bad(path, format!("[[record]] {:?}: {e}", r.name))),
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
        let uncertainty = match &raw.uncertainty {
            Some(t) => parse_uncertainty(path, t, &block)?,
            None => Uncertainty::default(),
        };
        let polarity_mode = match h.polarity.as_deref() {
            None | Some("each") => PolarityMode::Each,
            Some("random") => PolarityMode::Random,
            Some(o) => return Err(bad(path, format!("[study].polarity = {o:?}: expected \"each\" or \"random\""))),
        };
        let im = match h.im.as_deref() {
            None | Some("pga") => Im::Pga,
            Some("pgv") => Im::Pgv,
            Some(o) => return Err(bad(path, format!("[study].im = {o:?}: expected \"pga\" or \"pgv\""))),
        };
        let any_random = !uncertainty.describe().is_empty()
            || sets.iter().any(|s| match s.dist {
                CoefficientDist::Single(d) => d.is_random(),
                CoefficientDist::Pair { e_in, e_out } => e_in.is_random() || e_out.is_random(),
            })
            || polarity_mode == PolarityMode::Random;
        Ok(Study {
            overturn_limit_given: h.overturn_limit_rad,
            samples: h.samples.unwrap_or(0),
            seed: h.seed.unwrap_or(2021),
            polarity_mode,
            uncertainty,
            im,
            ida_samples: h.ida_samples.unwrap_or(if any_random { 10 } else { 1 }).max(1),
            name: h.name.clone().unwrap_or_else(|| block.name.clone()),
            path: path.to_path_buf(),
            block_path: base.join(&raw.study.block),
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

/// One sample of an ensemble: where it sits, what it drew, what happened.
#[derive(Debug, Clone, serde::Serialize)]
pub struct SampleRun {
    pub record: String,
    pub coefficients: String,
    /// The row's polarity (None: drawn per sample, see `inputs.polarity`).
    pub row_polarity: Option<i8>,
    pub scale: f64,
    pub sample: usize,
    /// The intensity measure of the scaled record the sample felt.
    pub im: f64,
    #[serde(flatten)]
    pub inputs: Inputs,
    #[serde(flatten)]
    pub outcome: Outcome,
}

/// What an ensemble says for one record × polarity row × coefficient set.
#[derive(Debug, Clone, serde::Serialize)]
pub struct EnsembleRow {
    pub record: String,
    pub coefficients: String,
    /// None: polarity drawn per sample.
    pub polarity: Option<i8>,
    #[serde(flatten)]
    pub stats: ensemble::EnsembleStats,
}

/// A job of an ensemble: record, set, polarity row, scale index and factor.
#[derive(Debug, Clone, Copy)]
struct Job {
    record: usize,
    set: usize,
    row: Option<f64>,
    scale_idx: usize,
    scale: f64,
}

impl Study {
    /// The polarity rows of the ensembles: each polarity, or one random row.
    pub fn rows(&self) -> Vec<Option<f64>> {
        match self.polarity_mode {
            PolarityMode::Each => self.polarities.iter().map(|p| Some(*p)).collect(),
            PolarityMode::Random => vec![None],
        }
    }

    fn nominal(&self) -> Nominal {
        let b = &self.block.block;
        Nominal {
            magnification: self.magnification,
            r_m: b.r_m,
            alpha: b.alpha,
            i0: b.i0,
            spring_bed: self.block.spring_bed,
        }
    }

    /// The block of a sample: R, α, I_0 and the spring bed as drawn.
    fn sample_block(&self, x: &Inputs) -> BlockSpec {
        let mut b = self.block.clone();
        b.block.r_m = x.r_m;
        b.block.alpha = x.alpha;
        b.block.i0 = x.i0;
        if let Some((k, h)) = x.spring_bed {
            b.restraint = crate::solver::Restraint::spring_bed(k * 1e6, h);
        }
        b
    }

    fn run_sample(&self, job: Job, i: usize, ims: &[f64]) -> SampleRun {
        let rec = &self.records[job.record];
        let set = &self.sets[job.set];
        let key = SampleKey {
            seed: self.seed,
            record: ensemble::name_key(&rec.name),
            row: match job.row {
                None => 0,
                Some(p) if p > 0.0 => 1,
                Some(_) => 2,
            },
            scale: job.scale_idx as u64,
            sample: i as u64,
        };
        let x = ensemble::draw(&key, &self.uncertainty, &self.nominal(), &set.name, &set.dist, job.row);
        let block = self.sample_block(&x);
        let spec = RunSpec {
            e_in: x.e_in,
            e_out: x.e_out,
            scale: x.magnification * job.scale,
            polarity: x.polarity,
            overturn_limit: self.overturn_limit_given.unwrap_or(x.alpha),
            t_extra: self.t_extra,
            rtol: self.rtol,
            atol: self.rtol * 1e-2,
            keep_history: false,
        };
        let (sum, _) = run(&block, &rec.record, &spec);
        SampleRun {
            record: rec.name.clone(),
            coefficients: set.name.clone(),
            row_polarity: job.row.map(|p| p as i8),
            scale: job.scale,
            sample: i,
            im: ims[job.record] * x.magnification * job.scale,
            inputs: x,
            outcome: Outcome {
                overturned: sum.overturned,
                overturn_time_s: sum.overturn_time_s,
                max_theta_over_alpha: sum.max_theta_over_alpha,
            },
        }
    }

    /// The IM of each record at factor 1.
    fn unit_ims(&self) -> Vec<f64> {
        self.records
            .iter()
            .map(|r| match self.im {
                Im::Pga => r.record.pga_g(1.0),
                Im::Pgv => r.record.pgv_cm_s(1.0),
            })
            .collect()
    }

    /// Run `n` samples for every job, in parallel over all samples.
    fn run_jobs(&self, jobs: &[Job], n: usize, tick: &(dyn Fn() + Sync)) -> Vec<SampleRun> {
        let ims = self.unit_ims();
        let work: Vec<(Job, usize)> = jobs.iter().flat_map(|j| (0..n).map(move |i| (*j, i))).collect();
        work.par_iter()
            .map(|&(j, i)| {
                let r = self.run_sample(j, i, &ims);
                tick();
                r
            })
            .collect()
    }
}

/// The ensembles at scale 1: `n` samples per record × polarity row × set.
/// Returns the rows (record-major, then polarity row, then set) and every sample.
pub fn run_ensembles(study: &Study, n: usize, tick: &(dyn Fn() + Sync)) -> (Vec<EnsembleRow>, Vec<SampleRun>) {
    let jobs = jobs_at(study, 0, 1.0);
    let samples = study.run_jobs(&jobs, n, tick);
    let rows = samples
        .chunks(n.max(1))
        .zip(&jobs)
        .map(|(chunk, j)| EnsembleRow {
            record: study.records[j.record].name.clone(),
            coefficients: study.sets[j.set].name.clone(),
            polarity: j.row.map(|p| p as i8),
            stats: ensemble::summarise(&chunk.iter().map(|s| s.outcome).collect::<Vec<_>>()),
        })
        .collect();
    (rows, samples)
}

/// IDA with ensembles: `n` samples per record × polarity row × set at each scale
/// (scale indices 1, 2, … so that no stream is shared with the scale-1 ensemble).
pub fn run_ida_samples(study: &Study, scales: &[f64], n: usize, tick: &(dyn Fn() + Sync)) -> Vec<SampleRun> {
    let jobs: Vec<Job> = scales.iter().enumerate().flat_map(|(k, &scale)| jobs_at(study, k + 1, scale)).collect();
    study.run_jobs(&jobs, n, tick)
}

/// One job per record × polarity row × set at one scale (record-major, then
/// polarity row, then set).
fn jobs_at(study: &Study, scale_idx: usize, scale: f64) -> Vec<Job> {
    let mut jobs = Vec::new();
    for record in 0..study.records.len() {
        for row in study.rows() {
            for set in 0..study.sets.len() {
                jobs.push(Job {
                    record,
                    set,
                    row,
                    scale_idx,
                    scale,
                });
            }
        }
    }
    jobs
}

/// A set's fragility: the fit (or why not) and the observed fractions per record ×
/// scale (mean IM of the group, runs, overturned).
#[derive(Debug, Clone, serde::Serialize)]
pub struct SetFragility {
    pub coefficients: String,
    /// In summary.json: the fitted values, or `{"error": why}`.
    #[serde(serialize_with = "fit_or_error")]
    pub fit: Result<Fragility, FragilityError>,
    pub observed: Vec<Trial>,
}

fn fit_or_error<S: serde::Serializer>(fit: &Result<Fragility, FragilityError>, ser: S) -> Result<S::Ok, S::Error> {
    use serde::Serialize;
    match fit {
        Ok(f) => f.serialize(ser),
        Err(e) => serde_json::json!({ "error": e.to_string() }).serialize(ser),
    }
}

/// Fit a lognormal fragility per coefficient set to sample runs: every run is one
/// Bernoulli trial at the IM it felt.
pub fn fragility_by_set(study: &Study, runs: &[SampleRun]) -> Vec<SetFragility> {
    study
        .sets
        .iter()
        .map(|set| {
            let mine: Vec<&SampleRun> = runs.iter().filter(|r| r.coefficients == set.name).collect();
            let trials: Vec<Trial> = mine
                .iter()
                .map(|r| Trial {
                    im: r.im,
                    n: 1,
                    k: r.outcome.overturned as usize,
                })
                .collect();
            let mut observed: Vec<Trial> = Vec::new();
            let mut keys: Vec<(String, u64)> = mine.iter().map(|r| (r.record.clone(), r.scale.to_bits())).collect();
            keys.sort();
            keys.dedup();
            for (rec, sc) in keys {
                let g: Vec<&&SampleRun> = mine.iter().filter(|r| r.record == rec && r.scale.to_bits() == sc).collect();
                let n = g.len();
                observed.push(Trial {
                    im: g.iter().map(|r| r.im).sum::<f64>() / n as f64,
                    n,
                    k: g.iter().filter(|r| r.outcome.overturned).count(),
                });
            }
            observed.sort_by(|a, b| a.im.total_cmp(&b.im));
            SetFragility {
                coefficients: set.name.clone(),
                fit: fit_lognormal(&trials),
                observed,
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
