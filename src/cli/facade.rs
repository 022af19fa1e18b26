//! `rocklab facade STUDY --out DIR [--scales FROM:TO:N]`: load the study, run
//! it (nominal runs, ensembles, IDA, fragility), write the report.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::Context;
use clap::Args;

use super::{load, progress, say};
use rocklab::facade::{fragility_by_set, parse_scales, run_ensembles, run_ida, run_ida_samples, run_study, SampleRun, Study};
use rocklab::report::facade::{ensemble_source, facade_files, ida_source, FacadeResults};
use rocklab::report::write_files;
use rocklab::solver::run::SolverError;

#[derive(Args, Debug)]
pub struct FacadeArgs {
    /// Study file (TOML, see README).
    pub study: PathBuf,
    #[arg(long)]
    pub out: PathBuf,
    /// Incremental dynamic analysis over scale factors FROM:TO:N (×magnification).
    #[arg(long)]
    pub scales: Option<String>,
    #[command(flatten)]
    pub ensemble: EnsembleArgs,
}

/// Ensemble options shared by `facade` and `demo`.
#[derive(Args, Debug, Clone, Default)]
pub struct EnsembleArgs {
    /// Ensemble size per record × coefficient set × polarity (overrides [study].samples; 0: none).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the ensembles (overrides [study].seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Samples per record × polarity × set at each IDA scale (overrides [study].ida_samples).
    #[arg(long)]
    pub ida_samples: Option<usize>,
}

impl EnsembleArgs {
    /// Sizes within [`rocklab::limits::MAX_SAMPLES`] (issue 22: ensembles bounded).
    pub fn check(&self) -> anyhow::Result<()> {
        for (flag, n) in [("--samples", self.samples), ("--ida-samples", self.ida_samples)] {
            if let Some(n) = n.filter(|n| *n > rocklab::limits::MAX_SAMPLES) {
                anyhow::bail!("{flag} {n}: expected at most {}", rocklab::limits::MAX_SAMPLES);
            }
        }
        Ok(())
    }
    pub fn apply(&self, study: &mut Study) {
        if let Some(n) = self.samples {
            study.samples = n;
        }
        if let Some(s) = self.seed {
            study.seed = s;
        }
        if let Some(n) = self.ida_samples {
            study.ida_samples = n.max(1);
        }
    }
}

pub fn run(a: FacadeArgs) -> anyhow::Result<ExitCode> {
    let mut study = Study::load(&a.study)?;
    a.ensemble.check()?;
    a.ensemble.apply(&mut study);
    let scales = a.scales.as_deref().map(parse_scales).transpose()?;
    run_and_write(&study, scales.as_deref(), &a.out)?;
    Ok(ExitCode::SUCCESS)
}

/// The whole study (shared with `demo`): load the inputs' facts, run, write.
pub fn run_and_write(study: &Study, scales: Option<&[f64]>, out: &Path) -> anyhow::Result<()> {
    let inputs = load::study_inputs(study);
    let results = compute(study, scales)?;
    let (files, md) = facade_files(study, &results, &inputs)?;
    write_files(out, &files).with_context(|| format!("writing {}", out.display()))?;
    say(&md);
    say(&format!("wrote {}", out.display()));
    Ok(())
}

/// The core step: the nominal runs at scale 1, the ensembles (when `samples` > 0),
/// the IDA (with `scales`) and the fragility fits, with progress on the terminal.
fn compute(study: &Study, scales: Option<&[f64]>) -> Result<FacadeResults, SolverError> {
    let start = Instant::now();
    let pb = progress(study.combinations().len(), "façade runs");
    let runs = run_study(study, 1.0, true, &|| pb.inc(1))?;
    pb.finish_and_clear();
    say(&format!(
        "{} nominal runs (each at 3 tolerances) in {:.2} s",
        runs.len(),
        start.elapsed().as_secs_f64()
    ));
    let ensemble = (study.samples > 0).then(|| ensembles(study)).transpose()?;
    let ens_samples = ensemble.as_ref().map_or(&[][..], |e| e.1.as_slice());
    let drawn = fragility_samples(study, scales, ens_samples)?;
    let fragility_wall_s = drawn.as_ref().and_then(|d| d.wall_s);
    let fragility = drawn.map(|d| (d.source, fragility_by_set(study, &d.samples)));
    let ida = scales.map(|sc| ida(study, sc).map(|pts| (sc.to_vec(), pts))).transpose()?;
    Ok(FacadeResults {
        runs,
        ensemble,
        fragility,
        fragility_wall_s,
        ida,
        wall_s: start.elapsed().as_secs_f64(),
    })
}

fn ensembles(study: &Study) -> Result<(Vec<rocklab::facade::EnsembleRow>, Vec<SampleRun>), SolverError> {
    let n = study.samples;
    let pb = progress(study.records.len() * study.rows().len() * study.sets.len() * n, "ensemble runs");
    let start = Instant::now();
    let (rows, samples) = run_ensembles(study, n, &|| pb.inc(1))?;
    pb.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    say(&format!(
        "{} ensemble runs in {wall:.2} s ({:.2} ms per run)",
        samples.len(),
        1e3 * wall / samples.len().max(1) as f64
    ));
    Ok((rows, samples))
}

/// The runs the fragility is fitted to, where they come from, and how long they
/// took when they were run for it.
struct FragilityRuns {
    source: String,
    samples: Vec<SampleRun>,
    wall_s: Option<f64>,
}

/// The runs the fragility is fitted to, and where they come from: an IDA over
/// `scales` (with the study's IDA samples), else the scale-1 ensembles when there
/// are two records or more.
fn fragility_samples(study: &Study, scales: Option<&[f64]>, ens_samples: &[SampleRun]) -> Result<Option<FragilityRuns>, SolverError> {
    if let Some(sc) = scales {
        let n = study.ida_samples;
        let pb = progress(
            sc.len() * study.records.len() * study.rows().len() * study.sets.len() * n,
            "fragility runs",
        );
        let start = Instant::now();
        let samples = run_ida_samples(study, sc, n, &|| pb.inc(1))?;
        pb.finish_and_clear();
        let wall = start.elapsed().as_secs_f64();
        say(&format!("{} fragility runs in {wall:.2} s", samples.len()));
        Ok(Some(FragilityRuns {
            source: ida_source(sc, n, samples.len()),
            samples,
            wall_s: Some(wall),
        }))
    } else if !ens_samples.is_empty() && study.records.len() >= 2 {
        Ok(Some(FragilityRuns {
            source: ensemble_source(ens_samples.len(), study.records.len()),
            samples: ens_samples.to_vec(),
            wall_s: None,
        }))
    } else {
        Ok(None)
    }
}

/// The IDA: every combination at every scale.
fn ida(study: &Study, scales: &[f64]) -> Result<Vec<rocklab::facade::IdaPoint>, SolverError> {
    let pb = progress(scales.len() * study.combinations().len(), "IDA runs");
    let start = Instant::now();
    let pts = run_ida(study, scales, &|| pb.inc(1))?;
    pb.finish_and_clear();
    say(&format!(
        "IDA: {} runs ({} scales × {} combinations) in {:.2} s",
        pts.len(),
        scales.len(),
        study.combinations().len(),
        start.elapsed().as_secs_f64()
    ));
    Ok(pts)
}
