//! Issue #12: snapshots of the small rendered outputs (insta), built from small
//! in-memory inputs so that they do not depend on slow runs: a campaign table in
//! Markdown, CSV, LaTeX and HTML (an ok, a suspect and a failed test, a mean that
//! leaves one out), the calibration and per-impact tables, the façade's nominal
//! results table. A change of layout shows here as a diff to review
//! (`INSTA_UPDATE=always cargo test --test render`, then read the .snap files).

use std::path::Path;

use rocklab::calibrate::{Calibration, TestFit};
use rocklab::campaign_means::{CampaignMeans, Means};
use rocklab::facade::{Study, StudyRun};
use rocklab::fit::FitStop;
use rocklab::report::calibration::{calibration_table, per_impact_table};
use rocklab::report::facade::results_table;
use rocklab::report::table::{to_csv, to_html, to_latex, to_markdown};
use rocklab::report::tables::{campaign_tables, CampaignView, TestValues};
use rocklab::restitution::Coefficients;
use rocklab::study::RunSummary;

fn coefficients(x: f64) -> Coefficients {
    Coefficients {
        e: x,
        e_plus: x + 0.01,
        e_minus: x - 0.01,
        r: x,
        r_plus: x + 0.05,
        r_minus: x - 0.03,
        r1: x - 0.2,
        r1_plus: x + 0.02,
        r1_minus: x - 0.1,
        r2: x - 0.1,
    }
}

/// Every quantity's standard uncertainty `u`.
fn uncertainty(u: f64) -> Coefficients {
    Coefficients {
        e: u,
        e_plus: u,
        e_minus: u,
        r: u,
        r_plus: u,
        r_minus: u,
        r1: u,
        r1_plus: u,
        r1_minus: u,
        r2: u,
    }
}

/// The means the tables show for coefficients `c`.
fn means(c: &Coefficients) -> Means {
    Means {
        r: c.r,
        r_plus: c.r_plus,
        r_minus: c.r_minus,
        r1: c.r1,
        r1_plus: c.r1_plus,
        r1_minus: c.r1_minus,
        r2: c.r2,
    }
}

/// Table 1 of a three-test campaign: 150_1 ok (with uncertainties), 50_1
/// suspect, 100_1 failed to read; the mean leaves out 50_1.
fn campaign_table() -> rocklab::report::table::Table {
    let (q1, u1, q2) = (coefficients(0.6), uncertainty(0.012), coefficients(0.55));
    let m = CampaignMeans {
        means: Some(means(&coefficients(0.6))),
        means_u: Some(Means {
            r_plus: 0.013,
            r_minus: 0.006,
            ..means(&uncertainty(0.004))
        }),
        included: vec!["150_1".into()],
        left_out: vec![("50_1".into(), "suspect".into()), ("100_1".into(), "not reduced".into())],
    };
    let view = CampaignView {
        rocking: "one-sided",
        e_housner: 0.9738,
        e_housner_source: "computed: Eq. 2".into(),
        tests: vec![
            TestValues {
                id: "150_1",
                values: Ok((&q1, Some(&u1), None)),
            },
            TestValues {
                id: "50_1",
                values: Ok((&q2, None, Some("the last half-cycle spans 4 samples | too short".into()))),
            },
            TestValues {
                id: "100_1",
                values: Err("logs/100_1.csv: line 9, column 2: 'abc' is not a number".into()),
            },
        ],
        means: &m,
    };
    campaign_tables(&view).remove(0)
}

#[test]
fn campaign_table_markdown() {
    insta::assert_snapshot!("campaign_table1_md", to_markdown(&campaign_table()));
}

#[test]
fn campaign_table_csv() {
    insta::assert_snapshot!("campaign_table1_csv", String::from_utf8(to_csv(&campaign_table()).unwrap()).unwrap());
}

#[test]
fn campaign_table_latex() {
    insta::assert_snapshot!("campaign_table1_tex", to_latex(&campaign_table()));
}

#[test]
fn campaign_table_html() {
    insta::assert_snapshot!("campaign_table1_html", to_html(&campaign_table()));
}

fn fit(id: &str, e_in: f64, e_out: f64) -> TestFit {
    TestFit {
        id: id.into(),
        e_in,
        e_out,
        se_e_in: 0.002,
        se_e_out: 0.01,
        ci95_e_in: [e_in - 0.00392, e_in + 0.00392],
        ci95_e_out: [e_out - 0.0196, e_out + 0.0196],
        release_offset_s: 0.001,
        zero_offset_mm: -0.02,
        p2_factor: 1.01,
        kappa_per_s2: Some(40.0),
        rms_mm: 0.31,
        nrmse: 0.0019,
        iterations: 14,
        stop: FitStop::Converged,
        samples: 300,
        replay_mm: Vec::new(),
    }
}

fn calibration() -> Calibration {
    Calibration {
        campaign: "one-sided-demo".into(),
        rocking: rocklab::wall::Rocking::OneSided,
        e_housner: 0.9738,
        e_in: 0.33,
        e_out: 0.66,
        r_in: 0.339,
        r_out: 0.678,
        joint: None,
        agreement: None,
        joint_failure: None,
        tests: vec![fit("150_1", 0.312, 0.637), fit("150_2", 0.357, 0.852)],
        per_impact: vec![
            ("150_1".into(), vec![0.3148, 0.6050, 0.5602], vec![0.6129, 0.7636]),
            ("150_2".into(), vec![0.3534, 0.4671, 0.4473], vec![0.8434, 0.8217, 0.9147]),
        ],
        included: vec!["150_1".into(), "150_2".into()],
        left_out: Vec::new(),
        failed: Vec::new(),
    }
}

#[test]
fn calibration_table_markdown_and_html() {
    let t = calibration_table(&calibration());
    insta::assert_snapshot!("calibration_md", to_markdown(&t));
    insta::assert_snapshot!("calibration_html", to_html(&t));
}

#[test]
fn per_impact_table_puts_the_sides_side_by_side() {
    let t = per_impact_table(&calibration());
    insta::assert_snapshot!("per_impact_md", to_markdown(&t));
    insta::assert_snapshot!("per_impact_html", to_html(&t));
}

fn run(set: &str, polarity: i8, peak: f64, overturn: Option<f64>, well_conditioned: bool) -> StudyRun {
    StudyRun {
        record: "20161030_NRC".into(),
        coefficients: set.into(),
        polarity,
        scale: 1.27,
        summary: RunSummary {
            max_theta_over_alpha: peak,
            min_theta_over_alpha: -0.01,
            overturned: overturn.is_some(),
            overturn_time_s: overturn,
            impacts: 12,
            pga_g: 0.6169930145258575,
            pgv_cm_s: 61.32169130735002,
            solve_wall_s: 0.0,
            steps: 100,
        },
        well_conditioned,
        sensitivity: [peak, peak],
        law_reach: None,
        history: Vec::new(),
    }
}

/// The fixture study (its sets, records and polarities); the runs are made up
/// for one record (the table only lays them out; records without runs have no row).
#[test]
fn facade_results_table_markdown_and_html() {
    let study = Study::load(&Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/study.toml")).unwrap();
    let runs = vec![
        run("housner", 1, 1.0, Some(10.944952879764564), true),
        run("calibrated", 1, 1.0, Some(12.021281250646783), true),
        run("housner", -1, 0.5461, None, false),
        run("calibrated", -1, 0.5198, None, true),
    ];
    let t = results_table(&study, &runs);
    insta::assert_snapshot!("facade_results_md", to_markdown(&t));
    insta::assert_snapshot!("facade_results_html", to_html(&t));
}

/// The source files below `dir` (recursively), with their text.
fn sources(dir: &Path) -> Vec<(std::path::PathBuf, String)> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(sources(&p));
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push((p.clone(), std::fs::read_to_string(&p).unwrap()));
        }
    }
    out
}

/// Issue #12: renderers return bytes and one function writes them; the report
/// layer reads no file (the load step passes the inputs' facts in); the CLI holds
/// no rendering code (no plot panels, no HTML, no Markdown table rows).
#[test]
fn only_write_files_writes_and_rendering_stays_in_report() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let writes: Vec<String> = sources(&src)
        .iter()
        .filter(|(p, _)| !p.ends_with("atomic.rs"))
        .flat_map(|(p, text)| {
            ["write_atomic(", "write_under(", "write_set_under(", "fs::write(", "File::create("]
                .iter()
                .filter(|w| text.lines().any(|l| l.contains(*w) && !l.trim_start().starts_with("//")))
                .map(move |w| format!("{} calls {w}", p.display()))
        })
        .collect();
    assert_eq!(writes.len(), 1, "one writer (report::write_files) expected: {writes:?}");
    assert!(writes[0].contains("report/mod.rs"), "{writes:?}");
    for (p, text) in sources(&src.join("report")) {
        for read in ["fs::read", "File::open"] {
            assert!(!text.contains(read), "{} reads a file ({read})", p.display());
        }
    }
    for (p, text) in sources(&src.join("cli")) {
        for render in ["Panel", "plots::", "<table", "<td", "\"| "] {
            assert!(!text.contains(render), "{} renders ({render}): move it to src/report", p.display());
        }
    }
}
