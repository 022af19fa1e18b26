//! `rocklab init DIR`: draft `DIR/campaign.toml` from the logs in `DIR`
//! ([`rocklab::ingest::scaffold`]); never over an existing manifest without
//! `--force`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context;
use clap::Args;
use rocklab::ingest::scaffold::{manifest_text, survey_dir, FILL_IN};
use rocklab::report::{write_files, Files};

use super::say;

#[derive(Args, Debug)]
#[command(
    after_help = "Example:\n  rocklab init lab/wall-A          # writes lab/wall-A/campaign.toml\n  # fill in the values marked \"fill in\", then:\n  rocklab reduce lab/wall-A/campaign.toml --out out/wall-A"
)]
pub struct InitArgs {
    /// Folder of displacement logs (text: .csv, .txt, .tsv, .dat, .asc).
    pub dir: PathBuf,
    /// Replace an existing DIR/campaign.toml.
    #[arg(long)]
    pub force: bool,
}

pub fn run(a: InitArgs) -> anyhow::Result<ExitCode> {
    let path = a.dir.join("campaign.toml");
    if path.exists() && !a.force {
        anyhow::bail!(
            "{} exists: `rocklab init` does not replace a manifest (move it away, or pass --force)",
            path.display()
        );
    }
    let (logs, skipped) = survey_dir(&a.dir).with_context(|| format!("reading the folder {}", a.dir.display()))?;
    if logs.is_empty() {
        let why = skipped.iter().map(|s| format!("\n  {}: {}", s.file, s.reason)).collect::<String>();
        anyhow::bail!(
            "{}: no text log to draft a campaign from (.csv, .txt, .tsv, .dat, .asc){why}",
            a.dir.display()
        );
    }
    let name = a
        .dir
        .canonicalize()
        .ok()
        .and_then(|d| d.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "campaign".into());
    let text = manifest_text(&name, &logs, &skipped);
    let mut files = Files::default();
    files.add("campaign.toml", text.as_bytes());
    write_files(&a.dir, &files).with_context(|| format!("writing {}", path.display()))?;
    say(&format!("wrote {} ({} tests)", path.display(), logs.len()));
    for s in &skipped {
        say(&format!("  not drafted: {}: {}", s.file, s.reason));
    }
    let to_fill = text
        .lines()
        .filter(|l| !l.trim_start().starts_with('#') && l.contains(&format!("\"{FILL_IN}")))
        .count();
    say(&format!(
        "{to_fill} value(s) to fill in (marked \"{FILL_IN}\"), then: rocklab reduce {} --out OUT",
        path.display()
    ));
    Ok(ExitCode::SUCCESS)
}
