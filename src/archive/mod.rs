//! A lab's archive of reduced campaigns: `ARCHIVE/tests.parquet` (one row per test)
//! and `ARCHIVE/impacts.parquet` (one row per impact), built from the reductions'
//! `summary.json` and queried with SQL, on polars (lazy Parquet scans, its SQL
//! context). Rows are keyed by the manifest's SHA-256: adding a reduction again
//! replaces its rows. `ARCHIVE/archive.html` plots every campaign's r⁺ and r⁻.
//!
//! Writes are atomic across the two files. A change is first written, each file
//! atomically, into `ARCHIVE/.pending/`, and committed by writing the marker
//! `.pending/COMMIT` (the commit point); the files are then renamed into place and
//! `.pending` removed. Whoever opens the archive next (add, query, the Python
//! binding through [`recover`]) finishes a committed change (roll forward) or
//! discards an uncommitted one, so a crash at any point leaves either the old
//! archive or the new one, both tables consistent.

use std::path::{Path, PathBuf};

use polars::prelude::*;

mod page;
pub mod rows;

pub use rows::{test_columns, TABLE_VALUES};

/// What can go wrong with an archive.
#[derive(Debug, thiserror::Error)]
pub enum ArchiveError {
    #[error("{file}: {message}")]
    Summary { file: String, message: String },
    #[error("{path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: {message}")]
    Table { path: PathBuf, message: String },
    #[error("SQL: {0}")]
    Sql(String),
    #[error("{0}")]
    Write(String),
    #[error("archive page: {0}")]
    Page(String),
}

/// The table files, by name.
pub const TABLES: [&str; 2] = ["tests", "impacts"];
const PENDING: &str = ".pending";
const COMMIT: &str = "COMMIT";

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> ArchiveError + '_ {
    move |source| ArchiveError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn table_err(path: &Path) -> impl FnOnce(PolarsError) -> ArchiveError + '_ {
    move |e| ArchiveError::Table {
        path: path.to_path_buf(),
        message: e.to_string(),
    }
}

/// The path of table `name` (`tests` or `impacts`) in `archive`.
pub fn table_path(archive: &Path, name: &str) -> PathBuf {
    archive.join(format!("{name}.parquet"))
}

/// Finish or discard an interrupted change (see the module docs); a no-op on a
/// clean archive. Returns what it did, for the user.
pub fn recover(archive: &Path) -> Result<Option<&'static str>, ArchiveError> {
    let pending = archive.join(PENDING);
    if !pending.exists() {
        return Ok(None);
    }
    if pending.join(COMMIT).exists() {
        for name in TABLES {
            let staged = table_path(&pending, name);
            if staged.exists() {
                std::fs::rename(&staged, table_path(archive, name)).map_err(io(&staged))?;
            }
        }
        std::fs::remove_dir_all(&pending).map_err(io(&pending))?;
        Ok(Some("finished an interrupted change that had been committed"))
    } else {
        std::fs::remove_dir_all(&pending).map_err(io(&pending))?;
        Ok(Some("discarded an interrupted change that had not been committed"))
    }
}

/// A lazy scan of table `name`, or an empty frame of its schema when the archive
/// does not hold it yet.
fn scan(archive: &Path, name: &str, empty: &DataFrame) -> Result<LazyFrame, ArchiveError> {
    let path = table_path(archive, name);
    if !path.exists() {
        return Ok(empty.clear().lazy());
    }
    let p = PlRefPath::try_from_path(&path).map_err(table_err(&path))?;
    LazyFrame::scan_parquet(p, ScanArgsParquet::default()).map_err(table_err(&path))
}

/// The impacts table. An archive written before each impact carried its test's
/// status (`tests.status`) gets it from `tests`, by manifest and test, so that
/// queries and the next add see one schema.
fn scan_impacts(archive: &Path, empty: &rows::Reduction) -> Result<LazyFrame, ArchiveError> {
    let path = table_path(archive, "impacts");
    let lf = scan(archive, "impacts", &empty.impacts)?;
    if lf.clone().collect_schema().map_err(table_err(&path))?.contains("status") {
        return Ok(lf);
    }
    let keys = [col("manifest_sha256"), col("test")];
    let status = scan(archive, "tests", &empty.tests)?.select([col("manifest_sha256"), col("test"), col("status")]);
    let order: Vec<Expr> = empty.impacts.get_column_names().iter().map(|c| col(c.as_str())).collect();
    // The rows keep their order (a left join need not, unless asked).
    let args = JoinArgs {
        maintain_order: MaintainOrderJoin::Left,
        ..JoinArgs::new(JoinType::Left)
    };
    Ok(lf.join(status, keys.clone(), keys, args).select(order))
}

/// What an add did.
#[derive(Debug)]
pub struct Added {
    /// (campaign, manifest sha256, tests, impacts, rows it replaced) per reduction.
    pub reductions: Vec<(String, String, usize, usize, usize)>,
    /// Rows of each table after the add.
    pub tests_rows: usize,
    pub impacts_rows: usize,
    /// Notes for the user (recovery, impacts not in SPEC's shape).
    pub notes: Vec<String>,
}

/// A step of [`add_with_hook`] that a test may interrupt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Step {
    /// Both tables staged, the change not yet committed.
    Staged,
    /// Committed, `tests.parquet` renamed into place, `impacts.parquet` not yet.
    FirstRenamed,
}

/// Add the reductions whose `summary.json` are in `report_dirs` to `archive`
/// (created if missing), replacing the rows of the same manifests.
pub fn add(archive: &Path, report_dirs: &[PathBuf]) -> Result<Added, ArchiveError> {
    add_with_hook(archive, report_dirs, &mut |_| Ok(()))
}

/// [`add`], calling `hook` at each [`Step`]; an error from it stops the add there
/// and leaves the files as a crash at that point would (fault injection in tests).
pub fn add_with_hook(archive: &Path, report_dirs: &[PathBuf], hook: &mut dyn FnMut(Step) -> Result<(), ArchiveError>) -> Result<Added, ArchiveError> {
    std::fs::create_dir_all(archive).map_err(io(archive))?;
    let mut notes: Vec<String> = recover(archive)?.map(String::from).into_iter().collect();
    let mut new = Vec::new();
    for dir in report_dirs {
        let file = dir.join("summary.json");
        let text = std::fs::read(&file).map_err(io(&file))?;
        let doc: serde_json::Value = serde_json::from_slice(&text).map_err(|e| ArchiveError::Summary {
            file: file.display().to_string(),
            message: format!("not valid JSON: {e}"),
        })?;
        let r = rows::reduction(&doc, &file.display().to_string())?;
        if !r.impacts_skipped.is_empty() {
            notes.push(format!(
                "{}: tests {} have impacts without SPEC's per-impact fields (side, e, r): none of their impacts archived",
                file.display(),
                r.impacts_skipped.join(", ")
            ));
        }
        new.push(r);
    }
    let shas: Vec<String> = new.iter().map(|r| r.sha256.clone()).collect();
    let keep = |lf: LazyFrame| shas.iter().fold(lf, |lf, s| lf.filter(col("manifest_sha256").neq(lit(s.as_str()))));
    let empty_tests = rows::reduction(&empty_summary(), "")?;
    let mut reductions = Vec::new();
    let old_tests = scan(archive, "tests", &empty_tests.tests)?.collect().map_err(table_err(archive))?;
    for r in &new {
        let replaced = old_tests
            .clone()
            .lazy()
            .filter(col("manifest_sha256").eq(lit(r.sha256.as_str())))
            .collect()
            .map_err(table_err(archive))?
            .height();
        reductions.push((r.campaign.clone(), r.sha256.clone(), r.tests.height(), r.impacts.height(), replaced));
        // The same campaign from another manifest (a typo fixed in it, then
        // reduced again) is another key: both are kept, and the user is told.
        let others = old_tests
            .clone()
            .lazy()
            .filter(
                col("campaign")
                    .eq(lit(r.campaign.as_str()))
                    .and(col("manifest_sha256").neq(lit(r.sha256.as_str()))),
            )
            .collect()
            .map_err(table_err(archive))?;
        let other_shas: std::collections::BTreeSet<String> = others
            .column("manifest_sha256")
            .and_then(|c| c.str().map(|s| s.iter().flatten().map(|x| x[..x.len().min(12)].to_string()).collect()))
            .map_err(table_err(archive))?;
        if !other_shas.is_empty() {
            notes.push(format!(
                "{} is also in the archive from another manifest ({}…, {} tests): both are kept, as two reductions (was the manifest corrected? its old rows stay until a reduction of that manifest replaces them); the archive page shows each with its manifest, and SQL tells them apart by manifest_sha256",
                r.campaign,
                other_shas.into_iter().collect::<Vec<_>>().join("…, "),
                others.height()
            ));
        }
    }
    let mut tables = Vec::new();
    for name in TABLES {
        let old = if name == "tests" {
            scan(archive, name, &empty_tests.tests)?
        } else {
            scan_impacts(archive, &empty_tests)?
        };
        let mut parts = vec![keep(old)];
        parts.extend(
            new.iter()
                .map(|r| if name == "tests" { r.tests.clone() } else { r.impacts.clone() }.lazy()),
        );
        let df = concat(parts, UnionArgs::default())
            .and_then(|lf| lf.collect())
            .map_err(table_err(&table_path(archive, name)))?;
        tables.push((name, df));
    }
    let (tests_rows, impacts_rows) = (tables[0].1.height(), tables[1].1.height());
    commit(archive, &mut tables, hook)?;
    if let Err(e) = page::write(archive, &tables[0].1, &tables[1].1) {
        notes.push(format!("archive.html not written: {e}"));
    }
    Ok(Added {
        reductions,
        tests_rows,
        impacts_rows,
        notes,
    })
}

/// Stage both tables, commit, rename them into place (see the module docs).
fn commit(archive: &Path, tables: &mut [(&str, DataFrame)], hook: &mut dyn FnMut(Step) -> Result<(), ArchiveError>) -> Result<(), ArchiveError> {
    let pending = archive.join(PENDING);
    // The project's one writer (each file atomically: a temporary, then a rename).
    let write = |files: &crate::report::Files| crate::report::write_files(&pending, files).map_err(|e| ArchiveError::Write(e.to_string()));
    let mut staged = crate::report::Files::default();
    for (name, df) in tables.iter_mut() {
        staged.add(
            format!("{name}.parquet"),
            crate::report::parquet::bytes(df).map_err(|e| ArchiveError::Write(e.to_string()))?,
        );
    }
    write(&staged)?;
    hook(Step::Staged)?;
    let mut marker = crate::report::Files::default();
    marker.add(COMMIT, "both tables staged\n");
    write(&marker)?;
    for (i, (name, _)) in tables.iter().enumerate() {
        let staged = table_path(&pending, name);
        std::fs::rename(&staged, table_path(archive, name)).map_err(io(&staged))?;
        if i == 0 {
            hook(Step::FirstRenamed)?;
        }
    }
    std::fs::remove_dir_all(&pending).map_err(io(&pending))
}

/// A summary with no test: the schema of the tables.
fn empty_summary() -> serde_json::Value {
    serde_json::json!({ "campaign": "", "manifest_sha256": "", "tests": [] })
}

/// Both tables of `archive` as frames (after [`recover`]).
pub fn load(archive: &Path) -> Result<(DataFrame, DataFrame), ArchiveError> {
    check_exists(archive)?;
    recover(archive)?;
    let empty = rows::reduction(&empty_summary(), "")?;
    let tests = scan(archive, "tests", &empty.tests)?.collect().map_err(table_err(archive))?;
    let impacts = scan_impacts(archive, &empty)?.collect().map_err(table_err(archive))?;
    Ok((tests, impacts))
}

/// The paths of `tests.parquet` and `impacts.parquet` of an existing archive, after
/// [`recover`] (for readers of the files themselves, e.g. the Python binding).
pub fn open(archive: &Path) -> Result<[PathBuf; 2], ArchiveError> {
    check_exists(archive)?;
    recover(archive)?;
    Ok(TABLES.map(|name| table_path(archive, name)))
}

fn check_exists(archive: &Path) -> Result<(), ArchiveError> {
    if !table_path(archive, "tests").exists() && !archive.join(PENDING).exists() {
        return Err(ArchiveError::Io {
            path: archive.to_path_buf(),
            source: std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no archive here (no tests.parquet): add reductions with `rocklab archive add`",
            ),
        });
    }
    Ok(())
}

/// The answer of a SQL query over the tables `tests` and `impacts` of `archive`.
pub fn query(archive: &Path, sql: &str) -> Result<DataFrame, ArchiveError> {
    check_exists(archive)?;
    recover(archive)?;
    let empty = rows::reduction(&empty_summary(), "")?;
    let mut ctx = polars::sql::SQLContext::new();
    ctx.register("tests", scan(archive, "tests", &empty.tests)?);
    ctx.register("impacts", scan_impacts(archive, &empty)?);
    ctx.execute(sql).and_then(|lf| lf.collect()).map_err(|e| ArchiveError::Sql(e.to_string()))
}

/// A frame as an aligned text table: every row and column (polars' own display
/// elides them past a limit), floats in full (the shortest text that reads back
/// as the same f64; polars' display rounds to 6 digits), nulls as "null".
pub fn show(df: &DataFrame) -> String {
    let cell = |c: &Column, i: usize| match c.get(i) {
        Ok(AnyValue::String(s)) => s.to_string(),
        Ok(AnyValue::StringOwned(s)) => s.to_string(),
        Ok(AnyValue::Null) => "null".to_string(),
        Ok(AnyValue::Float64(v)) => v.to_string(), // shortest text that reads back exactly
        Ok(AnyValue::Float32(v)) => v.to_string(),
        Ok(v) => v.to_string(),
        Err(e) => format!("<{e}>"),
    };
    let cols = df.columns();
    let mut grid: Vec<Vec<String>> = vec![cols.iter().map(|c| c.name().to_string()).collect()];
    grid.extend((0..df.height()).map(|i| cols.iter().map(|c| cell(c, i)).collect()));
    let widths: Vec<usize> = (0..cols.len())
        .map(|j| grid.iter().map(|r| r[j].chars().count()).max().unwrap_or(0))
        .collect();
    let mut out = String::new();
    for (k, row) in grid.iter().enumerate() {
        let line: Vec<String> = row.iter().zip(&widths).map(|(s, w)| format!("{s:<w$}")).collect();
        out.push_str(line.join("  ").trim_end());
        out.push('\n');
        if k == 0 {
            out.push_str(&widths.iter().map(|w| "-".repeat(*w)).collect::<Vec<_>>().join("  "));
            out.push('\n');
        }
    }
    out.push_str(&format!("({} row{})", df.height(), if df.height() == 1 { "" } else { "s" }));
    out
}
