//! `rocklab archive add REPORT_DIR… --to ARCHIVE` and `rocklab archive query
//! ARCHIVE "SQL"`: a lab's archive of reduced campaigns (see `rocklab::archive`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Args, Subcommand};

use super::say;

#[derive(Args, Debug)]
pub struct ArchiveArgs {
    #[command(subcommand)]
    command: ArchiveCommand,
}

#[derive(Subcommand, Debug)]
enum ArchiveCommand {
    /// Add reduced campaigns (folders holding summary.json) to an archive; a
    /// reduction of the same manifest (same SHA-256) replaces its rows.
    Add {
        /// Output folders of `rocklab reduce`.
        #[arg(required = true)]
        reports: Vec<PathBuf>,
        /// The archive folder (created): tests.parquet, impacts.parquet, archive.html.
        #[arg(long)]
        to: PathBuf,
    },
    /// Print the answer of a SQL query over the tables `tests` and `impacts`.
    Query {
        /// The archive folder.
        archive: PathBuf,
        /// The query, e.g. "SELECT campaign, avg(r_plus) FROM tests GROUP BY campaign".
        sql: String,
    },
}

pub fn run(args: ArchiveArgs) -> anyhow::Result<ExitCode> {
    match args.command {
        ArchiveCommand::Add { reports, to } => {
            let added = rocklab::archive::add(&to, &reports)?;
            for n in &added.notes {
                eprintln!("note: {n}");
            }
            for (campaign, sha, tests, impacts, replaced) in &added.reductions {
                let what = if *replaced > 0 {
                    format!(", replacing {replaced} earlier rows")
                } else {
                    String::new()
                };
                say(&format!(
                    "added {campaign} (manifest {}…): {tests} tests, {impacts} impacts{what}",
                    &sha[..sha.len().min(12)]
                ));
            }
            say(&format!(
                "{}: {} tests, {} impacts; page {}",
                to.display(),
                added.tests_rows,
                added.impacts_rows,
                to.join("archive.html").display()
            ));
        }
        ArchiveCommand::Query { archive, sql } => {
            let df = rocklab::archive::query(&archive, &sql)?;
            say(&rocklab::archive::show(&df));
        }
    }
    Ok(ExitCode::SUCCESS)
}
