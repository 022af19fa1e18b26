//! The façade study file (README, `fixtures/facade/study.toml`): parsed in two
//! stages, the raw TOML (unknown keys rejected by name) and a validated
//! [`Study`], reading the block file, the records and the calibration files it
//! names (paths relative to the study's folder).

use std::path::Path;

use serde::Deserialize;

use crate::ensemble::{CoefficientDist, Dist, PolarityMode, Uncertainty};
use crate::error::{FileError, FileKind};
use crate::facade::{calibration_set, normal_or_fixed, CoefficientSet, Im, Study, StudyRecord};
use crate::ground_motion::{Format, ReadOptions, Units};
use crate::ingest::text::{parse_toml, read_text};
use crate::limits;
use crate::restitution_law::LawReading;
use crate::solver::BlockSpec;
use crate::wall::housner_e;

type Result<T> = std::result::Result<T, FileError>;

fn bad(path: &Path, msg: impl std::fmt::Display) -> FileError {
    FileError::invalid(path, msg)
}

fn check_e(path: &Path, set: &str, key: &str, e: f64) -> Result<f64> {
    if e > 0.0 && e <= 1.0 {
        Ok(e)
    } else {
        Err(bad(path, format!("[[coefficients]] {set:?}: {key} = {e}: expected 0 < e ≤ 1")))
    }
}

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
    /// With a law: "fit" (default: the parameters' covariance) or "none".
    spread: Option<String>,
    /// A restitution law: a summary.json written by `rocklab reduce` (its
    /// `restitution_law`) or a JSON file holding the law itself.
    law: Option<String>,
    /// e_H the law's r is multiplied by (default: Eq. 2 with the block's α, and
    /// with each sample's α in the ensembles).
    e_h: Option<f64>,
    /// Where the solver reads the law: "amplitude" (default: the apex of the
    /// half-cycle the impact ends) or "speed" (the amplitude of the campaign's
    /// impacts of the impact's speed).
    reading: Option<String>,
}

/// One distribution of `[uncertainty]`: a number (fixed), `{ normal = [mean, sd] }`
/// or `{ uniform = [lo, hi] }`.
fn parse_dist(path: &Path, key: &str, v: &toml::Value) -> Result<Dist> {
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

/// The physical range of an `[uncertainty]` input, when it has one.
fn uncertainty_range(key: &str) -> Option<limits::Range> {
    Some(match key {
        "magnification" => limits::MAGNIFICATION,
        "r_m" | "contact_height_m" => limits::LENGTH_M,
        "alpha_rad" => limits::Range::new(1e-4, 1.5, "rad"),
        "i0_kg_m2" => limits::Range::new(1e-3, 1e13, "kg m²"),
        "unit_stiffness_mn_m2" => limits::STIFFNESS,
        _ => return None,
    })
}

/// A distribution whose support (uniform) or mean (normal) lies in `range`.
fn dist_in_range(path: &Path, key: &str, d: Dist, range: limits::Range) -> Result<()> {
    let ends = match d {
        Dist::Uniform { lo, hi } => vec![lo, hi],
        Dist::Normal { mean, .. } => vec![mean],
        Dist::Fixed { value } => vec![value],
    };
    match ends.iter().find(|v| !range.contains(**v)) {
        Some(v) => Err(bad(
            path,
            format!("[uncertainty].{key}: {}: expected a value {}", limits::show(*v), range.describe()),
        )),
        None => Ok(()),
    }
}

/// `[uncertainty]`: magnification, r_m, alpha_rad, i0_kg_m2, unit_stiffness_mn_m2,
/// contact_height_m; unknown keys are rejected by name.
fn parse_uncertainty(path: &Path, t: &toml::Table, block: &BlockSpec) -> Result<Uncertainty> {
    let mut u = Uncertainty::default();
    for (k, v) in t {
        let d = Some(parse_dist(path, k, v)?);
        if let (Some(dist), Some(range)) = (d, uncertainty_range(k)) {
            dist_in_range(path, k, dist, range)?;
        }
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
fn set_dist(path: &Path, s: &RawSet, e_in: f64, e_out: f64, single: bool) -> Result<CoefficientDist> {
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

/// One `[[coefficients]]` set: given, Housner's Eq. 2 with the block's α, or a
/// calibration file.
fn coefficient_set(path: &Path, base: &Path, s: &RawSet, alpha: f64) -> Result<CoefficientSet> {
    if let Some(file) = s.law.as_deref() {
        return law_set(path, base, s, file, alpha);
    }
    if s.e_h.is_some() {
        return Err(bad(path, format!("[[coefficients]] {:?}: e_h is for a set with a law", s.name)));
    }
    if s.reading.is_some() {
        return Err(bad(path, format!("[[coefficients]] {:?}: reading is for a set with a law", s.name)));
    }
    if s.spread.is_some() && s.calibration.is_none() {
        return Err(bad(
            path,
            format!("[[coefficients]] {:?}: spread is for a set read from a calibration file", s.name),
        ));
    }
    let e_eq2 = housner_e(alpha);
    let (e_in, e_out, source, single) = match (s.e, s.e_in, s.e_out, s.housner.as_deref(), s.calibration.as_deref()) {
        (Some(e), None, None, None, None) => (e, e, "given".to_string(), true),
        (None, Some(i), Some(o), None, None) => (i, o, "given".to_string(), false),
        (None, None, None, Some("eq2"), None) => (e_eq2, e_eq2, format!("Eq. 2 with α = {alpha}"), true),
        (None, None, None, None, Some(file)) => return calibrated_set(path, base, s, file),
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
    Ok(CoefficientSet {
        name: s.name.clone(),
        e_in: check_e(path, &s.name, "e_in", e_in)?,
        e_out: check_e(path, &s.name, "e_out", e_out)?,
        source,
        dist,
    })
}

/// A set with a restitution law read from `file` (a summary.json's
/// `restitution_law`, or the law alone), applied with e_H = `e_h` or Eq. 2.
fn law_set(path: &Path, base: &Path, s: &RawSet, file: &str, alpha: f64) -> Result<CoefficientSet> {
    let named = |msg: String| bad(path, format!("[[coefficients]] {:?}: {msg}", s.name));
    let others = [
        s.e.is_some(),
        s.e_in.is_some(),
        s.e_out.is_some(),
        s.housner.is_some(),
        s.calibration.is_some(),
    ];
    if others.iter().any(|x| *x) || s.sd_e.or(s.sd_e_in).or(s.sd_e_out).is_some() {
        return Err(named(
            "law = FILE takes no e, e_in, e_out, housner, calibration or sd_e* (its spread is the law's covariance: spread = \"fit\" or \"none\")"
                .into(),
        ));
    }
    let drawn = match s.spread.as_deref() {
        None | Some("fit") => true,
        Some("none") => false,
        Some(o) => return Err(named(format!("spread = {o:?}: a law set takes \"fit\" or \"none\""))),
    };
    if let Some(e_h) = s.e_h.filter(|e| !(*e > 0.0 && *e <= 1.0)) {
        return Err(named(format!("e_h = {e_h}: expected 0 < e_H ≤ 1")));
    }
    let reading = match s.reading.as_deref().map(|r| (r, LawReading::parse(r))) {
        None => LawReading::Amplitude,
        Some((_, Some(r))) => r,
        Some((o, None)) => return Err(named(format!("reading = {o:?}: expected \"amplitude\" or \"speed\""))),
    };
    let law = crate::ingest::law::read(&base.join(file))?;
    if reading == LawReading::Speed {
        law.readable_by_speed()
            .map_err(|why| named(format!("reading = \"speed\": law {file}: {why}")))?;
    }
    let e_h = match s.e_h {
        Some(e) => format!("e_H = {e}"),
        None => "e_H by Eq. 2".to_string(),
    };
    let source = format!("law {file} ({}), {e_h}", law.form.as_str());
    Ok(CoefficientSet::law(&s.name, law, s.e_h, alpha, drawn, source).read_by(reading))
}

/// A set read from a calibration file, with the spread it asks for.
fn calibrated_set(path: &Path, base: &Path, s: &RawSet, file: &str) -> Result<CoefficientSet> {
    if s.sd_e.or(s.sd_e_in).or(s.sd_e_out).is_some() {
        return Err(bad(
            path,
            format!(
                "[[coefficients]] {:?}: a calibration set takes its spread from the file (spread = \"tests\", \"mean\" or \"none\"), not sd_e*",
                s.name
            ),
        ));
    }
    let cal = crate::ingest::calibration::read(&base.join(file))?;
    let set = calibration_set(&s.name, file, &cal.calibration, s.spread.as_deref().unwrap_or("tests"))
        .map_err(|e| bad(path, format!("[[coefficients]] {:?}: {e}", s.name)))?;
    check_e(path, &s.name, "e_in", set.e_in)?;
    check_e(path, &s.name, "e_out", set.e_out)?;
    Ok(set)
}

/// Every `[[coefficients]]` set, names unique.
fn coefficient_sets(path: &Path, base: &Path, raw: &[RawSet], alpha: f64) -> Result<Vec<CoefficientSet>> {
    if raw.is_empty() {
        return Err(bad(path, "no [[coefficients]]: expected at least one coefficient set"));
    }
    let sets = raw.iter().map(|s| coefficient_set(path, base, s, alpha)).collect::<Result<Vec<_>>>()?;
    if let Some(dup) = sets.iter().enumerate().find(|(i, a)| sets[..*i].iter().any(|b| b.name == a.name)) {
        return Err(bad(path, format!("[[coefficients]] {:?}: the name is used twice", dup.1.name)));
    }
    Ok(sets)
}

/// Every `[[record]]`, read.
fn records(path: &Path, base: &Path, raw: &[RawRecord]) -> Result<Vec<StudyRecord>> {
    raw.iter()
        .map(|r| {
            let format = Format::from_name(r.format.as_deref().unwrap_or("auto")).map_err(|e| bad(path, format!("[[record]] {:?}: {e}", r.name)))?;
            let units = r
                .units
                .as_deref()
                .map(|u| Units::parse(u).ok_or_else(|| bad(path, format!("[[record]] {:?}: units = {u:?}: expected g, m/s2 or cm/s2", r.name))))
                .transpose()?;
            let record = crate::ingest::record::read(&base.join(&r.file), &ReadOptions { format, dt: r.dt, units })
                .map_err(|e| bad(path, format!("[[record]] {:?}: {e}", r.name)))?;
            Ok(StudyRecord {
                name: r.name.clone(),
                component: r.component.clone(),
                record,
            })
        })
        .collect()
}

/// The `[study]` choices that are names: polarities, the polarity mode, the IM.
fn choices(path: &Path, h: &RawHead) -> Result<(Vec<f64>, PolarityMode, Im)> {
    let polarities = match &h.polarities {
        None => vec![1.0, -1.0],
        Some(p) if !p.is_empty() && p.iter().all(|x| *x == 1 || *x == -1) => p.iter().map(|x| *x as f64).collect(),
        Some(p) => return Err(bad(path, format!("[study].polarities = {p:?}: expected a list of 1 and/or -1"))),
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
    Ok((polarities, polarity_mode, im))
}

/// The `[study]` numbers within their physical ranges ([`crate::limits`]; issue 22:
/// `rtol = 1e-308` ran without end, `rtol = 1e308` failed naming neither file nor key).
fn head_ranges(path: &Path, h: &RawHead) -> Result<()> {
    let check = |key: &str, v: f64, r: limits::Range| r.check(&format!("[study].{key}"), v).map(|_| ()).map_err(|m| bad(path, m));
    check("magnification", h.magnification, limits::MAGNIFICATION)?;
    check("t_extra_s", h.t_extra_s, limits::T_EXTRA_S)?;
    if let Some(r) = h.rtol {
        check("rtol", r, limits::RTOL)?;
    }
    for (key, n) in [("samples", h.samples), ("ida_samples", h.ida_samples)] {
        if let Some(n) = n.filter(|n| *n > limits::MAX_SAMPLES) {
            return Err(bad(path, format!("[study].{key} = {n}: expected at most {}", limits::MAX_SAMPLES)));
        }
    }
    Ok(())
}

/// The reader of a study file (the type is the façade study's).
impl Study {
    /// Read and validate a study file and everything it names.
    pub fn load(path: &Path) -> Result<Study> {
        let text = read_text(path, FileKind::Study)?;
        Self::validate(parse_toml(&text, path)?, path).map_err(|e| e.located(path, &text))
    }

    fn validate(raw: RawStudy, path: &Path) -> Result<Study> {
        let base = path.parent().unwrap_or_else(|| Path::new("."));
        let block = BlockSpec::load(&base.join(&raw.study.block))?;
        let h = &raw.study;
        head_ranges(path, h)?;
        let (polarities, polarity_mode, im) = choices(path, h)?;
        if raw.record.is_empty() {
            return Err(bad(path, "no [[record]]: expected at least one record"));
        }
        let sets = coefficient_sets(path, base, &raw.coefficients, block.block.alpha)?;
        let records = records(path, base, &raw.record)?;
        let overturn_limit = h.overturn_limit_rad.unwrap_or(block.block.alpha);
        limits::ANGLE_RAD
            .check("[study].overturn_limit_rad", overturn_limit)
            .map_err(|m| bad(path, m))?;
        let uncertainty = match &raw.uncertainty {
            Some(t) => parse_uncertainty(path, t, &block)?,
            None => Uncertainty::default(),
        };
        let any_random = !uncertainty.describe().is_empty() || sets.iter().any(|s| s.dist.is_random()) || polarity_mode == PolarityMode::Random;
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
            coefficient_files: raw
                .coefficients
                .iter()
                .filter_map(|s| s.calibration.as_deref().or(s.law.as_deref()))
                .map(|f| base.join(f))
                .collect(),
            e_housner_eq2: housner_e(block.block.alpha),
            block,
        })
    }
}
