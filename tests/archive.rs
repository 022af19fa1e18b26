//! Issue #19: the lab archive. `rocklab archive add` of both demo reductions,
//! twice, holds 10 test rows without duplicates, equal to summary.json;
//! `archive query` answers SQL; a crash between the two tables' writes leaves a
//! readable, consistent archive; impacts in SPEC's shape become impacts.parquet rows.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use polars::prelude::*;
use rocklab::archive::{self, ArchiveError, Step};
use serde_json::{json, Value};

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_rocklab")
}

fn run(args: &[&str]) -> String {
    let out = Command::new(bin()).args(args).output().unwrap();
    let (so, se) = (String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    assert!(out.status.success(), "rocklab {args:?} failed:\n{so}\n{se}");
    so.into_owned()
}

/// Reduce a demo campaign into `out` (no plots: the tables are what is archived).
fn reduce(campaign: &str, out: &Path) -> Value {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("fixtures/campaigns")
        .join(campaign)
        .join("campaign.toml");
    run(&["reduce", manifest.to_str().unwrap(), "--out", out.to_str().unwrap(), "--no-plots"]);
    // Numbers read exactly (serde_json's float_roundtrip, checked below); Python's
    // json, an independent reader, checks the same in python/tests/test_archive.py.
    serde_json::from_str::<serde_json::Value>(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

fn strs(df: &DataFrame, c: &str) -> Vec<String> {
    df.column(c).unwrap().str().unwrap().iter().map(|s| s.unwrap_or("").to_string()).collect()
}

fn nums(df: &DataFrame, c: &str) -> Vec<Option<f64>> {
    df.column(c).unwrap().f64().unwrap().iter().collect()
}

#[test]
fn add_twice_query_and_values_equal_summary() {
    let tmp = tempfile::tempdir().unwrap();
    let (one, two, arc) = (tmp.path().join("one"), tmp.path().join("two"), tmp.path().join("archive"));
    let docs = [reduce("one-sided-demo", &one), reduce("two-sided-demo", &two)];
    for doc in &docs {
        assert_eq!(doc["manifest_sha256"].as_str().unwrap().len(), 64);
        assert!(doc["wall"]["height_m"].as_f64().is_some());
    }
    // The tables' Parquet copies sit beside the CSVs.
    for t in ["table1", "table2", "table3"] {
        assert!(one.join(format!("{t}.parquet")).exists(), "{t}.parquet missing");
    }
    let (a, b, z) = (one.to_str().unwrap(), two.to_str().unwrap(), arc.to_str().unwrap());
    run(&["archive", "add", a, b, "--to", z]);
    let second = run(&["archive", "add", a, b, "--to", z]);
    assert!(second.contains("replacing 5 earlier rows"), "{second}");
    let (tests, impacts) = archive::load(&arc).unwrap();
    assert_eq!(tests.height(), 10, "{tests}");
    let keys: BTreeSet<(String, String)> = strs(&tests, "manifest_sha256").into_iter().zip(strs(&tests, "test")).collect();
    assert_eq!(keys.len(), 10, "duplicate rows");
    // Every value equal to summary.json's (the same f64, through Parquet).
    let (campaigns, ids) = (strs(&tests, "campaign"), strs(&tests, "test"));
    for doc in &docs {
        for t in doc["tests"].as_array().unwrap() {
            let i = (0..tests.height())
                .find(|&i| campaigns[i] == doc["campaign"].as_str().unwrap() && ids[i] == t["id"].as_str().unwrap())
                .unwrap();
            assert_eq!(strs(&tests, "status")[i], t["status"].as_str().unwrap());
            for v in archive::TABLE_VALUES {
                for k in [v.to_string(), format!("{v}_u")] {
                    assert_eq!(nums(&tests, &k)[i], t[&k].as_f64(), "{} {} {k}", campaigns[i], ids[i]);
                }
            }
            assert_eq!(nums(&tests, "e_housner")[i], doc["e_housner"].as_f64());
            let slender = doc["wall"]["height_m"].as_f64().unwrap() / doc["wall"]["thickness_m"].as_f64().unwrap();
            assert_eq!(nums(&tests, "slenderness")[i], Some(slender));
        }
    }
    // Every impact of summary.json with a coefficient (side, e, r) is a row, value
    // for value; an impact without one (its next peak not read) is not. (The
    // archive once skipped a whole test for one such impact: zero rows.)
    let listed: Vec<&Value> = docs
        .iter()
        .flat_map(|d| d["tests"].as_array().unwrap())
        .flat_map(|t| t["impacts"].as_array().unwrap())
        .filter(|i| i["side"].is_string())
        .collect();
    assert!(listed.len() >= 50, "only {} impacts with a coefficient in the demos", listed.len());
    assert_eq!(impacts.height(), listed.len(), "{impacts}");
    let mut archived: Vec<(Option<f64>, Option<f64>)> = nums(&impacts, "e").into_iter().zip(nums(&impacts, "r_u")).collect();
    let mut summary: Vec<(Option<f64>, Option<f64>)> = listed.iter().map(|i| (i["e"].as_f64(), i["r_u"].as_f64())).collect();
    let key = |v: &(Option<f64>, Option<f64>)| (v.0.unwrap().to_bits(), v.1.unwrap().to_bits());
    archived.sort_by_key(key);
    summary.sort_by_key(key);
    assert_eq!(archived, summary);
    // `reduce` writes the same rows beside its CSVs.
    assert!(one.join("impacts.parquet").exists() && two.join("impacts.parquet").exists());
    let out = run(&[
        "archive",
        "query",
        z,
        "SELECT campaign, count(*) AS n, avg(r_plus) AS r_plus FROM tests GROUP BY campaign ORDER BY campaign",
    ]);
    assert!(out.contains("one-sided-demo") && out.contains("two-sided-demo"), "{out}");
    assert!(out.contains("(2 rows)"), "{out}");
    let df = archive::query(&arc, "SELECT count(*) AS n FROM tests WHERE campaign = 'one-sided-demo'").unwrap();
    assert_eq!(df.column("n").unwrap().cast(&DataType::Int64).unwrap().i64().unwrap().get(0), Some(5));
    // The archive page plots them.
    let page = std::fs::read_to_string(arc.join("archive.html")).unwrap();
    assert!(page.contains("<svg") && page.contains("one-sided-demo") && page.contains("two-sided-demo"));
    // …and every impact's r against its amplitude (two panels, one per side).
    assert!(
        page.contains(&format!("every archived impact ({} impacts of the tests with status ok)", listed.len())),
        "impact figure missing"
    );
    // Session 13: the campaigns' table averaged every test with status ok, 50_1
    // (exclude_from_mean) too, so its mean r⁻ of one-sided-demo (0.591) was not
    // the campaign's own (Table 1: 0.593). It is now the campaign's mean.
    for doc in &docs {
        let (c, m) = (doc["campaign"].as_str().unwrap(), &doc["mean"]);
        let n = doc["mean_included"].as_array().unwrap().len();
        let cells = row_cells(&page, c);
        let want = [
            n.to_string(),
            format!("{:.3}", m["r_plus"].as_f64().unwrap()),
            format!("{:.3}", m["r_minus"].as_f64().unwrap()),
        ];
        assert_eq!(&cells[5..8], &want.iter().map(String::as_str).collect::<Vec<_>>()[..], "{c}: {cells:?}");
    }
    assert_eq!(page.matches("r against amplitude").count(), 2);
    // A bad query is an error, not a crash.
    let e = archive::query(&arc, "SELECT nope FROM tests").unwrap_err();
    assert!(matches!(e, ArchiveError::Sql(_)), "{e}");
}

/// A summary of `n_tests` tests whose impacts are in SPEC's shape (k, side,
/// amplitude_over_alpha, speeds, e, e_u, r, r_u), keyed by `sha`.
fn spec_summary(sha: &str, n_tests: usize, n_impacts: usize) -> Value {
    let tests: Vec<Value> = (0..n_tests)
        .map(|t| {
            let impacts: Vec<Value> = (0..n_impacts)
                .map(|k| {
                    json!({"k": k, "side": if k % 2 == 0 { "in" } else { "out" }, "amplitude_over_alpha": 0.5 / (k + 1) as f64,
                           "speed_before_mm_s": 600.0 - 50.0 * k as f64, "speed_after_mm_s": 390.0 - 30.0 * k as f64,
                           "e": 0.65, "e_u": 0.006, "r": 0.668 + 0.001 * t as f64, "r_u": 0.006})
                })
                .collect();
            json!({"id": format!("T{t}"), "status": "ok", "r_plus": 0.7, "r_minus": 0.6, "r_plus_u": 0.01, "r_minus_u": 0.01,
                   "exclude_from_mean": false, "impacts": impacts})
        })
        .collect();
    json!({"campaign": format!("c-{sha}"), "rocking": "one-sided", "alpha_rad": 0.13, "e_housner": 0.97,
           "manifest_sha256": sha, "rocklab_version": "0", "wall": {"height_m": 2.7, "thickness_m": 0.36},
           "tests": tests})
}

fn write_summary(dir: &Path, doc: &Value) -> PathBuf {
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(dir.join("summary.json"), serde_json::to_vec(doc).unwrap()).unwrap();
    dir.to_path_buf()
}

#[test]
fn impacts_in_spec_shape_become_rows() {
    let tmp = tempfile::tempdir().unwrap();
    let r = write_summary(&tmp.path().join("r"), &spec_summary("aa", 3, 7));
    let arc = tmp.path().join("arc");
    let added = archive::add(&arc, &[r]).unwrap();
    assert_eq!((added.tests_rows, added.impacts_rows), (3, 21));
    let (_, impacts) = archive::load(&arc).unwrap();
    assert_eq!(impacts.height(), 21);
    assert_eq!(strs(&impacts, "side")[..3], ["in", "out", "in"]);
    assert_eq!(nums(&impacts, "r")[7], Some(0.669)); // test T1, impact 0
    let df = archive::query(
        &arc,
        "SELECT test, count(*) AS n FROM impacts WHERE side = 'in' GROUP BY test ORDER BY test",
    )
    .unwrap();
    assert_eq!(strs(&df, "test"), ["T0", "T1", "T2"]);
}

/// Each impact carries its test's status (a suspect test's impacts are printed,
/// not vouched for), and an archive written before that column gets it from its
/// `tests` table when read, queried or added to.
#[test]
fn impacts_carry_their_tests_status_also_in_older_archives() {
    let tmp = tempfile::tempdir().unwrap();
    let mut doc = spec_summary("aa", 3, 4);
    doc["tests"][1]["status"] = json!("suspect: the fit misses the log");
    let arc = tmp.path().join("arc");
    archive::add(&arc, &[write_summary(&tmp.path().join("r"), &doc)]).unwrap();
    let (_, impacts) = archive::load(&arc).unwrap();
    let expected: Vec<String> = (0..3)
        .flat_map(|t| vec![if t == 1 { "suspect: the fit misses the log" } else { "ok" }.to_string(); 4])
        .collect();
    assert_eq!(strs(&impacts, "status"), expected);
    // The same archive as an older rocklab wrote it: impacts without the column.
    let file = archive::open(&arc).unwrap()[1].clone();
    let mut old = impacts.drop("status").unwrap();
    ParquetWriter::new(std::fs::File::create(&file).unwrap()).finish(&mut old).unwrap();
    let (_, read) = archive::load(&arc).unwrap();
    assert_eq!(read.get_column_names(), impacts.get_column_names());
    assert_eq!(strs(&read, "status"), expected);
    let n = archive::query(&arc, "SELECT count(*) AS n FROM impacts WHERE status = 'ok'").unwrap();
    assert_eq!(n.column("n").unwrap().get(0).unwrap().extract::<u32>(), Some(8));
    // Adding to it writes one schema; the old rows keep the status they were given.
    archive::add(&arc, &[write_summary(&tmp.path().join("s"), &spec_summary("bb", 1, 2))]).unwrap();
    let (_, after) = archive::load(&arc).unwrap();
    assert_eq!(after.height(), 14);
    assert_eq!(strs(&after, "status").iter().filter(|s| s.starts_with("suspect")).count(), 4);
}

/// Session 13: a campaign whose tests are all suspect (the engine campaign
/// fresh-one-s8) was archived but missing from the page's table of campaigns.
#[test]
fn every_archived_campaign_is_in_the_page_even_with_no_test_ok() {
    let tmp = tempfile::tempdir().unwrap();
    let mut doc = spec_summary("aa", 2, 2);
    for t in 0..2 {
        doc["tests"][t]["status"] = json!("suspect: the fit misses the log");
    }
    let arc = tmp.path().join("arc");
    archive::add(&arc, &[write_summary(&tmp.path().join("r"), &doc)]).unwrap();
    let page = std::fs::read_to_string(arc.join("archive.html")).unwrap();
    let at = page.find(">c-aa</td>").expect("the campaign has no row");
    let row = page[at..].split("</tr>").next().unwrap();
    let cells: Vec<&str> = row.split("</td>").filter_map(|c| c.rsplit('>').next()).collect();
    assert_eq!(
        cells[..8],
        [
            "c-aa",
            "one-sided",
            "7.50",
            "2",
            "0",
            "0",
            "— (no test in the means)",
            "— (no test in the means)"
        ]
    );
}

/// Session 13: a campaign reduced again after a fix to its manifest (another
/// SHA-256) was added beside its first reduction without a word, and the page
/// merged both into one row (10 tests, one mean). The add now says so, and the
/// page gives each reduction its row, named with its manifest.
#[test]
fn a_campaign_from_a_corrected_manifest_is_said_and_shown_apart() {
    let tmp = tempfile::tempdir().unwrap();
    let arc = tmp.path().join("arc");
    let first = spec_summary("aa", 2, 2);
    let mut second = spec_summary("bb", 3, 2);
    second["campaign"] = first["campaign"].clone();
    archive::add(&arc, &[write_summary(&tmp.path().join("r1"), &first)]).unwrap();
    let added = archive::add(&arc, &[write_summary(&tmp.path().join("r2"), &second)]).unwrap();
    assert!(
        added
            .notes
            .iter()
            .any(|n| n.starts_with("c-aa is also in the archive from another manifest (aa…, 2 tests): both are kept")),
        "{:?}",
        added.notes
    );
    let page = std::fs::read_to_string(arc.join("archive.html")).unwrap();
    for (sha, n) in [("aa", "2"), ("bb", "3")] {
        let cells = row_cells(&page, &format!("c-aa (manifest {sha}…)"));
        assert_eq!(cells[3], n, "{cells:?}");
    }
    // A re-add of the same manifest replaces, and is not such a case.
    let again = archive::add(&arc, &[write_summary(&tmp.path().join("r3"), &second)]).unwrap();
    assert_eq!(again.reductions[0].4, 3);
    assert!(again.notes.iter().any(|n| n.contains("(aa…, 2 tests)")), "{:?}", again.notes);
}

/// (tests rows, impacts rows, the shas in each) of an archive as a reader finds it.
fn state(arc: &Path) -> (usize, usize, BTreeSet<String>, BTreeSet<String>) {
    let (t, i) = archive::load(arc).unwrap();
    let shas = |df: &DataFrame| strs(df, "manifest_sha256").into_iter().collect::<BTreeSet<_>>();
    (t.height(), i.height(), shas(&t), shas(&i))
}

#[test]
fn a_crash_between_the_two_writes_leaves_a_consistent_archive() {
    for crash_at in [Step::Staged, Step::FirstRenamed] {
        let tmp = tempfile::tempdir().unwrap();
        let arc = tmp.path().join("arc");
        let old = write_summary(&tmp.path().join("old"), &spec_summary("aa", 2, 4));
        archive::add(&arc, &[old]).unwrap();
        assert_eq!(state(&arc).0, 2);
        // A re-reduction of the same manifest (5 tests, 6 impacts each), then a second
        // campaign, the add "crashing" at `crash_at`: the hook's error stops it there
        // and nothing is cleaned up, as after a kill.
        let new = write_summary(&tmp.path().join("new"), &spec_summary("aa", 5, 6));
        let other = write_summary(&tmp.path().join("other"), &spec_summary("bb", 1, 2));
        let mut hook = |s: Step| {
            if s == crash_at {
                Err(ArchiveError::Page("injected crash".into()))
            } else {
                Ok(())
            }
        };
        assert!(archive::add_with_hook(&arc, &[new, other], &mut hook).is_err());
        // Right after the crash the files are those of one state or the other only
        // once a reader has recovered; every reader recovers first.
        let (nt, ni, st, si) = state(&arc);
        match crash_at {
            // Not committed: the old archive, whole.
            Step::Staged => assert_eq!((nt, ni), (2, 8), "{crash_at:?}"),
            // Committed: the new archive, whole (5 + 1 tests, 30 + 2 impacts).
            Step::FirstRenamed => assert_eq!((nt, ni), (6, 32), "{crash_at:?}"),
        }
        assert_eq!(st, si, "{crash_at:?}: the two tables hold different reductions");
        assert!(!arc.join(".pending").exists());
        // And the archive takes the next add as usual.
        let again = write_summary(&tmp.path().join("again"), &spec_summary("aa", 3, 1));
        let added = archive::add(&arc, &[again]).unwrap();
        assert_eq!(added.tests_rows, nt - if crash_at == Step::Staged { 2 } else { 5 } + 3);
    }
}

#[test]
fn a_summary_without_the_manifest_hash_is_refused() {
    let tmp = tempfile::tempdir().unwrap();
    let mut doc = spec_summary("aa", 1, 1);
    doc.as_object_mut().unwrap().remove("manifest_sha256");
    let r = write_summary(&tmp.path().join("r"), &doc);
    let e = archive::add(&tmp.path().join("arc"), &[r]).unwrap_err().to_string();
    assert!(e.contains("summary.json: no 'manifest_sha256'"), "{e}");
    let e = archive::query(&tmp.path().join("nothing"), "SELECT 1").unwrap_err().to_string();
    assert!(e.contains("no archive here"), "{e}");
}

/// summary.json is read back exactly: serde_json is built with `float_roundtrip`
/// (Cargo.toml); without it this 17-digit value lands one ulp off.
#[test]
fn summary_numbers_are_read_exactly() {
    let v: serde_json::Value = serde_json::from_str(r#"{"a": 0.014936020564324741}"#).unwrap();
    assert_eq!(v["a"].as_f64(), Some("0.014936020564324741".parse::<f64>().unwrap()));
}

/// The cells' texts of the archive page's table row whose cell reads `label`, from
/// that cell on.
fn row_cells<'a>(page: &'a str, label: &str) -> Vec<&'a str> {
    let at = page.find(&format!(">{label}</td>")).unwrap_or_else(|| panic!("no row of {label}"));
    page[at..]
        .split("</tr>")
        .next()
        .unwrap()
        .split("</td>")
        .filter_map(|c| c.rsplit('>').next())
        .collect()
}
