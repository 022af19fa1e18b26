//! Issue 22, end to end on the built binary: names from the inputs that become
//! file names (test ids in `reduce` with plots, record names in `facade`,
//! coefficient-set names in `facade --scales`) never write outside `--out`,
//! whatever they hold (`..`, absolute paths, separators, NUL); the one writer
//! refuses a path that leaves `--out` and any non-finite number, writing nothing.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use rocklab::report::{write_files, Files};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures")
}

/// Every file below `dir`, relative to it.
fn tree(dir: &Path) -> BTreeSet<PathBuf> {
    let mut out = BTreeSet::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.insert(p.strip_prefix(dir).unwrap().to_path_buf());
            }
        }
    }
    out
}

fn run(args: &[&std::ffi::OsStr]) -> (i32, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_rocklab")).args(args).output().unwrap();
    (o.status.code().unwrap_or(-1), String::from_utf8_lossy(&o.stderr).into_owned())
}

/// The hostile names: parent folders, an absolute path, separators, NUL (as TOML
/// escapes), a leading dot.
const NAMES: &[&str] = &[
    "../../escaped",
    "/../../escaped",
    "/tmp/escaped",
    "a/b\\\\c",
    "a\\u0000b",
    ".hidden",
    "..",
];

/// Runs `args` (with OUT for the output folder) in a fresh folder holding
/// `files`, and checks that every file written is under OUT (`root/a/b/out`).
fn stays_inside(files: &[(&str, Vec<u8>)], args: &[&str]) -> BTreeSet<PathBuf> {
    let root = tempfile::tempdir().unwrap();
    let work = root.path().join("a/b");
    std::fs::create_dir_all(&work).unwrap();
    for (name, bytes) in files {
        std::fs::write(work.join(name), bytes).unwrap();
    }
    let before = tree(root.path());
    let out = work.join("out");
    let args: Vec<std::ffi::OsString> = args
        .iter()
        .map(|a| match *a {
            "OUT" => out.clone().into_os_string(),
            f if f.ends_with(".toml") => work.join(f).into_os_string(),
            other => other.into(),
        })
        .collect();
    let refs: Vec<&std::ffi::OsStr> = args.iter().map(|a| a.as_os_str()).collect();
    let (code, stderr) = run(&refs);
    assert_eq!(code, 0, "{stderr}");
    let after = tree(root.path());
    let new: Vec<_> = after.difference(&before).collect();
    assert!(!new.is_empty());
    for p in &new {
        assert!(p.starts_with("a/b/out"), "{} written outside --out", p.display());
    }
    for (name, bytes) in files {
        assert_eq!(&std::fs::read(work.join(name)).unwrap(), bytes, "{name} modified");
    }
    tree(&out)
}

// issue 22: a test id "../../x" made `reduce` (with plots) write PNG/SVG files in
// the parents of --out.
#[test]
fn reduce_test_ids_stay_inside_out() {
    let log = std::fs::read(fixtures().join("campaigns/one-sided-demo/150_1.csv")).unwrap();
    let mut manifest = String::from_utf8(std::fs::read(fixtures().join("campaigns/one-sided-demo/campaign.toml")).unwrap()).unwrap();
    manifest.truncate(manifest.find("[[test]]").unwrap());
    for (i, name) in NAMES.iter().enumerate() {
        manifest.push_str(&format!("[[test]]\nid = \"{name}\"\nfile = \"log{i}.csv\"\n"));
    }
    let mut files = vec![("campaign.toml", manifest.into_bytes())];
    let logs: Vec<String> = (0..NAMES.len()).map(|i| format!("log{i}.csv")).collect();
    files.extend(logs.iter().map(|l| (l.as_str(), log.clone())));
    let out = stays_inside(&files, &["reduce", "campaign.toml", "--out", "OUT"]);
    // Four plots per test, and the campaign's restitution law (issue 20) as PNG and SVG.
    let plots = out.iter().filter(|p| p.starts_with("plots")).count();
    assert_eq!(plots, 4 * NAMES.len() + 2, "{out:?}");
}

fn study(record_names: &[&str], set_names: &[&str]) -> String {
    let mut s = String::from("[study]\nname = \"s\"\nblock = \"block.toml\"\nmagnification = 1.27\nsamples = 0\n");
    for r in record_names {
        s.push_str(&format!("[[record]]\nname = \"{r}\"\nfile = \"pulse.AT2\"\n"));
    }
    for (i, c) in set_names.iter().enumerate() {
        s.push_str(&format!("[[coefficients]]\nname = \"{c}\"\ne = {}\n", 0.9 - 0.01 * i as f64));
    }
    s
}

fn study_files(text: String) -> Vec<(&'static str, Vec<u8>)> {
    vec![
        ("study.toml", text.into_bytes()),
        ("block.toml", std::fs::read(fixtures().join("facade/block.toml")).unwrap()),
        (
            "pulse.AT2",
            std::fs::read(fixtures().join("ground-motions/synthetic/one_sine_pulse_nga.AT2")).unwrap(),
        ),
    ]
}

// issue 22: a record named "/../../escaped" (facade) and a coefficient set named
// the same way (facade --scales) wrote files in the parents of --out; a record
// name with NUL made facade stop after 11 of its files.
#[test]
fn facade_record_and_set_names_stay_inside_out() {
    let out = stays_inside(&study_files(study(NAMES, &["housner"])), &["facade", "study.toml", "--out", "OUT"]);
    let responses = out.iter().filter(|p| p.to_string_lossy().starts_with("response_")).count();
    assert_eq!(responses, 2 * NAMES.len(), "{out:?}");
    assert!(out.contains(Path::new("summary.json")) && out.contains(Path::new("report.html")));
    let out = stays_inside(
        &study_files(study(&["r"], NAMES)),
        &["facade", "study.toml", "--out", "OUT", "--scales", "0.5:1.0:2"],
    );
    let ida = out
        .iter()
        .filter(|p| p.to_string_lossy().starts_with("ida_") && p.extension().is_some_and(|x| x == "svg"))
        .count();
    assert_eq!(ida, NAMES.len() + 1, "one figure per set and the fraction: {out:?}");
}

// issue 22: two names that make one file name are refused before anything is
// written, not written over each other.
#[test]
fn two_names_making_one_file_are_refused_and_nothing_written() {
    let root = tempfile::tempdir().unwrap();
    for (name, bytes) in study_files(study(&["a/b", "a_b"], &["housner"])) {
        std::fs::write(root.path().join(name), bytes).unwrap();
    }
    let out = root.path().join("out");
    let (code, stderr) = run(&[
        "facade".as_ref(),
        root.path().join("study.toml").as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("two outputs under one name"), "{stderr}");
    assert!(!out.exists());
}

// issue 22: the writer refuses paths that leave --out and non-finite numbers,
// writing none of the files.
#[test]
fn the_writer_refuses_escapes_and_non_finite_numbers_writing_nothing() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    for bad in ["../x.csv", "/tmp/x.csv", "plots/../../x.svg", "a\0b.csv"] {
        let mut files = Files::default();
        files.add("ok.csv", "a\n1\n");
        files.add(bad, "a\n1\n");
        let e = write_files(&out, &files).unwrap_err().to_string();
        assert!(e.contains("nothing was written"), "{e}");
    }
    for (name, bytes) in [
        ("h.csv", "t,theta\n0,NaN\n"),
        ("h.csv", "t,theta\n0,-inf\n"),
        ("p.svg", "<path d=\"M0 NaN\"/>"),
        ("r.md", "| inf |"),
    ] {
        let mut files = Files::default();
        files.add("ok.csv", "a\n1\n");
        files.add(name, bytes);
        let e = write_files(&out, &files).unwrap_err().to_string();
        assert!(e.contains("non-finite"), "{e}");
    }
    assert_eq!(tree(root.path()).len(), 0);
}

// issue 22: "Is a directory (os error 21): Is a directory (os error 21)".
#[test]
fn an_io_error_is_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let (code, stderr) = run(&[
        "simulate".as_ref(),
        "--block".as_ref(),
        fixtures().join("facade/block.toml").as_os_str(),
        "--record".as_ref(),
        dir.path().as_os_str(),
        "--e".as_ref(),
        "0.9".as_ref(),
        "--out".as_ref(),
        dir.path().join("o").as_os_str(),
    ]);
    assert_eq!(code, 2);
    assert_eq!(stderr.matches("os error 21").count(), 1, "{stderr}");
}

// A folder of --out that is a symbolic link (`out/plots -> elsewhere`, left by
// another tool) would carry the plots outside --out: the run is refused, naming
// the link, and nothing is written, there or under --out.
#[cfg(unix)]
#[test]
fn a_linked_folder_under_out_is_not_written_through() {
    let root = tempfile::tempdir().unwrap();
    let (out, elsewhere) = (root.path().join("out"), root.path().join("elsewhere"));
    std::fs::create_dir_all(&out).unwrap();
    std::fs::create_dir_all(&elsewhere).unwrap();
    std::os::unix::fs::symlink(&elsewhere, out.join("plots")).unwrap();
    let (code, stderr) = run(&[
        "reduce".as_ref(),
        fixtures().join("campaigns/one-sided-demo/campaign.toml").as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(stderr.contains("symbolic link"), "{stderr}");
    assert_eq!(tree(&elsewhere).len(), 0, "written through the link");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1, "something written under --out");
}

// A calibration whose every test is left out of the means has no mean to write:
// calibration.toml once held e_in = e_out = -0.0 (the mean of nothing), which a
// façade study would have read as e = 0. The run is refused with the tests and
// why each is left out; nothing is written and no table of unwritten values is
// printed.
#[test]
fn a_calibration_with_every_test_left_out_writes_nothing() {
    let root = tempfile::tempdir().unwrap();
    let demo = fixtures().join("campaigns/two-sided-demo");
    let manifest = std::fs::read_to_string(demo.join("campaign.toml")).unwrap();
    let head = &manifest[..manifest.find("[[test]]").unwrap()];
    let toml = format!("{head}[[test]]\nid = \"A_T0_5\"\nfile = \"A_T0_5.csv\"\nexclude_from_mean = true\n");
    std::fs::write(root.path().join("campaign.toml"), toml).unwrap();
    std::fs::copy(demo.join("A_T0_5.csv"), root.path().join("A_T0_5.csv")).unwrap();
    let out = root.path().join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_rocklab"))
        .arg("calibrate")
        .arg(root.path().join("campaign.toml"))
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("no test of two-sided-demo can be included in the calibration (A_T0_5 (exclude_from_mean))"),
        "{stderr}"
    );
    assert!(!out.exists(), "something was written");
    assert!(!stdout.contains("| A_T0_5 |"), "a table of unwritten values was printed: {stdout}");
}

// A test id of 100,000 characters (found by the mutation driver, seed 1010) once
// hung `reduce` with plots for minutes: the legend cut its label one character
// at a time, measuring the whole label each time. Labels are now cut by a binary
// search on a prefix of at most 200 characters.
#[test]
fn a_huge_test_id_is_cut_in_the_plots_without_a_hang() {
    let root = tempfile::tempdir().unwrap();
    let demo = fixtures().join("campaigns/two-sided-demo");
    let manifest = std::fs::read_to_string(demo.join("campaign.toml")).unwrap();
    let head = &manifest[..manifest.find("[[test]]").unwrap()];
    let id = "x".repeat(100_000);
    std::fs::write(
        root.path().join("campaign.toml"),
        format!("{head}[[test]]\nid = \"{id}\"\nfile = \"A_T0_5.csv\"\n"),
    )
    .unwrap();
    std::fs::copy(demo.join("A_T0_5.csv"), root.path().join("A_T0_5.csv")).unwrap();
    let out = root.path().join("out");
    let (code, stderr) = run(&[
        "reduce".as_ref(),
        root.path().join("campaign.toml").as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
    ]);
    assert_eq!(code, 0, "{stderr}");
    assert!(tree(&out).iter().any(|p| p.to_string_lossy().ends_with("_motion.png")));
}

/// A copy of the one-sided demo campaign in `dir`, its log `150_1.csv` renamed
/// `log_name` (and the manifest pointing at it).
fn demo_copy_with_log_named(dir: &Path, log_name: &str) {
    let demo = fixtures().join("campaigns/one-sided-demo");
    for e in std::fs::read_dir(&demo).unwrap().flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let to = if name == "150_1.csv" { log_name.to_string() } else { name.clone() };
        std::fs::copy(e.path(), dir.join(to)).unwrap();
    }
    let manifest = std::fs::read_to_string(dir.join("campaign.toml")).unwrap();
    let manifest = manifest.replace("file = \"150_1.csv\"", &format!("file = \"{log_name}\""));
    assert!(manifest.contains(log_name));
    std::fs::write(dir.join("campaign.toml"), manifest).unwrap();
}

/// `rocklab reduce DIR --out DIR --no-plots`: (exit code, stderr).
fn reduce_into_itself(camp: &Path) -> (i32, String) {
    run(&[
        "reduce".as_ref(),
        camp.as_os_str(),
        "--out".as_ref(),
        camp.as_os_str(),
        "--no-plots".as_ref(),
    ])
}

/// Every file below `dir` with its bytes.
fn contents(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    tree(dir).into_iter().map(|p| (p.clone(), std::fs::read(dir.join(&p)).unwrap())).collect()
}

// Session 13: `reduce C --out C` with a log named like an output (`table1.csv`)
// replaced the lab's raw log by Table 1. An output that would replace an input
// of the run is refused, and nothing is written.
#[test]
fn reduce_into_its_own_folder_never_replaces_an_input() {
    let root = tempfile::tempdir().unwrap();
    let camp = root.path();
    demo_copy_with_log_named(camp, "table1.csv");
    let before = contents(camp);
    let (code, stderr) = reduce_into_itself(camp);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("output table1.csv:") && stderr.contains("is an input of this run"),
        "{stderr}"
    );
    assert!(stderr.contains("nothing was written"), "{stderr}");
    assert_eq!(contents(camp), before, "an input was changed or an output written");
    // Without a clash the campaign's own folder is a valid --out, inputs untouched.
    let root = tempfile::tempdir().unwrap();
    let camp = root.path();
    demo_copy_with_log_named(camp, "150_1.csv");
    let before = contents(camp);
    let (code, stderr) = reduce_into_itself(camp);
    assert_eq!(code, 0, "{stderr}");
    let after = contents(camp);
    for (p, bytes) in &before {
        assert_eq!(after.iter().find(|(q, _)| q == p).map(|(_, b)| b), Some(bytes), "{p:?} changed");
    }
    assert!(after.iter().any(|(p, _)| p == Path::new("table1.csv")));
}

// Session 13: a study whose law set reads `summary.json` from the folder given
// as --out had that file replaced by the study's own summary.json; a block file
// read by `simulate` likewise. Both are refused, the inputs left as they were.
#[test]
fn facade_and_simulate_never_replace_the_files_they_read() {
    let root = tempfile::tempdir().unwrap();
    let dir = root.path();
    let mut text = study(&["r"], &[]);
    text.push_str("[[coefficients]]\nname = \"law\"\nlaw = \"summary.json\"\nspread = \"none\"\n");
    for (name, bytes) in study_files(text) {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    std::fs::copy(fixtures().join("facade/law.json"), dir.join("summary.json")).unwrap();
    let before = contents(dir);
    let (code, stderr) = run(&["facade".as_ref(), dir.join("study.toml").as_os_str(), "--out".as_ref(), dir.as_os_str()]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("output summary.json:") && stderr.contains("is an input of this run"),
        "{stderr}"
    );
    assert_eq!(contents(dir), before);

    std::fs::copy(dir.join("block.toml"), dir.join("history.csv")).unwrap();
    let before = contents(dir);
    let (code, stderr) = run(&[
        "simulate".as_ref(),
        "--block".as_ref(),
        dir.join("history.csv").as_os_str(),
        "--record".as_ref(),
        dir.join("pulse.AT2").as_os_str(),
        "--e".as_ref(),
        "0.9".as_ref(),
        "--out".as_ref(),
        dir.as_os_str(),
    ]);
    assert_eq!(code, 2, "{stderr}");
    assert!(
        stderr.contains("output history.csv:") && stderr.contains("is an input of this run"),
        "{stderr}"
    );
    assert_eq!(contents(dir), before);
}

// Session 13: the writer wrote file after file, so a failure half-way (a full
// disk; here a file where a folder must be) left part of a set behind, and a run
// killed while writing left a hidden temporary. Now every file is staged first:
// a failure while staging removes what was staged and the folders it made, and
// a dead run's temporaries are removed by the next run writing those names.
#[test]
fn a_failure_while_writing_leaves_nothing_and_old_temporaries_are_cleared() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    std::fs::create_dir_all(&out).unwrap();
    std::fs::write(out.join("plots"), "a file where a folder is needed").unwrap();
    let mut files = Files::default();
    files.add("summary.json", "{}");
    files.add("sub/a.csv", "a\n1\n");
    files.add("plots/p.svg", "<svg/>");
    let e = write_files(&out, &files).unwrap_err().to_string();
    assert!(e.contains("plots") && e.contains("a file is there, not a folder"), "{e}");
    assert_eq!(
        tree(root.path()),
        BTreeSet::from([PathBuf::from("out/plots")]),
        "part of the set was written"
    );
    assert!(!out.join("sub").exists(), "a folder made for the failed set was left");

    // A temporary of a process that no longer runs (pid above any pid_max).
    let stale = out.join(".summary.json.tmp-4999999999");
    std::fs::write(&stale, "half").unwrap();
    std::fs::remove_file(out.join("plots")).unwrap();
    write_files(&out, &files).unwrap();
    assert!(!stale.exists() || !Path::new("/proc/self").exists(), "the dead run's temporary was left");
    assert_eq!(std::fs::read(out.join("summary.json")).unwrap(), b"{}");
}

// Session 13: `--out` naming a file ran the whole reduction, then said
// "File exists (os error 17)". It is refused at once, naming the file.
#[test]
fn an_out_that_is_a_file_is_refused_before_any_work() {
    let root = tempfile::tempdir().unwrap();
    let file = root.path().join("notes.txt");
    std::fs::write(&file, "keep").unwrap();
    let manifest = fixtures().join("campaigns/one-sided-demo/campaign.toml");
    for out in [file.clone(), file.join("sub")] {
        let o = Command::new(env!("CARGO_BIN_EXE_rocklab"))
            .arg("reduce")
            .arg(&manifest)
            .arg("--out")
            .arg(&out)
            .output()
            .unwrap();
        let (stdout, stderr) = (String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
        assert_eq!(o.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains("notes.txt is a file, not a folder"), "{stderr}");
        assert!(!stdout.contains("campaign one-sided-demo"), "the campaign was reduced first: {stdout}");
    }
    assert_eq!(std::fs::read(&file).unwrap(), b"keep");
}

// Session 13: `calibrate --impacts 0` (or 1) reduced the campaign and then left
// every test out as having "fewer than 0 impacts". It is refused at once.
#[test]
fn calibrate_refuses_an_impact_count_the_fit_cannot_use() {
    let root = tempfile::tempdir().unwrap();
    let out = root.path().join("out");
    let manifest = fixtures().join("campaigns/one-sided-demo/campaign.toml");
    for n in ["0", "1", "1001"] {
        let (code, stderr) = run(&[
            "calibrate".as_ref(),
            manifest.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
            "--impacts".as_ref(),
            n.as_ref(),
        ]);
        assert_eq!(code, 2, "{stderr}");
        assert!(
            stderr.contains(&format!("--impacts = {n}: expected a value from 2 to 1000 impacts")),
            "{stderr}"
        );
        assert!(!out.exists());
    }
}

// Session 13: a log in mm declared as m (152 m at a sensor 2.33 m above the
// hinge) was reduced into "impacts 2.5 ms apart" and r⁺ = 328 ± 82966 %, marked
// suspect for reasons that never named the unit. Each test is now an error that
// says what cannot be and what to check.
#[test]
fn a_displacement_beyond_the_lever_arm_names_the_unit() {
    let root = tempfile::tempdir().unwrap();
    let camp = root.path();
    demo_copy_with_log_named(camp, "150_1.csv");
    let manifest = std::fs::read_to_string(camp.join("campaign.toml")).unwrap();
    let wrong = manifest.replace("unit = \"mm\", height_m", "unit = \"m\", height_m");
    assert_ne!(wrong, manifest);
    std::fs::write(camp.join("campaign.toml"), wrong).unwrap();
    let out = root.path().join("out");
    let (code, stderr) = run(&[
        "reduce".as_ref(),
        camp.as_os_str(),
        "--out".as_ref(),
        out.as_os_str(),
        "--no-plots".as_ref(),
    ]);
    assert_eq!(code, 1, "{stderr}");
    assert!(
        stderr.contains("150_1.csv: the displacement spans 162380 mm")
            && stderr.contains("more than the sensor's lever arm about the hinge (2330 mm)"),
        "{stderr}"
    );
    assert!(stderr.contains("[channels].displacement.unit"), "{stderr}");
    let summary: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert!(summary["tests"].as_array().unwrap().iter().all(|t| t["status"] == "error"), "{summary}");
}
