//! Issue #2 benchmark: read, differentiate and find the peaks of a generated
//! 2,000,000-row log (1 kHz, 2000 s: a release from 150 mm, two-sided rocking with
//! e = 0.9, then rest; noise 0.02 mm, quantised to 0.01 mm).
//!
//! `cargo bench --bench ingest_peaks` prints divan's median. The log and a manifest
//! are left in `target/bench-data/` so that peak memory can be measured on the
//! whole command: `just bench-mem`. Beside them, `log2m_wide.csv` (the same rows
//! with 14 extra channels: 16 columns, 242 MB) and `campaign_wide.toml`, for the
//! memory bound of issue 22 (≤ 150 MB peak to reduce it).

use std::io::Write;
use std::path::{Path, PathBuf};

use rocklab::ingest::{Campaign, Rocking};
use rocklab::peaks::{analyse, PeakOptions, Physics};
use rocklab::reduce::read_log;

fn main() {
    write_bench_data(&bench_dir());
    divan::main();
}

fn bench_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("target/bench-data")
}

/// Deterministic uniform noise in [−0.5, 0.5) (xorshift), so no extra crate.
struct Noise(u64);
impl Noise {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    }
}

/// Two-sided linearised rocking sampled at 1 kHz (10 sub-steps per sample).
fn write_bench_data(dir: &Path) {
    let log = dir.join("log2m.csv");
    if log.exists() && dir.join("log2m_wide.csv").exists() {
        return;
    }
    std::fs::create_dir_all(dir).unwrap();
    let (alpha, p2, lever, e) = (0.1447f64, 5.89f64, 2330.0f64, 0.9f64);
    let mut theta = 0.0645f64;
    let mut omega = 0.0f64;
    let mut noise = Noise(0x9E3779B97F4A7C15);
    let mut out = String::with_capacity(2_000_000 * 24);
    out.push_str("# generated benchmark log\ntime_s,disp_mm,acc_g\n");
    let mut wide = std::io::BufWriter::new(std::fs::File::create(dir.join("log2m_wide.csv")).unwrap());
    let mut channels = Noise(0x2545F4914F6CDD1D);
    let extra: Vec<String> = (1..=14).map(|k| format!(",ch{k:02}")).collect();
    writeln!(wide, "# generated benchmark log, 16 channels\ntime_s,disp_mm,acc_g{}", extra.concat()).unwrap();
    let dt = 1e-3;
    for i in 0..2_000_000u64 {
        let t = i as f64 * dt;
        if t > 1.0 {
            for _ in 0..10 {
                let h = dt / 10.0;
                let s = if theta >= 0.0 { 1.0 } else { -1.0 };
                let acc = -p2 * s * (alpha - s * theta).sin();
                omega += acc * h;
                let next = theta + omega * h;
                if next * theta < 0.0 {
                    omega *= e;
                    if omega.abs() < 1e-4 {
                        omega = 0.0;
                    }
                }
                theta = if omega == 0.0 { 0.0 } else { next };
            }
        }
        let x = lever * theta.sin() + 0.04 * (noise.next() + noise.next() + noise.next());
        let row = format!("{t:.3},{:.2},0", (x * 100.0).round() / 100.0);
        out.push_str(&row);
        out.push('\n');
        // 14 channels of noise, 7-8 characters each (a wide DAQ export).
        write!(wide, "{row}").unwrap();
        for _ in 0..14 {
            write!(wide, ",{:.4}", 2.0 * channels.next()).unwrap();
        }
        writeln!(wide).unwrap();
    }
    wide.flush().unwrap();
    std::fs::write(&log, out).unwrap();
    let manifest = r#"[campaign]
name = "bench"
rocking = "two-sided"
[wall]
height_m = 2.70
thickness_m = 0.36
hinge_height_m = 0.23
[channels]
time = { column = "time_s", unit = "s" }
displacement = { column = "disp_mm", unit = "mm", height_m = 2.56 }
[[test]]
id = "log2m"
file = "log2m.csv"
"#;
    std::fs::write(dir.join("campaign.toml"), manifest).unwrap();
    std::fs::write(
        dir.join("campaign_wide.toml"),
        manifest
            .replace("log2m.csv", "log2m_wide.csv")
            .replace("name = \"bench\"", "name = \"bench-wide\""),
    )
    .unwrap();
}

#[divan::bench(sample_count = 10)]
fn read_differentiate_peaks_2m_rows() -> usize {
    let dir = bench_dir();
    let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
    let spec = &campaign.tests[0];
    let log = read_log(spec).unwrap();
    let phys = Physics {
        rocking: Rocking::TwoSided,
        lever_arm_mm: spec.lever_arm_m * 1e3,
        p_guess: campaign.p_squared().sqrt(),
    };
    let a = analyse(&log.time_s, &log.disp_mm, &phys, &PeakOptions::default()).unwrap();
    divan::black_box(a.peaks.len())
}
