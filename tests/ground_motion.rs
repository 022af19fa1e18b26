//! Issue #3: ground-motion readers.

use std::path::{Path, PathBuf};

use rocklab::ground_motion::{parse, Format, ReadOptions, Units};
use rocklab::ingest::record::read;

fn gm(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/ground-motions").join(rel)
}

/// PGA and PGV of the NRC east components (SPEC and ground-motions/README: checked
/// there from the samples), and ×1.27 the paper's Table 5 rows. Tolerances: half a
/// unit of the last printed digit (PGA 4 decimals in g, PGV 2 decimals in cm/s;
/// Table 5 prints 2 decimals of g and of cm/s).
#[test]
fn nrc_east_pga_pgv_and_table_5() {
    let cases = [
        ("IT.NRC..HGE.D.20160824.013632.C.ACC.ASC", 0.3595, 29.75, 0.46, 37.79),
        ("IT.NRC..HGE.D.20161030.064018.C.ACC.ASC", 0.4858, 48.28, 0.62, 61.32),
    ];
    for (file, pga, pgv, pga_t5, pgv_t5) in cases {
        let r = read(&gm(&format!("esm-central-italy-2016/{file}")), &ReadOptions::default()).unwrap();
        assert_eq!(r.format, Format::Esm);
        assert_eq!(r.dt, 0.005);
        assert!((r.pga_g(1.0) - pga).abs() <= 0.00005, "{file}: PGA {}", r.pga_g(1.0));
        assert!((r.pgv_cm_s(1.0) - pgv).abs() <= 0.005, "{file}: PGV {}", r.pgv_cm_s(1.0));
        assert!((r.pga_g(1.27) - pga_t5).abs() <= 0.005, "{file}: scaled PGA {}", r.pga_g(1.27));
        assert!((r.pgv_cm_s(1.27) - pgv_t5).abs() <= 0.01, "{file}: scaled PGV {}", r.pgv_cm_s(1.27));
    }
}

/// COSMOS V2: 42000 points, dt = 5 ms from real header #62, peak −6.852 cm/s² at
/// 76.215 s (the file's own header says so).
#[test]
fn cosmos_v2() {
    let r = read(&gm("cosmos/us1000hyfh_akbmrp_AKBMR--n.1000hyfh.BNZ.--.acc.V2c"), &ReadOptions::default()).unwrap();
    assert_eq!(r.format, Format::Cosmos);
    assert_eq!(r.acc_m_s2.len(), 42000);
    assert!((r.dt - 0.005).abs() < 1e-12);
    let (i, a) = r
        .acc_m_s2
        .iter()
        .enumerate()
        .fold((0, 0.0f64), |b, (i, a)| if a.abs() > b.1.abs() { (i, *a) } else { b });
    assert!((a * 100.0 + 6.852).abs() < 0.001, "{a}");
    assert!((i as f64 * r.dt - 76.215).abs() < 1e-9);
}

const SINE_PGA: f64 = 0.6;

/// Two columns and one column with --dt: the shipped sine pulse (0.6 g).
#[test]
fn two_and_one_column() {
    let opts = ReadOptions {
        units: Some(Units::G),
        ..Default::default()
    };
    let two = read(&gm("synthetic/one_sine_pulse.csv"), &opts).unwrap();
    assert_eq!(two.format, Format::TwoColumn);
    assert!((two.dt - 0.005).abs() < 1e-12);
    assert!((two.pga_g(1.0) - SINE_PGA).abs() < 1e-9);
    let one = read(
        &gm("synthetic/one_sine_pulse_1col.txt"),
        &ReadOptions {
            dt: Some(0.005),
            ..opts.clone()
        },
    )
    .unwrap();
    assert_eq!(one.format, Format::OneColumn);
    assert_eq!(one.acc_m_s2, two.acc_m_s2);
    // Without --dt or --units: a clear error, no guess.
    let e = read(
        &gm("synthetic/one_sine_pulse_1col.txt"),
        &ReadOptions {
            units: Some(Units::G),
            ..Default::default()
        },
    )
    .unwrap_err();
    assert!(e.to_string().contains("--dt"), "{e}");
    let e = read(&gm("synthetic/one_sine_pulse.csv"), &ReadOptions::default()).unwrap_err();
    assert!(e.to_string().contains("--units"), "{e}");
}

fn values(n: usize) -> Vec<f64> {
    (0..n).map(|i| 0.01 * ((i as f64) * 0.7).sin() - 0.002 * i as f64 / n as f64).collect()
}

/// PEER AT2: NGA-West2 and old headers, 5 or 8 values per line, CR CR LF and CR line
/// ends, numbers that run together; all read back the same values.
#[test]
fn at2_variants() {
    let v = values(23);
    let fmt15 = |x: f64| format!("{x:15.7E}");
    let mut nga = String::from("PEER NGA STRONG MOTION DATABASE RECORD\nSynthetic, 1/1/2000, Station, 000\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=     23, DT=   .0100 SEC,\n");
    for c in v.chunks(5) {
        nga.push_str(&c.iter().map(|x| fmt15(*x)).collect::<String>());
        nga.push('\n');
    }
    let mut old =
        String::from("PACIFIC ENGINEERING\r\r\nSYNTHETIC\r\r\nACCELERATION TIME HISTORY IN UNITS OF G\r\r\n    23    0.0100    NPTS, DT\r\r\n");
    for c in v.chunks(8) {
        old.push_str(&c.iter().map(|x| format!("{x:10.5}")).collect::<String>());
        old.push_str("\r\r\n");
    }
    // Fortran E fields without separating blanks: "-.1234567E-02-.2345678E-02".
    let tight: String = nga
        .lines()
        .enumerate()
        .map(|(i, l)| {
            if i >= 4 {
                l.replace(" -", "-").replace("  ", " ")
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\r");
    for (name, text, tol) in [("nga", nga, 1e-9), ("old", old, 5e-6), ("cr-only tight", tight, 1e-9)] {
        let r = parse(Path::new(name), &text, &ReadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(r.format, Format::At2, "{name}");
        assert_eq!(r.dt, 0.01, "{name}");
        assert_eq!(r.acc_m_s2.len(), 23, "{name}");
        for (a, b) in r.acc_m_s2.iter().zip(&v) {
            assert!((a / rocklab::G - b).abs() < tol, "{name}: {a} vs {b}");
        }
    }
}

/// Malformed files name the file and the line.
#[test]
fn malformed_files_name_the_line() {
    let text = "PEER\nx\nACCELERATION TIME SERIES IN UNITS OF G\nNPTS=      3, DT=   .0100 SEC,\n 0.1 0.2\n 0.3 zz\n";
    let e = parse(Path::new("bad.at2"), text, &ReadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("bad.at2:6") && e.contains("'zz'"), "{e}");
    let text = "0 0.1\n0.01 0.2\n0.02\n";
    let e = parse(
        Path::new("bad.txt"),
        text,
        &ReadOptions {
            units: Some(Units::G),
            ..Default::default()
        },
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("bad.txt:3"), "{e}");
    let text = "NDATA: 3\nSAMPLING_INTERVAL_S: 0.005\nUNITS: cm/s^2\n1\n2\n";
    let e = parse(Path::new("cut.asc"), text, &ReadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("cut.asc:1") && e.contains("NDATA 3 but 2"), "{e}");
    let e = read(Path::new("/nonexistent/rec.asc"), &ReadOptions::default()).unwrap_err().to_string();
    assert!(e.contains("rec.asc") && e.contains("not found"), "{e}");
}

/// The shipped synthetic pulse in every format reads back the same samples as the
/// two-column file. Tolerances follow each file's printed precision: E15.7 (8
/// significant digits), F10.6 (5e-7 g), COSMOS 1E15.6 in cm/s² (7 significant digits).
#[test]
fn synthetic_pulse_in_every_format() {
    let reference = read(
        &gm("synthetic/one_sine_pulse.csv"),
        &ReadOptions {
            units: Some(Units::G),
            ..Default::default()
        },
    )
    .unwrap();
    let g = rocklab::G;
    for (file, format, tol_g) in [
        ("synthetic/one_sine_pulse_nga.AT2", Format::At2, 1e-7),
        ("synthetic/one_sine_pulse_old.AT2", Format::At2, 5e-7),
        ("synthetic/one_sine_pulse.V2", Format::Cosmos, 1e-6),
    ] {
        let r = read(&gm(file), &ReadOptions::default()).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(r.format, format, "{file}");
        assert!((r.dt - 0.005).abs() < 1e-12, "{file}: dt {}", r.dt);
        assert_eq!(r.acc_m_s2.len(), reference.acc_m_s2.len(), "{file}");
        for (a, b) in r.acc_m_s2.iter().zip(&reference.acc_m_s2) {
            assert!((a - b).abs() / g <= tol_g, "{file}: {} vs {} g", a / g, b / g);
        }
    }
}
