//! The façade study (paper §5): one block, several records, several coefficient
//! sets, both polarities; optionally over a range of scale factors (incremental
//! dynamic analysis). The study file format is documented in docs/facade.md and in
//! `fixtures/facade/study.toml`. A set is a constant pair (e_in, e_out) or a
//! campaign's restitution law, applied at each impact at the apex of the
//! half-cycle it ends ([`crate::solver::impact`]).

use std::path::PathBuf;

use rayon::prelude::*;

use crate::calibrate::CalibrationValues;
use crate::ensemble::{self, CoefficientDist, Dist, Inputs, Nominal, Outcome, PolarityMode, SampleKey, Uncertainty};
use crate::fragility::{fit_lognormal, Fragility, FragilityError, Trial};
use crate::ground_motion::Record;
use crate::restitution_law::{LawReading, RestitutionLaw};
use crate::solver::run::{Event, SolverError};
use crate::solver::BlockSpec;
use crate::study::{run, RunSpec, RunSummary};
use crate::wall::{housner_e, Rocking, Side};

/// A coefficient set of the study: a pair (e_in, e_out), or a restitution law
/// (`dist` is [`CoefficientDist::Law`]; e_in and e_out are then its e at a = 1).
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

/// A validated study (read from its file by `rocklab::ingest::study`).
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
    /// The files the sets were read from (`calibration = FILE`, `law = FILE`),
    /// resolved against the study's folder: inputs no output may replace.
    pub coefficient_files: Vec<PathBuf>,
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

/// The coefficient set of a calibration: normal spreads of e_in and e_out as
/// `spread` says: "tests" (√(sd_tests² + se_fit²): how e varies from one
/// wall or test to the next, plus the fits' own error), "mean" (the standard error
/// of the means) or "none".
pub fn calibration_set(name: &str, file: &str, cal: &CalibrationValues, spread: &str) -> Result<CoefficientSet, SpreadError> {
    let (sd_in, sd_out) = match (spread, cal.spread.as_ref().map(|t| &t.spread)) {
        ("none", _) => (0.0, 0.0),
        (_, None) => return Err(SpreadError::Missing { file: file.to_string() }),
        ("tests", Some(sp)) => (sp.sd_e_in_tests.hypot(sp.se_e_in_fit), sp.sd_e_out_tests.hypot(sp.se_e_out_fit)),
        ("mean", Some(sp)) => (sp.se_e_in_mean, sp.se_e_out_mean),
        (other, _) => return Err(SpreadError::Unknown(other.to_string())),
    };
    let single = cal.rocking == Some(Rocking::TwoSided);
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

/// Why a calibration set has no spread.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SpreadError {
    #[error("calibration {file} has no [calibration.spread] (written by an older rocklab): re-run calibrate, or set spread = \"none\"")]
    Missing { file: String },
    #[error("spread = {0:?}: expected \"tests\", \"mean\" or \"none\"")]
    Unknown(String),
}

impl CoefficientSet {
    /// A set that applies a restitution law: e = min(1, r(side, a)·e_H) with e_H
    /// as given, else Eq. 2 with the block's α (`alpha`); its parameters drawn
    /// from their covariance in the ensembles when `drawn`.
    pub fn law(name: &str, law: RestitutionLaw, e_housner: Option<f64>, alpha: f64, drawn: bool, source: String) -> CoefficientSet {
        let e_h = e_housner.unwrap_or_else(|| housner_e(alpha));
        CoefficientSet {
            name: name.to_string(),
            e_in: law.e(Side::Inward, 1.0, e_h),
            e_out: law.e(Side::Outward, 1.0, e_h),
            source,
            dist: CoefficientDist::Law {
                law,
                e_housner,
                drawn,
                reading: LawReading::Amplitude,
            },
        }
    }

    /// The same law set read as `reading` says, its source saying so where it is
    /// read by speed (a pair is left as it is).
    pub fn read_by(mut self, reading: LawReading) -> CoefficientSet {
        if let CoefficientDist::Law { reading: r, .. } = &mut self.dist {
            if reading == LawReading::Speed && *r != reading {
                self.source.push_str(", read by the impact's speed");
            }
            *r = reading;
        }
        self
    }

    /// How a law set reads its law (a pair: by amplitude, which it ignores).
    pub fn law_reading(&self) -> LawReading {
        match self.dist {
            CoefficientDist::Law { reading, .. } => reading,
            _ => LawReading::Amplitude,
        }
    }

    /// The law of a law set and the e_H it is applied with on a block of
    /// slenderness `alpha` (None: a constant pair).
    pub fn law_at(&self, alpha: f64) -> Option<(RestitutionLaw, f64)> {
        match self.dist {
            CoefficientDist::Law { law, e_housner, .. } => Some((law, e_housner.unwrap_or_else(|| housner_e(alpha)))),
            _ => None,
        }
    }
}

/// N(mean, sd), or the fixed mean when sd is 0 or not finite.
pub fn normal_or_fixed(mean: f64, sd: f64) -> Dist {
    if sd > 0.0 && sd.is_finite() {
        Dist::Normal { mean, sd }
    } else {
        Dist::Fixed { value: mean }
    }
}

impl Study {
    fn spec(&self, set: &CoefficientSet, polarity: f64, scale: f64, rtol: f64, history: bool) -> RunSpec {
        RunSpec {
            e_in: set.e_in,
            e_out: set.e_out,
            law: set.law_at(self.block.block.alpha),
            law_reading: set.law_reading(),
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
    /// A law set's run: where its impacts fell against the law's data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub law_reach: Option<LawReach>,
    #[serde(skip)]
    pub history: Vec<crate::solver::run::Sample>,
}

/// Run the combinations at one scale (with histories for the plots when asked),
/// each at three tolerances; `tick` is called after each combination.
pub fn run_study(study: &Study, scale: f64, with_history: bool, tick: &(dyn Fn() + Sync)) -> Result<Vec<StudyRun>, SolverError> {
    study
        .combinations()
        .par_iter()
        .map(|&(r, s, p)| {
            let rec = &study.records[r];
            let set = &study.sets[s];
            let spec = study.spec(set, p, scale, study.rtol, with_history);
            let (sum, sim) = run(&study.block, &rec.record, &spec)?;
            let law_reach = spec.law.map(|(law, e_h)| law_reach(&sim.events, &law, e_h));
            let loose = run(&study.block, &rec.record, &study.spec(set, p, scale, study.rtol * 100.0, false))?.0;
            let tight = run(&study.block, &rec.record, &study.spec(set, p, scale, study.rtol / 100.0, false))?.0;
            let close = |o: &RunSummary| {
                o.overturned == sum.overturned
                    && (o.max_theta_over_alpha - sum.max_theta_over_alpha).abs() <= 0.05 * sum.max_theta_over_alpha.abs().max(0.05)
            };
            tick();
            Ok(StudyRun {
                record: rec.name.clone(),
                coefficients: set.name.clone(),
                polarity: p as i8,
                scale,
                well_conditioned: close(&loose) && close(&tight),
                sensitivity: [loose.max_theta_over_alpha, tight.max_theta_over_alpha],
                law_reach,
                summary: sum,
                history: sim.history,
            })
        })
        .collect()
}

/// The impacts of one side in a run, against a law's data (see [`LawReach`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct SideReach {
    /// Impacts entering the side.
    pub impacts: usize,
    /// Of them, those that ended a half-cycle smaller than any the campaign
    /// observed on the side (a below [`RestitutionLaw::observed`]'s smallest):
    /// the law's form (extrapolated, or held), not its data, gave their r.
    pub below_observed: usize,
    /// Of them, those that ended a half-cycle larger than any the campaign
    /// observed on the side.
    pub above_observed: usize,
    /// Of them, those whose e = min(1, r(a) e_H) is the cap 1 (an elastic impact).
    pub elastic: usize,
    /// Σ θ'² before the impacts ((rad/s)²: proportional to the kinetic energy
    /// they met), over all of them and over those below and above the data.
    pub energy: f64,
    pub energy_below: f64,
    pub energy_above: f64,
    /// Σ θ'² e over the impacts: with `energy`, the coefficient the side's
    /// impacts applied, weighted by the energy they met.
    pub energy_e: f64,
    /// The smallest and largest a = |θ|/α at which one of them read the law
    /// (0 and 0 without impacts).
    pub smallest_amplitude: f64,
    pub largest_amplitude: f64,
}

/// Where a law set's impacts fell in a run: per side, how many read the law
/// below or above the amplitudes the campaign observed there, and how many at
/// the cap e = 1. A verdict that rests on such impacts rests on the law's
/// extrapolation; the façade report says how many there were
/// (docs/facade.md, "Where the laws reach beyond their data").
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize)]
pub struct LawReach {
    pub inward: SideReach,
    pub outward: SideReach,
}

impl SideReach {
    /// The energy-weighted mean e of the side's impacts (None without impacts).
    pub fn mean_e(&self) -> Option<f64> {
        (self.energy > 0.0).then(|| self.energy_e / self.energy)
    }
}

impl LawReach {
    /// The largest share, over the two sides, of the kinetic energy the
    /// impacts met that was met beyond the law's data (0 without impacts).
    pub fn beyond_share(&self) -> f64 {
        [&self.inward, &self.outward]
            .iter()
            .filter(|x| x.energy > 0.0)
            .map(|x| (x.energy_below + x.energy_above) / x.energy)
            .fold(0.0, f64::max)
    }

    /// Add another run's counts (the amplitudes' range is the union).
    pub fn add(&mut self, other: &LawReach) {
        for (a, b) in [(&mut self.inward, &other.inward), (&mut self.outward, &other.outward)] {
            if b.impacts == 0 {
                continue;
            }
            a.smallest_amplitude = if a.impacts == 0 {
                b.smallest_amplitude
            } else {
                a.smallest_amplitude.min(b.smallest_amplitude)
            };
            a.largest_amplitude = a.largest_amplitude.max(b.largest_amplitude);
            a.impacts += b.impacts;
            a.below_observed += b.below_observed;
            a.above_observed += b.above_observed;
            a.elastic += b.elastic;
            a.energy += b.energy;
            a.energy_below += b.energy_below;
            a.energy_above += b.energy_above;
            a.energy_e += b.energy_e;
        }
    }
}

/// Count a run's impacts ([`Event::Impact`], each with the amplitude a its
/// coefficient was read at: the apex's, or the speed's where the set reads its
/// law by speed) against `law` applied with `e_h`.
pub fn law_reach(events: &[Event], law: &RestitutionLaw, e_h: f64) -> LawReach {
    let mut reach = LawReach::default();
    for ev in events {
        if let Event::Impact {
            entering,
            law_amplitude_over_alpha: a,
            v_before,
            ..
        } = *ev
        {
            let side = match entering {
                Side::Inward => &mut reach.inward,
                Side::Outward => &mut reach.outward,
            };
            let (lo, hi) = law.observed(entering);
            side.smallest_amplitude = if side.impacts == 0 { a } else { side.smallest_amplitude.min(a) };
            side.largest_amplitude = side.largest_amplitude.max(a);
            side.impacts += 1;
            let (k, e) = (v_before * v_before, law.e(entering, a, e_h));
            side.energy += k;
            side.energy_e += k * e;
            side.elastic += usize::from(e >= 1.0);
            if a < lo {
                side.below_observed += 1;
                side.energy_below += k;
            }
            if a > hi {
                side.above_observed += 1;
                side.energy_above += k;
            }
        }
    }
    reach
}

/// A `--scales` text that is not FROM:TO:N.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("--scales {0}: expected FROM:TO:N with 0.001 ≤ FROM < TO ≤ 100 and 2 ≤ N ≤ 1000 (e.g. 0.1:2.0:50)")]
pub struct ScalesError(pub String);

/// Scale factors FROM:TO:N (inclusive, N ≥ 2).
pub fn parse_scales(s: &str) -> Result<Vec<f64>, ScalesError> {
    let parts: Vec<&str> = s.split(':').collect();
    let err = || ScalesError(crate::error::excerpt(s, 60));
    if parts.len() != 3 {
        return Err(err());
    }
    let from: f64 = parts[0].parse().map_err(|_| err())?;
    let to: f64 = parts[1].parse().map_err(|_| err())?;
    let n: usize = parts[2].parse().map_err(|_| err())?;
    let m = crate::limits::MAGNIFICATION;
    if !(m.contains(from) && m.contains(to) && to > from && (2..=crate::limits::MAX_SCALES).contains(&n)) {
        return Err(err());
    }
    Ok((0..n).map(|i| from + (to - from) * i as f64 / (n - 1) as f64).collect())
}

/// A list of scale factors given as numbers (Python): at most
/// [`crate::limits::MAX_SCALES`], each within [`crate::limits::MAGNIFICATION`],
/// as [`parse_scales`] allows on the command line.
pub fn check_scale_list(scales: &[f64]) -> Result<(), String> {
    if scales.len() > crate::limits::MAX_SCALES {
        return Err(format!("{} scales: expected at most {}", scales.len(), crate::limits::MAX_SCALES));
    }
    for (i, &sc) in scales.iter().enumerate() {
        crate::limits::MAGNIFICATION.check(&format!("scales[{i}]"), sc)?;
    }
    Ok(())
}

/// An ensemble's size `n` (samples per row) within [`crate::limits::MAX_SAMPLES`].
pub fn check_samples(name: &str, n: usize) -> Result<(), String> {
    if n > crate::limits::MAX_SAMPLES {
        return Err(format!("{name} = {n}: expected at most {}", crate::limits::MAX_SAMPLES));
    }
    Ok(())
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
pub fn run_ida(study: &Study, scales: &[f64], tick: &(dyn Fn() + Sync)) -> Result<Vec<IdaPoint>, SolverError> {
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
            let (sum, _) = run(&study.block, &rec.record, &study.spec(set, p, sc, study.rtol, false))?;
            tick();
            Ok(IdaPoint {
                record: rec.name.clone(),
                coefficients: set.name.clone(),
                polarity: p as i8,
                scale: sc,
                max_theta_over_alpha: sum.max_theta_over_alpha,
                overturned: sum.overturned,
            })
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
    /// A law set's sample: where its impacts fell against the law's data
    /// (summed into its ensemble row; not written per sample).
    #[serde(skip)]
    pub law_reach: Option<LawReach>,
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
    /// A law set's row: [`LawReach`] summed over its samples, whose drawn
    /// inputs (the restraint's contact height, I₀, α) move its impacts'
    /// amplitudes against the law's data.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub law_reach: Option<LawReach>,
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

    fn run_sample(&self, job: Job, i: usize, ims: &[f64]) -> Result<SampleRun, SolverError> {
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
            law: x.law,
            law_reading: set.law_reading(),
            scale: x.magnification * job.scale,
            polarity: x.polarity,
            overturn_limit: self.overturn_limit_given.unwrap_or(x.alpha),
            t_extra: self.t_extra,
            rtol: self.rtol,
            atol: self.rtol * 1e-2,
            keep_history: false,
        };
        let (sum, sim) = run(&block, &rec.record, &spec)?;
        let law_reach = spec.law.map(|(law, e_h)| law_reach(&sim.events, &law, e_h));
        Ok(SampleRun {
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
            law_reach,
        })
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
    fn run_jobs(&self, jobs: &[Job], n: usize, tick: &(dyn Fn() + Sync)) -> Result<Vec<SampleRun>, SolverError> {
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
pub fn run_ensembles(study: &Study, n: usize, tick: &(dyn Fn() + Sync)) -> Result<(Vec<EnsembleRow>, Vec<SampleRun>), SolverError> {
    let jobs = jobs_at(study, 0, 1.0);
    let samples = study.run_jobs(&jobs, n, tick)?;
    let rows = samples
        .chunks(n.max(1))
        .zip(&jobs)
        .map(|(chunk, j)| EnsembleRow {
            record: study.records[j.record].name.clone(),
            coefficients: study.sets[j.set].name.clone(),
            polarity: j.row.map(|p| p as i8),
            stats: ensemble::summarise(&chunk.iter().map(|s| s.outcome).collect::<Vec<_>>()),
            law_reach: chunk.iter().filter_map(|s| s.law_reach).reduce(|mut a, b| {
                a.add(&b);
                a
            }),
        })
        .collect();
    Ok((rows, samples))
}

/// IDA with ensembles: `n` samples per record × polarity row × set at each scale
/// (scale indices 1, 2, … so that no stream is shared with the scale-1 ensemble).
pub fn run_ida_samples(study: &Study, scales: &[f64], n: usize, tick: &(dyn Fn() + Sync)) -> Result<Vec<SampleRun>, SolverError> {
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
    /// A law set's fragility: [`LawReach`] summed over every run it was fitted
    /// to, the IDA's scales included, where the larger scales rock the façade
    /// beyond the amplitudes the campaign observed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub law_reach: Option<LawReach>,
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
                let group: Vec<&&SampleRun> = mine.iter().filter(|r| r.record == rec && r.scale.to_bits() == sc).collect();
                let n = group.len();
                observed.push(Trial {
                    im: group.iter().map(|r| r.im).sum::<f64>() / n as f64,
                    n,
                    k: group.iter().filter(|r| r.outcome.overturned).count(),
                });
            }
            observed.sort_by(|a, b| a.im.total_cmp(&b.im));
            SetFragility {
                coefficients: set.name.clone(),
                fit: fit_lognormal(&trials),
                observed,
                law_reach: mine.iter().filter_map(|r| r.law_reach).reduce(|mut a, b| {
                    a.add(&b);
                    a
                }),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The counts of [`law_reach`] on made-up impacts against a law observed on
    /// a = 0.01–0.2 inward and 0.005–0.03 outward: below, inside and above each
    /// range, one capped at e = 1, with their energies and mean e.
    #[test]
    fn law_reach_counts_impacts_beyond_the_data() {
        use crate::restitution_law::{LawForm, ObservedAmplitudes};
        let mut law = RestitutionLaw::constant(0.6, 0.01, 0.8, 0.01);
        law.form = LawForm::SpeedLoss;
        law.parameters.inward.c = 0.01; // r = 0.6 − 0.01/√(a(2 − a)): 0.556 at a = 0.03
        law.parameters.outward.r_inf = 1.1; // e = 1 at every a with e_H = 0.95
        law.parameters.observed = Some(ObservedAmplitudes {
            inward: [0.01, 0.2],
            outward: [0.005, 0.03],
        });
        law.validate().unwrap();
        let imp = |entering, v_before: f64, a| Event::Impact {
            t: 0.0,
            entering,
            v_before,
            v_after: 0.0,
            amplitude_over_alpha: a,
            law_amplitude_over_alpha: a,
        };
        let events = [
            imp(Side::Inward, 1.0, 0.001),
            imp(Side::Inward, 2.0, 0.03),
            imp(Side::Inward, 3.0, 0.5),
            Event::Rest { t: 1.0 },
            imp(Side::Outward, 1.0, 0.01),
            imp(Side::Outward, 1.0, 0.002),
        ];
        let r = law_reach(&events, &law, 0.95);
        let (i, o) = (r.inward, r.outward);
        assert_eq!((i.impacts, i.below_observed, i.above_observed, i.elastic), (3, 1, 1, 0));
        assert_eq!((i.energy, i.energy_below, i.energy_above), (14.0, 1.0, 9.0));
        assert_eq!((i.smallest_amplitude, i.largest_amplitude), (0.001, 0.5));
        let e = |a| law.e(Side::Inward, a, 0.95);
        let mean = (e(0.001) + 4.0 * e(0.03) + 9.0 * e(0.5)) / 14.0;
        assert!((i.mean_e().unwrap() - mean).abs() < 1e-15);
        assert_eq!((o.impacts, o.below_observed, o.above_observed, o.elastic), (2, 1, 0, 2));
        assert_eq!(o.mean_e(), Some(1.0));
        // Adding runs adds the counts and widens the range.
        let mut sum = LawReach::default();
        sum.add(&r);
        sum.add(&law_reach(&events[4..5], &law, 0.95));
        assert_eq!((sum.outward.impacts, sum.outward.below_observed, sum.inward.impacts), (3, 1, 3));
        assert_eq!((sum.outward.smallest_amplitude, sum.outward.largest_amplitude), (0.002, 0.01));
        assert_eq!(LawReach::default().inward.mean_e(), None);
    }

    #[test]
    fn scales() {
        assert_eq!(parse_scales("0.5:1.5:3").unwrap(), vec![0.5, 1.0, 1.5]);
        for bad in ["1:0.5:3", "0.5:1", "a:b:c", "0:1:3", "0.1:1:1"] {
            assert!(parse_scales(bad).is_err(), "{bad}");
        }
    }
}
