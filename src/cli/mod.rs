//! Command line: what the user typed (clap), turned into validated settings; one
//! file per subcommand, each a `run(args) -> Result<ExitCode>`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Parser, Subcommand, ValueEnum};

mod archive;
mod calibrate;
mod demo;
mod facade;
mod init;
mod load;
mod reduce;
mod simulate;

#[derive(Parser, Debug)]
#[command(
    name = "rocklab",
    version,
    about = "Coefficients of restitution of rocking masonry walls from free-vibration tests (Giresini & Croce, COMPDYN 2021)",
    after_help = "Examples:\n  rocklab demo                                   # everything on the shipped fixtures → reports/demo/\n  rocklab init lab/wall-A                        # draft lab/wall-A/campaign.toml from its logs\n  rocklab reduce lab/wall-A/campaign.toml --out out/wall-A\n  rocklab calibrate lab/wall-A/campaign.toml --out out/wall-A-cal\n\nEach command's own example: rocklab help COMMAND. Documentation: README.md and docs/."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Draft DIR/campaign.toml for a folder of logs: tests, columns, units, format detected.
    Init(init::InitArgs),
    /// Reduce a free-vibration campaign: peaks, Eq. 3/4 coefficients, Tables 1–3, plots.
    Reduce(ReduceArgs),
    /// Fit e_in/e_out by replaying each test with the solver.
    Calibrate(calibrate::CalibrateArgs),
    /// Rocking response of a block to a ground-motion record (paper Eq. 1).
    Simulate(simulate::SimulateArgs),
    /// Façade study: coefficient sets × records × polarities (and scales).
    Facade(facade::FacadeArgs),
    /// A lab's archive of reduced campaigns: add reductions, query them with SQL.
    Archive(archive::ArchiveArgs),
    /// Reduce the fixture campaigns shipped in `fixtures/` into `reports/demo/`.
    Demo(DemoArgs),
}

#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum MethodArg {
    /// Impact-resolved fit of the free-rocking solution (default, no impact bias).
    Segments,
    /// Savitzky–Golay derivative and peak picking (classic, biased low at impacts).
    Savgol,
}

#[derive(Args, Debug, Clone)]
pub struct EstimatorArgs {
    /// Velocity-peak estimator.
    #[arg(long, value_enum, default_value_t = MethodArg::Segments)]
    pub method: MethodArg,
    /// Savitzky–Golay window (odd, samples), with --method savgol.
    #[arg(long, default_value_t = 11)]
    pub window: usize,
    /// Savitzky–Golay polynomial order, with --method savgol.
    #[arg(long, default_value_t = 3)]
    pub order: usize,
    /// Skip the PNG/SVG plots (faster on large campaigns).
    #[arg(long)]
    pub no_plots: bool,
}

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  rocklab reduce fixtures/campaigns/one-sided-demo/campaign.toml --out out/one-sided\n  # Tables 1–3, plots, summary.json and report.html in out/one-sided"
)]
pub struct ReduceArgs {
    /// Campaign manifest (TOML; docs/reduce.md; `rocklab init` drafts one), or the
    /// directory that holds it as `campaign.toml`.
    pub manifest: PathBuf,
    /// Output folder (created; files in it are replaced atomically).
    #[arg(long)]
    pub out: PathBuf,
    #[command(flatten)]
    pub estimator: EstimatorArgs,
}

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  rocklab demo                       # the fixture campaigns and the façade study → reports/demo/\n  rocklab demo --samples 20 --out /tmp/demo   # a quicker run"
)]
pub struct DemoArgs {
    /// Fixtures folder holding `campaigns/`.
    #[arg(long, default_value = "fixtures")]
    pub fixtures: PathBuf,
    /// Output folder.
    #[arg(long, default_value = "reports/demo")]
    pub out: PathBuf,
    /// Scale factors of the façade's fragility IDA, FROM:TO:N (× the magnification).
    #[arg(long, default_value = "0.2:2.0:10")]
    pub scales: String,
    #[command(flatten)]
    pub ensemble: facade::EnsembleArgs,
}

pub fn run() -> anyhow::Result<ExitCode> {
    let cli = Cli::parse();
    let out = match &cli.command {
        Command::Reduce(a) => Some(&a.out),
        Command::Simulate(a) => Some(&a.out),
        Command::Facade(a) => Some(&a.out),
        Command::Calibrate(a) => Some(&a.out),
        Command::Demo(a) => Some(&a.out),
        Command::Init(_) | Command::Archive(_) => None,
    };
    if let Some(out) = out {
        check_out(out)?;
    }
    match cli.command {
        Command::Init(a) => init::run(a),
        Command::Reduce(a) => reduce::run(a),
        Command::Simulate(a) => simulate::run_cli(a),
        Command::Facade(a) => facade::run(a),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Archive(a) => archive::run(a),
    }
}

/// Refuse an output folder that is a file before any work is done (the writer
/// would refuse it too, but only after a reduction or a study of minutes).
fn check_out(out: &std::path::Path) -> anyhow::Result<()> {
    let existing = out.ancestors().filter(|a| !a.as_os_str().is_empty()).find(|a| a.exists());
    match existing {
        Some(at) if !at.is_dir() => anyhow::bail!(
            "--out {}: {} is a file, not a folder (the outputs are several files: name a folder, new or existing)",
            out.display(),
            at.display()
        ),
        _ => Ok(()),
    }
}

/// Print a line to stdout; a closed pipe (`rocklab … | head`) is not an error.
pub fn say(line: &str) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    let _ = writeln!(out, "{line}");
}

/// Print a line to stderr, cut at 4,000 characters (issue 22: a message may quote
/// an input's path or id, of any length).
pub fn tell(line: &str) {
    eprintln!("{}", rocklab::error::excerpt_text(line, 4000));
}

/// A progress bar on stderr when it is a terminal; hidden otherwise (pipes, CI).
pub fn progress(n: usize, what: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(n as u64);
    pb.set_style(
        indicatif::ProgressStyle::with_template("{msg} [{bar:40}] {pos}/{len} ({eta})").unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    pb.set_message(what.to_string());
    pb
}
