//! Issue #19: the loggers' formats. The demo campaign written as .xlsx, .tdms,
//! .mat v5, .mat v7.3 and .parquet by independent writers
//! (tools/make_format_fixtures.py: openpyxl, npTDMS, scipy.io, h5py, pyarrow)
//! reduces to exactly the CSV's numbers; damaged files, wrong sheet / group /
//! channel / variable names and a text file renamed .xlsx give an error naming the
//! file and the place, never a panic.

use std::path::{Path, PathBuf};

use rocklab::ingest::{formats, Campaign, LogReader};
use rocklab::peaks::PeakOptions;
use rocklab::reduce::reduce_campaign;
use serde_json::Value;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn formats_dir() -> PathBuf {
    root().join("fixtures/formats")
}

/// The summary document of a reduction (default estimator).
fn summary_of(manifest: &Path) -> Value {
    let c = Campaign::load(manifest).unwrap_or_else(|e| panic!("{}: {e}", manifest.display()));
    let res = reduce_campaign(c, PeakOptions::default());
    for t in &res.tests {
        if let Err(e) = &t.result {
            panic!("{}: test {}: {e}", manifest.display(), t.spec.id);
        }
    }
    rocklab::report::summary::summary(&res).unwrap()
}

#[test]
fn each_format_reduces_to_exactly_the_csv_numbers() {
    let csv = summary_of(&root().join("fixtures/campaigns/one-sided-demo/campaign.toml"));
    for f in ["xlsx", "tdms", "mat5", "mat73", "parquet"] {
        let other = summary_of(&formats_dir().join(f).join("campaign.toml"));
        // Every number of every test (peaks, coefficients, uncertainties, impacts)
        // and the means: the whole documents, equal bit for bit.
        assert_eq!(other["tests"], csv["tests"], "{f}: the tests differ from the CSV's");
        assert_eq!(other["mean"], csv["mean"], "{f}: the means differ from the CSV's");
        assert_eq!(other["mean_u"], csv["mean_u"], "{f}");
    }
}

#[test]
fn each_format_reads_the_csv_columns_exactly() {
    let csv = LogReader::new(root().join("fixtures/campaigns/one-sided-demo/150_1.csv")).read().unwrap();
    for (dir, file) in [
        ("xlsx", "150_1.xlsx"),
        ("tdms", "150_1.tdms"),
        ("mat5", "150_1.mat"),
        ("mat73", "150_1.mat"),
        ("parquet", "150_1.parquet"),
    ] {
        let mut src = formats::Source::default();
        if dir == "xlsx" {
            src.sheet = Some("log".into());
        }
        if dir == "tdms" {
            src.group = Some("demo".into());
        }
        let log = LogReader::new(formats_dir().join(dir).join(file)).source(src).read().unwrap();
        assert_eq!(log.time_s, csv.time_s, "{dir}");
        assert_eq!(log.disp_mm, csv.disp_mm, "{dir}");
    }
}

#[test]
fn units_and_sign_apply_as_for_text() {
    // Time in ms and displacement in m, inward positive: the same factors as text.
    let p = formats_dir().join("parquet/150_2.parquet");
    let a = LogReader::new(&p).read().unwrap();
    let b = LogReader::new(&p).time("time_s", 1e-3).displacement("disp_mm", -1e3).read().unwrap();
    assert!(a.time_s.iter().zip(&b.time_s).all(|(x, y)| *y == x * 1e-3));
    assert!(a.disp_mm.iter().zip(&b.disp_mm).all(|(x, y)| *y == x * -1e3));
}

#[test]
fn tdms_waveform_time_from_its_properties() {
    // Only the displacement channel: t_i = wf_start_offset + i·wf_increment. The
    // CSV's times are the rounded text of i·0.005, so equal within 1e-12 s.
    let csv = LogReader::new(root().join("fixtures/campaigns/one-sided-demo/150_1.csv")).read().unwrap();
    let log = LogReader::new(formats_dir().join("waveform/150_1.tdms")).read().unwrap();
    assert_eq!(log.disp_mm, csv.disp_mm);
    assert_eq!(log.time_s.len(), csv.time_s.len());
    let worst = log.time_s.iter().zip(&csv.time_s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-12, "waveform time off by {worst} s");
    assert!(log.notes.iter().any(|n| n.contains("wf_increment 0.005")), "{:?}", log.notes);
    // In ms units the manifest's time factor must not apply to a time computed in s.
    let ms = LogReader::new(formats_dir().join("waveform/150_1.tdms"))
        .time("time_ms", 1e-3)
        .read()
        .unwrap();
    assert_eq!(ms.time_s, log.time_s);
}

/// The error of reading `path` with the given names and source, as text.
fn error_of(path: &Path, time: &str, disp: &str, src: formats::Source) -> String {
    match LogReader::new(path).time(time, 1.0).displacement(disp, 1.0).source(src).read() {
        Ok(_) => panic!("{} read without error", path.display()),
        Err(e) => {
            let text = e.to_string();
            assert_eq!(e.file(), path, "{text}");
            assert!(
                text.starts_with(&path.display().to_string()),
                "the message does not name the file: {text}"
            );
            text
        }
    }
}

fn sheet(s: &str) -> formats::Source {
    formats::Source {
        sheet: Some(s.into()),
        group: None,
    }
}

fn group(g: &str) -> formats::Source {
    formats::Source {
        sheet: None,
        group: Some(g.into()),
    }
}

#[test]
fn wrong_names_are_located() {
    let d = formats_dir();
    let none = formats::Source::default;
    let e = error_of(&d.join("xlsx/150_1.xlsx"), "time_s", "disp_mm", sheet("Sheet9"));
    assert!(e.contains("sheet 'Sheet9' not found (sheets: info, log)"), "{e}");
    let e = error_of(&d.join("xlsx/150_2.xlsx"), "time_s", "lvdt", none());
    assert!(
        e.contains("displacement column 'lvdt' not found in sheet 'data' (there: time_s, disp_mm, acc_g)"),
        "{e}"
    );
    // 150_1's first sheet is the 'info' sheet: without `sheet` the columns are not there.
    let e = error_of(&d.join("xlsx/150_1.xlsx"), "time_s", "disp_mm", none());
    assert!(e.contains("in sheet 'info'"), "{e}");
    let e = error_of(&d.join("tdms/150_1.tdms"), "time_s", "disp_mm", none());
    assert!(e.contains("channel 'disp_mm' is in several groups ('demo', 'raw')"), "{e}");
    let e = error_of(&d.join("tdms/150_1.tdms"), "time_s", "disp_mm", group("nope"));
    assert!(e.contains("group 'nope' not found (groups: demo, raw)"), "{e}");
    let e = error_of(&d.join("tdms/150_2.tdms"), "time_s", "lvdt", none());
    assert!(e.contains("channel 'lvdt' not found in any group"), "{e}");
    let e = error_of(&d.join("tdms/150_2.tdms"), "t", "disp_mm", none());
    assert!(
        e.contains("time channel 't' not found in group 'demo'") && e.contains("wf_increment"),
        "{e}"
    );
    for m in ["mat5", "mat73"] {
        let e = error_of(&d.join(m).join("150_2.mat"), "time_s", "lvdt", none());
        assert!(e.contains("variable 'lvdt' not found"), "{m}: {e}");
        assert!(e.contains("acc_g") && e.contains("disp_mm"), "{m}: {e}");
    }
    let e = error_of(&d.join("parquet/150_2.parquet"), "time", "disp_mm", none());
    assert!(e.contains("column 'time' not found (there: time_s, disp_mm, acc_g)"), "{e}");
    // A key of another format is refused, not ignored.
    let e = error_of(&d.join("parquet/150_2.parquet"), "time_s", "disp_mm", sheet("log"));
    assert!(e.contains("'sheet' is given but the file is not a workbook"), "{e}");
}

#[test]
fn a_text_file_renamed_xlsx_is_an_error() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("150_2.xlsx");
    std::fs::copy(root().join("fixtures/campaigns/one-sided-demo/150_2.csv"), &p).unwrap();
    let e = error_of(&p, "time_s", "disp_mm", formats::Source::default());
    assert!(e.contains("not readable as an Excel workbook"), "{e}");
    for ext in ["tdms", "mat", "parquet"] {
        let q = dir.path().join(format!("150_2.{ext}"));
        std::fs::copy(&p, &q).unwrap();
        let e = error_of(&q, "time_s", "disp_mm", formats::Source::default());
        assert!(e.contains("not readable as"), "{ext}: {e}");
    }
}

/// Every good fixture, with the names and source that read it.
fn good_files() -> Vec<(PathBuf, formats::Source)> {
    let d = formats_dir();
    vec![
        (d.join("xlsx/150_1.xlsx"), sheet("log")),
        (d.join("xlsx/150_2.xlsx"), formats::Source::default()),
        (d.join("tdms/150_1.tdms"), group("demo")),
        (d.join("waveform/150_1.tdms"), formats::Source::default()),
        (d.join("mat5/150_2.mat"), formats::Source::default()),
        (d.join("mat73/150_2.mat"), formats::Source::default()),
        (d.join("parquet/150_2.parquet"), formats::Source::default()),
    ]
}

/// A small deterministic generator (SplitMix64) for the damage positions.
fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

#[test]
fn truncated_files_give_a_located_error() {
    let dir = tempfile::tempdir().unwrap();
    for (good, src) in good_files() {
        let bytes = std::fs::read(&good).unwrap();
        for keep in [0, 10, 100, bytes.len() / 3, bytes.len() / 2, bytes.len() - 8, bytes.len() - 1] {
            let p = dir.path().join(good.file_name().unwrap());
            std::fs::write(&p, &bytes[..keep]).unwrap();
            let r = LogReader::new(&p).source(src.clone()).read();
            match r {
                Err(e) => assert_eq!(e.file(), p, "{e}"),
                Ok(log) => panic!(
                    "{} cut to {keep} of {} bytes read {} rows without error",
                    good.display(),
                    bytes.len(),
                    log.time_s.len()
                ),
            }
        }
    }
}

#[test]
fn corrupted_files_never_panic() {
    // Bytes overwritten at random places: an error naming the file, or (where the
    // damage fell on bytes a reader does not use, or on a value) data that still
    // passes every check of the log; never a panic, never a hang.
    let dir = tempfile::tempdir().unwrap();
    let mut state = 19;
    let (mut errors, mut read) = (0, 0);
    for (good, src) in good_files() {
        let bytes = std::fs::read(&good).unwrap();
        for _ in 0..25 {
            let mut b = bytes.clone();
            let at = (splitmix(&mut state) % b.len() as u64) as usize;
            let n = 1 + (splitmix(&mut state) % 64) as usize;
            for x in b.iter_mut().skip(at).take(n) {
                *x = splitmix(&mut state) as u8;
            }
            let p = dir.path().join(good.file_name().unwrap());
            std::fs::write(&p, &b).unwrap();
            match LogReader::new(&p).source(src.clone()).read() {
                Err(e) => {
                    assert_eq!(e.file(), p, "{e}");
                    errors += 1;
                }
                Ok(log) => {
                    assert!(log.time_s.windows(2).all(|w| w[1] > w[0]));
                    assert!(log.disp_mm.iter().all(|x| x.is_finite()));
                    read += 1;
                }
            }
        }
    }
    eprintln!("corrupted files: {errors} errors, {read} read with valid columns");
    assert!(errors > 0);
}

#[test]
fn bad_values_name_the_row() {
    let d = formats_dir().join("bad");
    let none = formats::Source::default;
    let e = error_of(&d.join("text_cell.xlsx"), "time_s", "disp_mm", none());
    assert!(e.contains("sheet 'log', row 5, column 2 ('disp_mm'): 'n/a' is not a number"), "{e}");
    let e = error_of(&d.join("nan.parquet"), "time_s", "disp_mm", none());
    assert!(e.contains("row 7: 'disp_mm' is NaN: expected a finite measured value"), "{e}");
    let e = error_of(&d.join("time_back.mat"), "time_s", "disp_mm", none());
    assert!(e.contains("row 4: 'time_s' 0.001 is decreasing (previous row 0.01)"), "{e}");
    let e = error_of(&d.join("matrix.mat"), "time_s", "disp_mm", none());
    assert!(e.contains("variable 'disp_mm' is a 2×4 array: expected a vector"), "{e}");
}
