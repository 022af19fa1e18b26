//! Issue 18, part B: peaks read where the log resolves them
//! (`rocklab::peaks::local`), and where it must not.
//!
//! A logger's low-pass rounds the kink of a sharp impact so that it looks like a
//! resolved contact, and a local reading of filtered samples is attenuated: the
//! per-impact choice must keep the kink model there. The logs are the idealised
//! generator's (`rocklab::synth`, instantaneous impacts) simulated at 20× the
//! logger's rate, passed through a causal 4th-order Bessel low-pass at 0.25 fs,
//! then sampled, with the test's noise, drift and 0.01 mm quantisation.

use rocklab::peaks::{analyse, PeakOptions, Physics, ReadingMethod};
use rocklab::synth::{draw, generate, Family, Rng, Synthetic, TestSpec};

/// Poles of the 4th-order Bessel low-pass with −3 dB at 1 rad/s
/// (`scipy.signal.besselap(4, norm="mag")`; checked: |H(j)| = 1/√2).
const BESSEL4: [(f64, f64); 2] = [(-0.995_208_764_4, 1.257_105_739_5), (-1.370_067_830_6, 0.410_249_717_6)];

/// The causal Bessel filter at `fc` Hz applied to `u` sampled every `h` s: two
/// second-order sections y'' − 2 Re(p) y' + |p|² y = |p|² u (unity DC gain),
/// integrated by RK4 with u linear within a step.
fn bessel4(u: &[f64], h: f64, fc: f64) -> Vec<f64> {
    let w = 2.0 * std::f64::consts::PI * fc;
    let mut sig = u.to_vec();
    for &(re, im) in &BESSEL4 {
        let (a, b) = (-2.0 * re * w, (re * re + im * im) * w * w);
        let rhs = |s: [f64; 2], x: f64| [s[1], b * (x - s[0]) - a * s[1]];
        let mut s = [sig[0], 0.0];
        let mut out = vec![s[0]];
        for i in 1..sig.len() {
            let (x0, x1) = (sig[i - 1], sig[i]);
            let xm = 0.5 * (x0 + x1);
            let k1 = rhs(s, x0);
            let k2 = rhs([s[0] + 0.5 * h * k1[0], s[1] + 0.5 * h * k1[1]], xm);
            let k3 = rhs([s[0] + 0.5 * h * k2[0], s[1] + 0.5 * h * k2[1]], xm);
            let k4 = rhs([s[0] + h * k3[0], s[1] + h * k3[1]], x1);
            for j in 0..2 {
                s[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
            }
            out.push(s[0]);
        }
        sig = out;
    }
    sig
}

/// The test of `spec` as a logger with a Bessel low-pass at `fc_over_fs` would
/// record it (module docs). The truth is unchanged.
fn filtered(spec: &TestSpec, fc_over_fs: f64) -> Synthetic {
    const OVER: usize = 20;
    let fine = generate(&TestSpec {
        fs_hz: spec.fs_hz * OVER as f64,
        sigma_mm: 0.0,
        drift_mm: 0.0,
        spikes: 0,
        ..spec.clone()
    });
    let h = 1.0 / fine.spec.fs_hz;
    let y = bessel4(&fine.x_mm, h, fc_over_fs * spec.fs_hz);
    let mut rng = Rng::new(spec.seed ^ 0xF1);
    let offset = (rng.uniform() * OVER as f64) as usize;
    let idx: Vec<usize> = (offset..y.len()).step_by(OVER).collect();
    let duration = fine.t[fine.t.len() - 1];
    let t: Vec<f64> = idx.iter().map(|&i| fine.t[i]).collect();
    let x: Vec<f64> = idx
        .iter()
        .map(|&i| {
            let v = y[i] + spec.drift_mm * fine.t[i] / duration + spec.sigma_mm * rng.normal();
            (v * 100.0).round() / 100.0
        })
        .collect();
    Synthetic {
        spec: spec.clone(),
        t,
        x_mm: x,
        ..fine
    }
}

fn physics(s: &Synthetic) -> Physics {
    Physics {
        rocking: if s.spec.one_sided() {
            rocklab::wall::Rocking::OneSided
        } else {
            rocklab::wall::Rocking::TwoSided
        },
        lever_arm_mm: s.spec.lever_mm,
        p_guess: s.spec.p2().sqrt(),
    }
}

/// The filter is checked on its own: a unit step through it settles to 1 and
/// its output at 1/(2π fc) after the step matches the analytic 4th-order Bessel
/// step response's slow rise (below 0.2), not the input's jump.
#[test]
fn the_bessel_filter_has_unity_gain_and_rounds_a_step() {
    let h = 1e-4;
    let u: Vec<f64> = (0..20000).map(|i| if i >= 100 { 1.0 } else { 0.0 }).collect();
    let y = bessel4(&u, h, 10.0);
    assert!((y[19999] - 1.0).abs() < 1e-6, "{}", y[19999]);
    let i = 100 + (1.0 / (2.0 * std::f64::consts::PI * 10.0) / h) as usize;
    assert!(y[i] > 0.0 && y[i] < 0.2, "{}", y[i]);
}

/// Sharp impacts through a Bessel low-pass at 0.25 fs: no peak is read as a
/// resolved contact (20 idealised draws, 120 peaks).
#[test]
fn a_filtered_sharp_impact_is_not_read_as_a_resolved_contact() {
    let mut local = Vec::new();
    for seed in 0..20 {
        let s = filtered(&draw(seed, Family::Rigid).spec, 0.25);
        let Ok(a) = analyse(&s.t, &s.x_mm, &physics(&s), &PeakOptions::default()) else {
            continue;
        };
        for p in a.resolved_peaks() {
            if p.method == ReadingMethod::LocalExtreme {
                local.push((seed, p.k));
            }
        }
    }
    assert!(local.is_empty(), "filtered kinks read as resolved contacts (seed, k): {local:?}");
}

/// On the idealised generator's own logs every peak keeps the kink model.
#[test]
fn sharp_impacts_keep_the_kink_model() {
    for seed in 0..20 {
        let s = draw(seed, Family::Rigid);
        let a = analyse(&s.t, &s.x_mm, &physics(&s), &PeakOptions::default()).unwrap();
        assert!(a.resolved_peaks().iter().all(|p| p.method == ReadingMethod::KinkModel), "seed {seed}");
    }
}
