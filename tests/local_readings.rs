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

/// Every impact of a campaign reduced against the engine's truth.
struct EveryImpact {
    /// Impacts listed by the truth (see [`every_impact`]).
    listed: usize,
    /// (test, k, r − r_true, u(r)) of every listed impact reported by an ok test.
    reported: Vec<(String, usize, f64, f64)>,
    /// Tests flagged (suspect or failed), and the worst error (pp) of any table
    /// value of the ok tests.
    flagged: usize,
    worst_ok_pp: f64,
    /// The flagged tests' impacts read by the contact model alone
    /// ([`rocklab::impacts::local_impacts`]): listed, and (test, k, error, u).
    flagged_listed: usize,
    flagged_local: Vec<(String, usize, f64, f64)>,
    /// Issue 20's law criterion on the reported impacts: (side, amplitude
    /// |θ|/α from the log, true r), and the campaign's law where it has one.
    law_points: Vec<(rocklab::wall::Side, f64, f64)>,
    law: Option<rocklab::restitution_law::RestitutionLaw>,
}

/// "RMS …, median |err|/u …" of impacts (test, k, error, u); None where there are none.
fn accuracy(impacts: &[(String, usize, f64, f64)]) -> Option<String> {
    let mut z: Vec<f64> = impacts.iter().map(|x| x.2.abs() / x.3).collect();
    z.sort_by(f64::total_cmp);
    let rms = (impacts.iter().map(|e| e.2 * e.2).sum::<f64>() / impacts.len().max(1) as f64).sqrt();
    z.get(z.len() / 2).map(|m| format!("RMS {rms:.4}, median |err|/u {m:.2}"))
}

impl EveryImpact {
    fn coverage(&self) -> f64 {
        self.reported.len() as f64 / self.listed.max(1) as f64
    }
    fn rms(&self) -> f64 {
        (self.reported.iter().map(|e| e.2 * e.2).sum::<f64>() / self.reported.len().max(1) as f64).sqrt()
    }
    /// RMS of the law read at each reported impact's amplitude against the
    /// truth, and of the best constant pair (each side's mean true r; one
    /// constant where the law is shared by both sides), as `tests/law.rs`
    /// scores the public campaigns.
    fn law_rms(&self) -> Option<(f64, f64)> {
        use rocklab::wall::Side;
        let law = self.law.as_ref()?;
        let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len().max(1) as f64).sqrt();
        let err: Vec<f64> = self.law_points.iter().map(|(side, a, r)| law.r(*side, *a) - r).collect();
        let shared = law.parameters.shared;
        let mean = |s: Side| {
            let v: Vec<f64> = self.law_points.iter().filter(|p| shared || p.0 == s).map(|p| p.2).collect();
            v.iter().sum::<f64>() / v.len().max(1) as f64
        };
        let (ci, co) = (mean(Side::Inward), mean(Side::Outward));
        let cst: Vec<f64> = self
            .law_points
            .iter()
            .map(|(side, _, r)| if *side == Side::Inward { ci } else { co } - r)
            .collect();
        Some((rms(&err), rms(&cst)))
    }
    fn print(&self, name: &str) {
        if let Some((law, cst)) = self.law_rms() {
            println!(
                "{name}: the law at the {} reported impacts' amplitudes: RMS {law:.4} against the truth (best constant pair {cst:.4})",
                self.law_points.len()
            );
        }
        // With no impact reported (every test flagged) there is no RMS to print.
        let shown = accuracy(&self.reported).unwrap_or_else(|| "no RMS: none reported".into());
        println!(
            "{name}: {} of {} listed impacts ({:.0} %), {shown}; {} tests flagged, ok tests within {:.2} pp",
            self.reported.len(),
            self.listed,
            100.0 * self.coverage(),
            self.flagged,
            self.worst_ok_pp
        );
        for x in &self.reported {
            println!("  {} k{} {:+.4} (u {:.4})", x.0, x.1, x.2, x.3);
        }
        if self.flagged > 0 {
            let shown = accuracy(&self.flagged_local).unwrap_or_else(|| "no RMS: none read".into());
            println!(
                "  flagged tests, the contact model alone: {} of their {} listed impacts, {shown}",
                self.flagged_local.len(),
                self.flagged_listed,
            );
            for x in &self.flagged_local {
                println!("    {} k{} {:+.4} (u {:.4})", x.0, x.1, x.2, x.3);
            }
        }
    }
}

/// Every impact of an engine-made campaign of `fixtures/campaigns` against its
/// truth (issue 20's criterion): the listed impacts are, where truth.json has
/// `e_true`, those where the engine saw a contact (`e_engine` a number ≤ 1,
/// null where the old edge no longer lifts off), with r = `e_over_eH`. The
/// hold-outs list no `e_true`; there r = |v_{k+1}/v_k| / e_H (the public
/// truth's definition of `e_true[].e`), and the impacts listed are those
/// where the wall rocks through both half-cycles the impact joins (an edge off
/// the bedding for at least half of each, `lift_fraction_per_half_cycle`; the
/// listing of tests/law.rs `truth_listed`), the first of the pair returned;
/// the second lists every impact between two of the truth's peaks, the
/// wall's vibrations on its bedding after it stops rocking included (the
/// listing before the R3 session).
fn every_impact(name: &str) -> (EveryImpact, EveryImpact) {
    every_impact_in(&std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns").join(name))
}

/// The truth's impacts of one test (see [`every_impact`]): (k, r, whether the
/// wall rocks through both half-cycles).
fn truth_impacts(tt: &serde_json::Value, e_h: f64) -> Vec<(usize, f64, bool)> {
    if let Some(list) = tt["e_true"].as_array() {
        return list
            .iter()
            .filter(|e| e["e_engine"].as_f64().is_some_and(|x| x <= 1.0))
            .map(|e| (e["k"].as_u64().unwrap() as usize, e["e_over_eH"].as_f64().unwrap(), true))
            .collect();
    }
    let v: Vec<f64> = tt["peaks"]
        .as_array()
        .unwrap()
        .iter()
        .map(|q| q["velocity_mm_s"].as_f64().unwrap())
        .collect();
    let lift: Vec<f64> = tt["sim"]["lift_fraction_per_half_cycle"]
        .as_array()
        .map(|l| l.iter().filter_map(|x| x.as_f64()).collect())
        .unwrap_or_default();
    let rocks = |k: usize| lift.get(k).is_some_and(|&f| f >= 0.5);
    v.windows(2)
        .enumerate()
        .map(|(k, w)| (k, (w[1] / w[0]).abs() / e_h, rocks(k) && rocks(k + 1)))
        .collect()
}

/// A flagged test's impacts read by the contact model alone
/// ([`rocklab::impacts::local_impacts`]).
fn flagged_local(r: &rocklab::reduction::Reduced, c: &rocklab::ingest::Campaign, lever_mm: f64, e_h: f64) -> rocklab::impacts::ImpactTable {
    use rocklab::peaks::late::{arc_contact_peaks, contact_peaks, nominal_arc, CONTACT_POST_S};
    let p = c.wall().rocking_part().p_squared().sqrt();
    let arc = r.analysis.small_arc.unwrap_or_else(|| nominal_arc(p, c.alpha_rad, lever_mm));
    let two = c.rocking == rocklab::wall::Rocking::TwoSided;
    let peaks = if two {
        arc_contact_peaks(&r.analysis, &r.log.time_s, lever_mm, arc, 12, CONTACT_POST_S)
    } else {
        contact_peaks(&r.analysis, &r.log.time_s, lever_mm, arc, 12, CONTACT_POST_S)
    };
    let geo = rocklab::impacts::Geometry {
        time_s: &r.log.time_s,
        lever_arm_mm: lever_mm,
        alpha_rad: c.alpha_rad,
    };
    rocklab::impacts::local_impacts(&peaks, e_h, &geo, arc, two)
}

/// [`every_impact`] of the campaign in `dir`.
fn every_impact_in(dir: &std::path::Path) -> (EveryImpact, EveryImpact) {
    use rocklab::ingest::Campaign;
    use rocklab::reduce::reduce_campaign;
    let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
    let e_h = campaign.e_housner;
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let res = reduce_campaign(campaign, PeakOptions::default());
    let empty = || EveryImpact {
        listed: 0,
        reported: Vec::new(),
        flagged: 0,
        worst_ok_pp: 0.0,
        flagged_listed: 0,
        flagged_local: Vec::new(),
        law_points: Vec::new(),
        law: res.law.as_ref().ok().map(|l| l.law),
    };
    let (mut rocking, mut all) = (empty(), empty());
    for t in &res.tests {
        let tt = truth["tests"].as_array().unwrap().iter().find(|x| x["id"] == t.spec.id.as_str()).unwrap();
        let listed = truth_impacts(tt, e_h);
        rocking.listed += listed.iter().filter(|l| l.2).count();
        all.listed += listed.len();
        let Some(r) = t.result.as_ref().ok().filter(|r| r.analysis.quality.is_ok()) else {
            rocking.flagged += 1;
            all.flagged += 1;
            rocking.flagged_listed += listed.iter().filter(|l| l.2).count();
            all.flagged_listed += listed.len();
            let Ok(r) = t.result.as_ref() else { continue };
            let local = flagged_local(r, &res.campaign, t.spec.lever_arm_m * 1e3, e_h);
            for (k, r_true, rocks) in listed {
                if let Some(i) = local.impacts.iter().find(|i| i.k == k) {
                    let entry = (t.spec.id.clone(), k, i.r - r_true, i.r_u.unwrap_or(f64::NAN));
                    if rocks {
                        rocking.flagged_local.push(entry.clone());
                    }
                    all.flagged_local.push(entry);
                }
            }
            continue;
        };
        let c = serde_json::to_value(r.coefficients).unwrap();
        for key in ["r", "r_plus", "r_minus", "r1", "r1_plus", "r1_minus", "r2"] {
            let pp = 100.0 * (c[key].as_f64().unwrap() - tt[key].as_f64().unwrap()).abs();
            rocking.worst_ok_pp = rocking.worst_ok_pp.max(pp);
            all.worst_ok_pp = all.worst_ok_pp.max(pp);
        }
        for (k, r_true, rocks) in listed {
            if let Some(i) = r.impacts.impacts.iter().find(|i| i.k == k) {
                let entry = (t.spec.id.clone(), k, i.r - r_true, i.r_u.unwrap_or(f64::NAN));
                if rocks {
                    rocking.reported.push(entry.clone());
                    rocking.law_points.push((i.side, i.amplitude_over_alpha, r_true));
                }
                all.reported.push(entry);
                all.law_points.push((i.side, i.amplitude_over_alpha, r_true));
            }
        }
    }
    (rocking, all)
}

/// Issue 20's per-impact criterion on the engine-made campaigns: each listed
/// impact's r within RMS 0.015 for ≥ 80 % of the listed impacts (the
/// hold-outs' impacts listed while the wall rocks, [`every_impact`]), asserted
/// on the public campaigns and the two-sided hold-out. When written: public
/// two-sided 100 % at RMS 0.0053, public one-sided 94 % at 0.0123 (88 % at 0.0120
/// since the contact readings' model-form term), hold-out
/// two-sided 83 % at 0.0087 (docs/restitution-law.md). The one-sided hold-out
/// met it too (81 % at 0.0100) while H1_140_1 was suspect; since the
/// twentieth session that test is ok (`peaks::exits_only_misfit`), and its
/// impacts 3 and 4, read from the global fit's v₄ (+4.4 % at u 4.6 %), are
/// 0.063 and 0.046 off at u(r) 0.063 and 0.072: 97 % at RMS 0.0166. There the
/// criterion is kept as [`every_impact_on_the_one_sided_holdout`], ignored and
/// failing, and this test asserts what holds: the coverage and that the stated
/// u covers the errors (≥ 95 % of the reported impacts within 2 u). Printed
/// beside: every impact between two of the truth's peaks, the bedding's
/// vibrations after the wall stops rocking included, and what the flagged
/// tests' impacts read by the contact model alone would be. Minutes in a
/// debug build:
/// `cargo test --release --test local_readings every_impact -- --include-ignored --nocapture`.
#[test]
#[cfg_attr(debug_assertions, ignore = "minutes in a debug build; run in release")]
fn every_impact_against_the_engine_truth() {
    for name in [
        "mujoco-public-two-sided",
        "mujoco-holdout-two-sided",
        "mujoco-public-one-sided",
        "mujoco-holdout-one-sided",
    ] {
        let (e, all) = every_impact(name);
        e.print(name);
        all.print(&format!("{name}, every impact between two of the truth's peaks"));
        if name == "mujoco-holdout-one-sided" {
            let within = e.reported.iter().filter(|x| x.2.abs() <= 2.0 * x.3).count() as f64 / e.reported.len().max(1) as f64;
            assert!(
                e.coverage() >= 0.8 && within >= 0.95,
                "{name}: {:.2} of the listed impacts, {within:.2} within 2 u",
                e.coverage()
            );
        } else {
            assert_per_impact_criterion(name, &e);
        }
    }
}

/// ≥ 80 % of the listed impacts reported, at RMS ≤ 0.015 (issue 20).
fn assert_per_impact_criterion(name: &str, e: &EveryImpact) {
    assert!(
        e.coverage() >= 0.8 && e.rms() <= 0.015,
        "{name}: {:.2} of the listed impacts at RMS {:.4}",
        e.coverage(),
        e.rms()
    );
}

/// Issue 20's per-impact criterion on the one-sided hold-out (see
/// [`every_impact_against_the_engine_truth`]): not met from the session that
/// let H1_140_1 through (97 % of the listed impacts at RMS 0.0166) until the
/// contact model's free arcs took the centre that fits them
/// (`late::centre_of`, thirtieth session: 97 % at RMS 0.0109).
#[test]
fn every_impact_on_the_one_sided_holdout() {
    let name = "mujoco-holdout-one-sided";
    let (e, _) = every_impact(name);
    e.print(name);
    assert_per_impact_criterion(name, &e);
}

/// The impacts after the table on a one-sided wall of the second engine
/// (`fixtures/campaigns/penalty-one-sided-s3`, `tools/penalty_campaign.py`,
/// Hunt–Crossley bedding, a nonlinear restraint): with the global fit's centre
/// in the contact model's free arcs (387–389 mm against the engine's
/// 384–386) most tests' lists stopped at the table's impacts (27 of 45 listed,
/// 60 %, on the campaign this fixture was copied from); with the centre the
/// arcs fit (`late::centre_of`) they run on (34 of 45, 76 %, RMS 0.0116).
/// Asserted: at least 70 % (between the two), at issue 20's RMS 0.015.
#[test]
fn the_late_impacts_of_a_second_engines_one_sided_wall_are_read() {
    let name = "penalty-one-sided-s3";
    let (e, _) = every_impact(name);
    e.print(name);
    assert!(
        e.coverage() >= 0.7 && e.rms() <= 0.015,
        "{name}: {:.2} of the listed impacts at RMS {:.4}",
        e.coverage(),
        e.rms()
    );
}

/// Issue 20's per-impact criterion on a two-sided wall the estimator was never
/// tuned on (`fixtures/campaigns/mujoco-fresh-two-sided`, `--preset
/// fresh-two-sided --seed 2921`, made in the twenty-ninth session): the
/// impacts listed while the wall rocks (see [`every_impact`]). Measured when
/// it was made: 49 of 49 listed impacts reported, RMS 0.0049.
#[test]
fn every_impact_on_a_fresh_two_sided_wall() {
    let name = "mujoco-fresh-two-sided";
    let (e, _) = every_impact(name);
    e.print(name);
    assert_per_impact_criterion(name, &e);
}

/// A late two-sided impact is not read from two kinks where the contact model
/// reads both its peaks near the noise (`impacts::LATE_MISFIT_LIMIT`):
/// `fixtures/campaigns/mujoco-holdout-two-sided-s3504` (`--preset
/// holdout-two-sided --seed 3504`, thirty-fifth session). Its 1000 Hz test
/// H2_110_2 reported impact 5 from two kinks, 0.101 off the truth at u 0.029
/// (3.5 u; the campaign's per-impact RMS 0.0234): peak 6's kink read the
/// slope into its crossing, 9.1 ms past the peak. With the contact model's
/// readings at χ²/ν 1.33 and 1.38 it is 0.006 off, and the campaign's RMS
/// 0.0061 (0.0072 over 25 impacts once its 100 Hz test was no longer flagged,
/// `checks::contact_too_long`).
/// Asserted: every reported impact within 3 of its u, and issue 20's RMS.
/// (Its 70 mm test is flagged, so its coverage is 76 %: 25 of 33 listed.)
#[test]
#[cfg_attr(debug_assertions, ignore = "a campaign reduced; run in release")]
fn late_two_sided_impacts_are_not_read_from_kinks_past_their_peaks() {
    let name = "mujoco-holdout-two-sided-s3504";
    let (e, _) = every_impact(name);
    e.print(name);
    let worst = e.reported.iter().map(|x| x.2.abs() / x.3).fold(0.0, f64::max);
    assert!(worst <= 3.0, "{name}: an impact {worst:.1} u off");
    assert!(e.rms() <= 0.015, "{name}: RMS {:.4}", e.rms());
}

/// Campaigns made by `tools/mujoco_campaign.py --preset fresh-*` (walls the
/// estimator was never tuned on), in the directories listed in
/// `FRESH_CAMPAIGNS` (separated by ':'): the per-impact figures and the
/// table's (tests flagged, worst value of the ok tests), printed
/// (docs/restitution-law.md).
#[test]
#[ignore = "needs campaigns made with MuJoCo outside the repository"]
fn fresh_engine_campaigns() {
    let dirs = std::env::var("FRESH_CAMPAIGNS").expect("FRESH_CAMPAIGNS=dir:dir");
    for dir in dirs.split(':') {
        let (e, all) = every_impact_in(std::path::Path::new(dir));
        e.print(dir);
        all.print(&format!("{dir}, every impact between two of the truth's peaks"));
    }
}

/// (reading kind or "ratio", k mod 2, k ≥ 5).
type ErrorClass = (&'static str, usize, bool);

/// Why one-sided late impacts are not read from kink readings (issue 20,
/// docs/restitution-law.md, "Every impact"): every peak of each test of an
/// engine-made campaign read locally ([`rocklab::peaks::late`]), each
/// reading's relative error against the truth's velocity peak, by side (k even
/// ends an outward half-cycle: on a one-sided wall the free arc, its impact on
/// the base and the transverse walls; k odd ends an inward one: on a one-sided
/// wall the short excursion into the transverse walls, its impact on the
/// base), and the relative error of |v_{k+1}/v_k| from two kink readings (what
/// a late r would be), for the late peaks (k ≥ 5) and the earlier ones.
/// Printed; the campaign is `mujoco-public-one-sided` or the directory in
/// `LATE_CAMPAIGN` (truth.json with `peaks`).
/// `cargo test --test local_readings late_readings_by_side -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement, printed (docs/restitution-law.md)"]
fn late_readings_by_side() {
    use rocklab::ingest::Campaign;
    use rocklab::peaks::late::Reading;
    use rocklab::reduce::reduce_campaign;
    let dir = match std::env::var("LATE_CAMPAIGN") {
        Ok(d) => std::path::PathBuf::from(d),
        Err(_) => std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns/mujoco-public-one-sided"),
    };
    let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
    let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
    let res = reduce_campaign(campaign, PeakOptions::default());
    // (kind, side, late) -> relative errors and relative u; ("ratio", side of
    // impact k, late) -> relative error of |v_{k+1}/v_k| from two kink readings.
    let mut errs: std::collections::BTreeMap<ErrorClass, Vec<(f64, f64)>> = Default::default();
    for t in &res.tests {
        let tt = truth["tests"].as_array().unwrap().iter().find(|x| x["id"] == t.spec.id.as_str()).unwrap();
        let peaks = tt["peaks"].as_array().unwrap();
        let Ok(r) = t.result.as_ref() else { continue };
        println!("{} ({})", t.spec.id, if r.analysis.quality.is_ok() { "ok" } else { "flagged" });
        let mut previous: Option<(usize, f64)> = None;
        for p in r.analysis.late_peaks(&r.log.time_s, t.spec.lever_arm_m * 1000.0, 0, 12) {
            let Some(q) = peaks.get(p.k) else { break };
            let (vt, tt_k) = (q["velocity_mm_s"].as_f64().unwrap(), q["time_s"].as_f64().unwrap());
            let rel = |x: Option<Reading>| x.map(|x| (x.velocity_mm_s / vt - 1.0, x.u_mm_s / vt.abs()));
            let show = |x: Option<(f64, f64)>| x.map_or("       -      ".to_string(), |(e, u)| format!("{e:+.3} ± {u:.3}"));
            println!(
                "  k{:<2} apex {:7.2} mm  truth {:7.1} mm/s, {:.1} ms before the crossing;  smooth {}  kink {}",
                p.k,
                p.apex_mm,
                vt,
                (p.crossing_s - tt_k) * 1e3,
                show(rel(p.smooth)),
                show(rel(p.kink))
            );
            let kink = rel(p.kink);
            if let (Some((k0, e0)), Some((e1, u1))) = (previous, kink) {
                errs.entry(("ratio", k0 % 2, k0 >= 5))
                    .or_default()
                    .push(((1.0 + e1) / (1.0 + e0) - 1.0, u1));
            }
            previous = kink.map(|x| (p.k, x.0));
            for (kind, x) in [("smooth", rel(p.smooth)), ("kink", kink)] {
                if let Some(x) = x {
                    errs.entry((kind, p.k % 2, p.k >= 5)).or_default().push(x);
                }
            }
        }
    }
    for ((kind, side, late), v) in &errs {
        let n = v.len() as f64;
        let mean = v.iter().map(|x| x.0).sum::<f64>() / n;
        let rms = (v.iter().map(|x| x.0 * x.0).sum::<f64>() / n).sqrt();
        let mut z: Vec<f64> = v.iter().map(|x| x.0.abs() / x.1).collect();
        z.sort_by(f64::total_cmp);
        println!(
            "{kind:>6} k {} {}: {} readings, mean error {mean:+.3}, RMS {rms:.3}, median |err|/u {:.2}",
            if *side == 0 { "even" } else { "odd " },
            if *late { "k >= 5" } else { "k < 5 " },
            v.len(),
            z[z.len() / 2]
        );
    }
}

/// The one-sided contact model's readings ([`rocklab::peaks::late::read_contact`]:
/// the half-cycle's free motion, free arc or lossy restraint, plus the
/// contact's force from its onset) against the engine's truth: each peak's
/// relative error, and the relative error of each ratio |v_{k+1}/v_k| of two
/// contact readings, by side and by the window's end after the crossing (12 and
/// 20 ms). Printed; campaigns: the two one-sided MuJoCo fixtures, or the
/// directories in `CONTACT_CAMPAIGNS` (':'-separated, truth.json with `peaks`).
/// `cargo test --release --test local_readings contact_readings -- --ignored --nocapture`.
#[test]
#[ignore = "a measurement, printed (docs/restitution-law.md)"]
fn contact_readings_by_side() {
    use rocklab::ingest::Campaign;
    use rocklab::peaks::late::contact_peaks;
    use rocklab::reduce::reduce_campaign;
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/campaigns");
    let dirs: Vec<std::path::PathBuf> = match std::env::var("CONTACT_CAMPAIGNS") {
        Ok(d) => d.split(':').map(std::path::PathBuf::from).collect(),
        Err(_) => vec![root.join("mujoco-public-one-sided"), root.join("mujoco-holdout-one-sided")],
    };
    for dir in dirs {
        let campaign = Campaign::load(&dir.join("campaign.toml")).unwrap();
        let p = campaign.wall().rocking_part().p_squared().sqrt();
        let truth: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(dir.join("truth.json")).unwrap()).unwrap();
        let res = reduce_campaign(campaign, PeakOptions::default());
        for post_ms in [20.0] {
            // (side of the peak or ratio, "peak"/"ratio", late) -> relative errors.
            let mut errs: std::collections::BTreeMap<(usize, &str, bool), Vec<f64>> = Default::default();
            println!("{} (window to {post_ms} ms after the crossing)", dir.display());
            for t in &res.tests {
                let Ok(r) = t.result.as_ref() else { continue };
                let tt = truth["tests"].as_array().unwrap().iter().find(|x| x["id"] == t.spec.id.as_str()).unwrap();
                let vt = |k: usize| tt["peaks"].as_array().unwrap().get(k).and_then(|q| q["velocity_mm_s"].as_f64());
                let lever_mm = t.spec.lever_arm_m * 1000.0;
                let arc = if std::env::var("CONTACT_NOMINAL").is_ok() {
                    rocklab::peaks::late::nominal_arc(p, res.campaign.alpha_rad, lever_mm)
                } else {
                    r.analysis.small_arc.unwrap()
                };
                let read = if truth["rocking"] == "two-sided" {
                    rocklab::peaks::late::arc_contact_peaks(&r.analysis, &r.log.time_s, lever_mm, arc, 12, post_ms * 1e-3)
                } else {
                    contact_peaks(&r.analysis, &r.log.time_s, lever_mm, arc, 12, post_ms * 1e-3)
                };
                let mut line = format!("  {} ({}):", t.spec.id, if r.analysis.quality.is_ok() { "ok" } else { "flagged" });
                let rel: Vec<(usize, Option<f64>, bool, f64)> = read
                    .iter()
                    .map(|q| {
                        let (k, c) = (q.k, q.reading);
                        let u = c.map_or(f64::NAN, |c| c.reading.u_mm_s / c.reading.velocity_mm_s.abs());
                        (
                            k,
                            c.and_then(|c| Some(c.reading.velocity_mm_s / vt(k)? - 1.0)),
                            c.is_some_and(|c| c.fits_noise()),
                            u,
                        )
                    })
                    .collect();
                for &(k, e, fits, u) in &rel {
                    let Some(e) = e else { continue };
                    let q = read.iter().find(|q| q.k == k).and_then(|q| q.reading).unwrap();
                    line += &format!(" k{k} {e:+.3}({u:.3}, {:.1}/{}){}", q.chi2, q.n - 5, if fits { "" } else { "*" });
                    errs.entry((k % 2, "peak", k >= 5)).or_default().push(e);
                }
                println!("{line}");
                let mut ratios = String::from("    ratios:");
                for w in rel.windows(2) {
                    if let ((k, Some(a), _, _), (_, Some(b), _, _)) = (w[0], w[1]) {
                        let e = (1.0 + b) / (1.0 + a) - 1.0;
                        ratios += &format!(" r{k} {e:+.3}");
                        errs.entry((k % 2, "ratio", k >= 5)).or_default().push(e);
                    }
                }
                println!("{ratios}");
            }
            for ((side, kind, late), v) in &errs {
                let n = v.len() as f64;
                let mean = v.iter().sum::<f64>() / n;
                let rms = (v.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
                println!(
                    "  {kind:>5} k {} {}: {} readings, mean {mean:+.3}, RMS {rms:.3}",
                    if *side == 0 { "even" } else { "odd " },
                    if *late { "k >= 5" } else { "k < 5 " },
                    v.len()
                );
            }
        }
    }
}
