//! `rocklab simulate --block BLOCK.toml --record FILE … --out DIR`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::{bail, Context};
use clap::{Args, ValueEnum};

use super::say;
use rocklab::ground_motion::{Format, ReadOptions, Units};
use rocklab::ingest::block::BlockSpec;
use rocklab::report::{docs, response, write_files, Files};
use rocklab::study::{run, RunSpec};

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatArg {
    Auto,
    Esm,
    At2,
    Cosmos,
    TwoColumn,
    OneColumn,
}

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  rocklab simulate --block fixtures/facade/block.toml \\\n    --record fixtures/ground-motions/esm-central-italy-2016/IT.NRC..HGE.D.20161030.064018.C.ACC.ASC \\\n    --scale 1.27 --polarity -1 --e-in 0.59 --e-out 0.68 --out out/nrc"
)]
pub struct SimulateArgs {
    /// Block file (TOML, docs/solver.md).
    #[arg(long)]
    pub block: PathBuf,
    /// Ground-motion record.
    #[arg(long)]
    pub record: PathBuf,
    #[arg(long, value_enum, default_value_t = FormatArg::Auto)]
    pub format: FormatArg,
    /// Time step (s) of a one-column record.
    #[arg(long)]
    pub dt: Option<f64>,
    /// Units of the record: g, m/s2 or cm/s2 (read from the header when it has one).
    #[arg(long)]
    pub units: Option<String>,
    /// Scale factor (magnification; the paper uses 1.27).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Polarity of the record: 1 or -1.
    #[arg(long, default_value_t = 1, allow_negative_numbers = true)]
    pub polarity: i32,
    /// One coefficient of restitution for both sides.
    #[arg(long, conflicts_with_all = ["e_in", "e_out"])]
    pub e: Option<f64>,
    /// Coefficient when entering the inward side.
    #[arg(long, requires = "e_out")]
    pub e_in: Option<f64>,
    /// Coefficient when entering the outward side.
    #[arg(long, requires = "e_in")]
    pub e_out: Option<f64>,
    /// calibration.toml written by `rocklab calibrate` (its e_in and e_out).
    #[arg(long, conflicts_with_all = ["e", "e_in", "e_out"])]
    pub calibration: Option<PathBuf>,
    /// Overturning limit (rad); default α.
    #[arg(long)]
    pub overturn_limit: Option<f64>,
    /// Seconds simulated after the end of the record.
    #[arg(long, default_value_t = 0.0)]
    pub t_extra: f64,
    /// Relative tolerance of the integrator.
    #[arg(long, default_value_t = 1e-8)]
    pub rtol: f64,
    /// Absolute tolerance of the integrator (rad, rad/s).
    #[arg(long, default_value_t = 1e-10)]
    pub atol: f64,
    #[arg(long)]
    pub out: PathBuf,
}

pub fn read_options(format: FormatArg, dt: Option<f64>, units: Option<&str>) -> anyhow::Result<ReadOptions> {
    let format = match format {
        FormatArg::Auto => None,
        FormatArg::Esm => Some(Format::Esm),
        FormatArg::At2 => Some(Format::At2),
        FormatArg::Cosmos => Some(Format::Cosmos),
        FormatArg::TwoColumn => Some(Format::TwoColumn),
        FormatArg::OneColumn => Some(Format::OneColumn),
    };
    let units = units
        .map(|u| Units::parse(u).ok_or_else(|| anyhow::anyhow!("--units {u}: expected g, m/s2 or cm/s2")))
        .transpose()?;
    Ok(ReadOptions { format, dt, units })
}

fn check_e(name: &str, e: f64) -> anyhow::Result<f64> {
    if e > 0.0 && e <= 1.0 {
        Ok(e)
    } else {
        bail!("{name} = {e}: expected 0 < e ≤ 1")
    }
}

/// e_in, e_out from --e or --e-in/--e-out, else the block file's [impact].
fn coefficients_from_args(a: &SimulateArgs, block: &BlockSpec) -> anyhow::Result<(f64, f64)> {
    Ok(match (a.e, a.e_in, a.e_out, block.impact) {
        (Some(e), ..) => (e, e),
        (None, Some(i), Some(o), _) => (i, o),
        (None, None, None, d) => match (d.e, d.e_in, d.e_out) {
            (Some(e), _, _) => (e, e),
            (None, Some(i), Some(o)) => (i, o),
            _ => bail!("no coefficient of restitution: pass --e E, --e-in X --e-out Y or --calibration FILE (or set [impact] in the block file)"),
        },
        _ => bail!("pass --e E, or both --e-in and --e-out"),
    })
}

/// The run's settings from the arguments and the block file's defaults, validated.
fn spec_from_args(a: &SimulateArgs, block: &BlockSpec) -> anyhow::Result<RunSpec> {
    let (e_in, e_out) = match &a.calibration {
        Some(file) => rocklab::ingest::calibration::read_coefficients(file)?,
        None => coefficients_from_args(a, block)?,
    };
    let (e_in, e_out) = (check_e("e_in", e_in)?, check_e("e_out", e_out)?);
    let overturn_limit = a.overturn_limit.or(block.impact.overturn_limit_rad).unwrap_or(block.block.alpha);
    let spec = RunSpec {
        e_in,
        e_out,
        law: None,
        law_reading: Default::default(),
        scale: a.scale,
        polarity: a.polarity as f64,
        overturn_limit,
        t_extra: a.t_extra,
        rtol: a.rtol,
        atol: a.atol,
        keep_history: true,
    };
    spec.check(|key| match key {
        "overturn_limit" => "overturn limit (rad)".into(),
        k => format!("--{}", k.replace('_', "-")),
    })
    .map_err(anyhow::Error::msg)?;
    Ok(spec)
}

pub fn run_cli(a: SimulateArgs) -> anyhow::Result<ExitCode> {
    let block = BlockSpec::load(&a.block)?;
    let record = rocklab::ingest::record::read(&a.record, &read_options(a.format, a.dt, a.units.as_deref())?)?;
    let spec = spec_from_args(&a, &block)?;
    let (summary, sim) = run(&block, &record, &spec)?;
    let alpha = block.block.alpha;
    let mut files = Files::default();
    for input in [Some(&a.block), Some(&a.record), a.calibration.as_ref()].into_iter().flatten() {
        files.input(input);
    }
    let doc = docs::simulate_summary(&block, &a.record.display().to_string(), &record, &spec, &summary, &sim)?;
    files.add("summary.json", serde_json::to_vec_pretty(&doc)?);
    files.add("history.csv", response::history_csv(&sim.history, alpha)?);
    response::simulate_figure(&block.name, &sim.history, alpha, &record, &spec)?.add_to(&mut files, "response");
    write_files(&a.out, &files).with_context(|| format!("writing {}", a.out.display()))?;
    say(&format!(
        "{}: max θ/α = {:.3}, min θ/α = {:.3}, {}, {} impacts, PGA {:.3} g, PGV {:.2} cm/s, solved in {:.2} ms",
        block.name,
        summary.max_theta_over_alpha,
        summary.min_theta_over_alpha,
        match summary.overturn_time_s {
            Some(t) => format!("OVERTURNED at {t:.3} s"),
            None => "stands".into(),
        },
        summary.impacts,
        summary.pga_g,
        summary.pgv_cm_s,
        summary.solve_wall_s * 1e3
    ));
    say(&format!("wrote {}", a.out.display()));
    Ok(ExitCode::SUCCESS)
}
