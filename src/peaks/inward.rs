//! The inward peaks of a one-sided wall with compliant contacts, read by the
//! contact model (eighteenth session, issue #18).
//!
//! A one-sided wall's odd half-cycles (k = 1, 3, 5) are pushes into the
//! transverse walls; their peak v_k is the speed at the crossing where the
//! wall leaves them. The global fit ([`super::model`]) reads these peaks from
//! one lossy restraint arc per half-cycle and a contact phase per crossing,
//! whose entry shape is not the engine's (docs/accuracy.md, "One-sided: why v₁
//! and v₃ read 2–3.7 % low"): on the MuJoCo one-sided campaigns its odd peaks
//! read 1–5 % low while its even peaks (free arcs) read about 1 % low, so the
//! ratios r₁ = |v₁/v₀|/e_H and r⁻ carry the difference, up to 1.2 pp on ok tests
//! (1.7 pp on a flagged one). The contact model ([`super::late::contact_peaks`],
//! docs/restitution-law.md) reads each push on its own, from a quarter of its
//! length to 20 ms past its crossing, as a damped spring-dashpot arc plus the
//! contact's force: its readings of the same peaks are 0–2 % low.
//!
//! The rule: on a one-sided log whose global fit chose contact phases, seen
//! through no logger filter (the contact model does not model one), with
//! status ok and stated uncertainties, every odd peak of the table is replaced
//! by its contact reading where every one of them fits the samples to the noise
//! (χ² ≤ ν + 3√(2ν)); otherwise none is, unless the global fit reads one of
//! the pushes to worse than 5 % of its speed ([`LOOSE_PUSH`]: the test could
//! not be vouched for with it), where a reading up to χ²/ν = 5 is taken too,
//! its u scaled by √(χ²/ν), if every push's reading is then within 5 % of its
//! speed (thirty-first session). All of one side or none: the tables
//! are ratios, which cancel a bias that the peaks of one side share only if one
//! reading gives them all (as [`super::local`] keeps one method per test). A
//! replacement that would make any ratio of consecutive peaks exceed 1 (a wall
//! gaining energy) is not made.
//!
//! "Status ok" leaves out one reason that concerns the global reading of a
//! push alone: its two readings of where the half-cycle ends, up to the
//! fitted zero and up to the rest line, differ by more than 20 %
//! ([`super::checks::zero_readings_disagree`]). [`super::analyse`] defers it
//! ([`Analysis::deferred_reason`]) and adds it back only where this rule
//! does not replace the pushes: a contact reading does not depend on where
//! the global model's zero lies, and since the forty-fifth session its u
//! does not carry that spread either (below).
//! (Twenty-fifth session: q1-s1405 Q1_170_1, 200 Hz, peak 5 moved by 26 %
//! between the two and was flagged, every value within 0.64 pp; its pushes'
//! contact readings are −0.9, +0.9 and +1.6 % of the truth, and it is ok,
//! within 0.76 pp. docs/accuracy.md, "One-sided: a push that does not
//! settle".)
//!
//! Uncertainty (forty-fifth session): a replaced peak is the contact
//! reading's, and so is its u:
//!
//!   u² = u_c² + d²/3 + (b v_c)²,
//!
//! - u_c, the contact reading's own u (fit, window, onset) with the contact
//!   model's form ([`crate::impacts::CONTACT_READING_FORM`], 1 % of the
//!   speed) in quadrature, as the per-impact table carries the same
//!   readings; independent from reading to reading;
//! - d = v_global − v_contact, the two readings' disagreement, the truth
//!   taken as anywhere between them (rectangular, d²/3, as the two models of
//!   the contacts in [`super::uncertainty::add_model_spread`]); independent;
//! - b = [`SHARED_FORM`], 1.4 %: the contact model's bias, which the contact
//!   readings of one test share. Two replaced peaks j, k have covariance
//!   b² v_j v_k, so that it cancels in a ratio of two of them; a replaced
//!   peak has none with the peaks the global fit reads.
//!
//! Why b, measured (release, `engine_campaigns`, the 28 one-sided MuJoCo
//! campaigns of the forty-third session, seeds 4301–4325): over the 124 ok
//! tests the 400 contact readings that replace a peak read −1.2 % of the
//! truth on average; a test's mean scatters 0.63 % from test to test (RMS of
//! the test means 1.37 %: b) and the readings of one test 0.6 % about it,
//! which u_c (medians 1.1–1.3 %) covers. Without b, 16 of the 400 (4 %) were
//! more than 2 u off, and two campaigns fell below 90 % of their peaks within
//! 2 u.
//!
//! Why the readings share a bias (forty-sixth session): a push ends in a
//! corner, the velocity continuous and the acceleration jumping from positive
//! to negative where the bedding bears or the pivot changes toe (both engines,
//! re-run at 0.1 ms), and the contact model's smooth arc rounds it off, below
//! the logger's noise. Columns that let the acceleration jump at the crossing
//! remove the mean bias but widen the scatter at 200 Hz and make later pushes
//! run off, so b stays (docs/accuracy.md, "Forty-sixth session").
//!
//! Until this session the replaced peak kept the global reading's
//! model-form terms (the other model of the contacts, the zero's spread)
//! and their correlations, the global fit's statistical part swapped for
//! the reading's, with √(u_c² + d²) as a floor. Those terms are spreads
//! between the global fit's models of the exit, which the contact reading
//! does not use: on the same ok tests they put pushes 1, 3 and 5 at ± 2.4,
//! 4.0 and 7.8 % (medians) while the readings were within 1.5 % RMS, every
//! table value of those tests but two was within 1 u of the truth (852 of
//! 854), and two tests whose values were all within 0.94 pp were flagged
//! for r₁ read to ± 6.4 and ± 7.6 pp (h1-s4307 H1_140_2, where the global
//! fit read the pushes 7 % above the contact readings and the truth, and
//! q1-s4315 Q1_160_1). Now both are ok; every peak the rule replaces on an
//! ok test is within 2 u of the truth (407 of 407) and every table value of
//! the ok tests (868); issue 18's criterion on those campaigns went from
//! 22 to 24 of 28.
//!
//! A push the global fit does not read at all, its own u (√f_kk, f the
//! global fit's own covariance: s²(JᵀJ)⁻¹ and the directions the log only
//! bounds, [`Analysis::fit_covariance`]) above 20 % of its speed
//! ([`UNDETERMINED`]), takes of the disagreement only the part that the
//! global fit's own variance does not explain:
//!
//!   u² = u_c² + max(0, d² − f_kk) + (b v_c)².
//!
//! (Twenty-fifth session: q1-s1424 Q1_170_1, 200 Hz, peaks 1, 3, 5 at
//! ± 200–220 % own; seeds 1424 and 1416 went from one flagged test each to
//! none, every value of their ok tests within 0.79 and 0.88 pp;
//! docs/accuracy.md, "One-sided: pushes the global fit does not read".)
//!
//! Measured (release, `tests/truth.rs` `engine_campaigns`, docs/accuracy.md):
//! the worst value of the ok tests falls on 9 of 11 one-sided MuJoCo campaigns
//! (hold-out seed 33: 1.16 → 0.57 pp; seed 34: 1.04 → 0.98 pp); the two tests
//! still above 1.0 pp are logged at 100 Hz, where the pushes are too short for
//! the contact model and nothing is replaced.
//!
//! # Late landings
//! A compliant bedding bears once the wall comes within a small tilt of θ = 0,
//! so the slower the landing, the earlier before the crossing its speed turns
//! (MuJoCo's q1-s1428 Q1_140_1: about 4, 7 and 10 ms before θ = 0 at the
//! landings that end half-cycles 0, 2 and 4). The global fit has one contact
//! shape per direction, which the fast first landings set; at a later one it
//! runs the free arc on too long and reads the landing fast (that test's peak 4
//! +5.2 %, the hold-out's H1_140_1 +4.4 %, r⁻ 1.3 and 1.2 pp off with status
//! ok; docs/probes/late-landing-q1-s1428.png). The contact model reads each
//! landing with its own onset (−0.7 and −0.6 %).
//!
//! The rule: a landing of the table from peak 4 on ([`FIRST_LATE_LANDING`]; k
//! even) is replaced by its contact reading where the global fit's residuals
//! within ± 15 ms of it stand out from the fit's own, RMS over their robust
//! spread over the whole fit at least [`LANDING_STANDS_OUT`]
//! ([`Analysis::local_misfit`]; the data say the global model does not describe
//! this landing), and the reading fits the samples to the noise; its u as a
//! push's above (at least √(u_c² + d²)); not where the new peaks would gain
//! energy; with the pushes' replacements in one step. Peak 2 keeps the global
//! reading: the first landings set the global fit's contact shape, and peak 0
//! (the release arc's end, which the contact model does not read) and peak 2
//! share the global reading's bias, which cancels in r₁⁻ and r⁻; read there by
//! the contact model (measured, offline, at the same 2.5), 22 of 39 changed
//! tests read worse, by up to 0.48 pp.
//!
//! # A misfit landing
//! A late landing (k even, from [`FIRST_LATE_LANDING`]) whose impact the
//! deferred reason names ([`super::Analysis::deferred_misfit`]: the global
//! fit's residuals within ± 2 samples of it spread more than 8 σ, and the test
//! is flagged unless the contact model reads the peak, "Residuals that stand
//! out" below) takes its contact reading even where that misses the noise,
//! up to χ²/ν = [`MISFIT_LIMIT`], its u scaled by √(χ²/ν) and within
//! [`LOOSE_PUSH`] of the speed: the pushes' fallback, where the global reading
//! cannot be vouched for. Elsewhere a landing's reading must fit the noise.
//!
//! Why (forty-third session): on 1000 Hz public-like one-sided walls the
//! contact model's χ²/ν over a landing's 200-odd samples is 1.2–1.7 (a small
//! misfit of its form, or in part the noise level's bias on quantised logs,
//! docs/estimator.md, "The noise level": not told apart); the global
//! fit read those landings +3.0 and +3.3 % (q1-s4304 and q1-s4325 Q1_150_1,
//! residuals 13.7 and 10.5 σ around impact 4) and the contact model −0.7 %
//! both times (χ²/ν 1.64 and 1.28). Measured (release, `engine_campaigns`,
//! 28 one-sided MuJoCo campaigns drawn that session, seeds 4301–4325): those
//! two tests became ok, 0.85 → 0.67 and 0.92 → 0.58 pp off; no other test's
//! status or worst value moved; issue 18's criterion 18 → 20 of 28.
//!
//! # Residuals that stand out
//! On a log the rule applies to, residuals that stand out around an impact
//! ([`super::checks::structured_near_impacts`]: the global fit's contact
//! there is not the wall's) are deferred like a push's unsettled zero
//! ([`super::Analysis::deferred_misfit`]): the test is eligible, the rule
//! reads what it reads, and the reason comes back unless the contact model
//! now reads every peak that ends at one of those impacts (peak j ends at
//! impact j: a push's exit, or a late landing; [`reads_past`]). Peak 0 (the
//! release arc's end) and peak 2 keep the global reading, so a misfit there
//! keeps the reason; so does one past the table (unless the table's peaks do
//! not depend on its samples, [`super::past_the_table`], which leaves it out
//! of the list first), and one at a push whose
//! contact reading misses the noise while the global fit reads the pushes
//! well. The replaced peaks carry the readings' disagreement in their u as
//! above.
//!
//! Why: the global fit has one contact shape per direction; where one
//! impact's contact is not that shape its residuals stand out and it reads
//! the peak there wrong, while the contact model reads each push and landing
//! from its own samples (thirty-eighth session, 1000 Hz q1-s3918 Q1_150_1:
//! impact 4 at 8.4 σ, peak 4 +3.0 % by the global fit, −0.5 % by the contact
//! model).
//!
//! Measured (release, `engine_campaigns` on the 100 engine campaigns at
//! hand, docs/accuracy.md "Thirty-eighth session"): nine tests change, each
//! read closer to the truth (worst value 0.88–2.43 → 0.39–1.54 pp); five
//! become ok (0.53, 0.59, 0.61, 1.05 and 1.54 pp, the last two within 0.7 u);
//! no ok test changes; issue 18's campaign criterion 61 → 62 of 100.
//!
//! Measured (thirty-fourth session, release, `engine_campaigns` on the 51
//! one-sided engine campaigns at hand; docs/accuracy.md): the worst value of
//! 23 tests changes, 21 fall (by up to 0.92 pp: c1-s2908 C1_140_1 1.22 → 0.42,
//! the hold-out's H1_140_1 1.19 → 0.79, q1-s1428 Q1_140_1 1.27 → 0.87 pp) and
//! 2 rise (by 0.06 and 0.14 pp, to 0.32 and 0.40); no test changes status; the
//! ok tests beyond 1.0 pp 24 → 21 of 193; issue 18's criterion on the MuJoCo
//! stand-ins 17 → 18 of 20.

use super::late::{contact_peaks, ContactPeak, ContactReading, CONTACT_POST_S};
use super::{Analysis, ReadingMethod};

/// The first landing on the base that [`late_landings`] reads again: peak 4
/// (module docs, "Late landings").
pub const FIRST_LATE_LANDING: usize = 4;

/// How far a late landing's residuals must stand out from the global fit's own
/// ([`Analysis::local_misfit`]) for the contact model to read it: 2.5 times
/// their robust spread (module docs, "Late landings").
pub const LANDING_STANDS_OUT: f64 = 2.5;

/// The most peaks read (as [`crate::reduction::MAX_IMPACT_PEAKS`]): the
/// restraint's (λ, ω) is fitted over every push the log resolves, so the
/// readings are those of the per-impact table, which reuses them
/// ([`Analysis::contact_readings`]).
pub const PEAKS_READ: usize = 12;

/// Replace the odd peaks of a one-sided analysis by their contact readings
/// (module docs). Returns whether it did. The caller decides that the wall is
/// one-sided and the estimator the default one: [`super::analyse`] calls it at
/// the end of the global fit, so that every caller (reduce, the Python
/// binding, the random draws of `synth`) reads the same peaks.
pub fn read_inward_peaks(a: &mut Analysis, t: &[f64], lever_mm: f64) -> bool {
    if !eligible(a) {
        return false;
    }
    let Some(arc) = a.small_arc else { return false };
    let read = contact_peaks(a, t, lever_mm, arc, PEAKS_READ, CONTACT_POST_S);
    let pushes = choose(a, &read);
    let mut all = pushes.clone().unwrap_or_default();
    let n_pushes = all.len();
    all.extend(late_landings(a, &read));
    if gains_energy(a, &all) {
        all.truncate(n_pushes);
    }
    a.contact_readings = Some(read);
    // One application: the shared form couples every replaced peak.
    if !all.is_empty() {
        apply(a, &all);
    }
    pushes.is_some()
}

/// Whether the contact model reads every peak of the table read at one of
/// `impacts` (peak j ends at impact j), and none of them lies past the
/// table: there the global fit's residuals that stand out around those
/// impacts say nothing of the peaks (module docs, "Residuals that stand out").
pub fn reads_past(a: &Analysis, impacts: &[usize]) -> bool {
    impacts.iter().all(|&j| a.methods.get(j) == Some(&ReadingMethod::ContactModel))
}

/// A log the rule applies to: contact phases, no filter in the model, status
/// ok, every peak with a stated u.
fn eligible(a: &Analysis) -> bool {
    a.contact_phases
        && a.response.filter.is_none()
        && a.response.fir_cutoff_hz.is_none()
        && a.quality.is_ok()
        && a.peak_covariance.is_some()
        && a.peaks.iter().all(|p| p.velocity_u_mm_s.is_some())
}

/// One replaced peak: k, time (s), velocity and u (mm/s).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Replacement {
    k: usize,
    time_s: f64,
    velocity_mm_s: f64,
    u_mm_s: f64,
    /// The part of u that every contact reading of the test shares
    /// ([`SHARED_FORM`] of the speed, signed as it; mm/s).
    shared_mm_s: f64,
    /// The contact reading's own u (mm/s; scaled by √(χ²/ν) where it misses
    /// the noise).
    reading_u_mm_s: f64,
}

/// The contact model's bias on a test's pushes and landings, shared by them
/// all, as a fraction of the speed (module docs, "Uncertainty"): 1.4 %.
pub const SHARED_FORM: f64 = 0.014;

/// A push whose global reading has an own standard uncertainty (from
/// s²(JᵀJ)⁻¹ and the bounded directions) above this fraction of its speed is
/// not read by the global fit: the log does not determine it, and the two
/// readings' disagreement says little of the contact reading. Such a push,
/// once replaced, carries of that disagreement only the part that the global
/// fit's own variance does not explain, beside the contact reading's u, its
/// model-form term ([`crate::impacts::CONTACT_READING_FORM`]) and the shared
/// one ([`SHARED_FORM`]) (module docs). 20 %: the spread that makes a peak's
/// zero unsettled ([`super::checks::zero_readings_disagree`]).
const UNDETERMINED: f64 = 0.2;

/// Where a push's contact reading misses the noise, the pushes are replaced
/// only if the global fit reads one of them to no better than this fraction
/// of its speed ([`pushes_loose`]): 5 %, about what leaves a ratio built on
/// it beyond the ± 5 pp that a table value may carry
/// (`crate::restitution`), so that the test could not be vouched for with
/// the global readings.
const LOOSE_PUSH: f64 = 0.05;

/// The readings that fit the samples to the noise only (no χ²/ν limit above
/// it), the rule's first try.
const NOISE_ONLY: f64 = 0.0;

/// The largest χ²/ν of a push's contact reading that the fallback takes
/// ([`pushes_loose`]), its u scaled by √(χ²/ν). Thirty-first session: over
/// the 63 engine campaigns at hand the pushes' readings that miss the noise
/// have χ²/ν 1.5–4.7 and read −3.0 … +0.2 % of the truth (mean −1.4 %, 29
/// readings), as close as those that fit (RMS 1.3 % against 1.4 % on the
/// MuJoCo stand-ins, 1.3 against 0.9 % on the penalty engine).
const MISFIT_LIMIT: f64 = 5.0;

/// Whether the global fit reads some push (k odd) to worse than
/// [`LOOSE_PUSH`] of its speed: there the contact readings are taken even
/// where one of them misses the noise (up to [`MISFIT_LIMIT`]). Where the
/// global fit reads every push well, a misfit reading is not taken: on the
/// penalty engine's precise tests (global u 0.3–1 %) the first push's
/// misfit readings were 1–2.6 % low, and replacing them moved r₁ from
/// 0.61 to 2.15 pp off (pen1-s2's E1_170_1).
fn pushes_loose(a: &Analysis) -> bool {
    a.peaks
        .iter()
        .skip(1)
        .step_by(2)
        .any(|p| p.velocity_u_mm_s.is_none_or(|u| u > LOOSE_PUSH * p.velocity_mm_s.abs()))
}

/// The replacements: every push's reading at the noise, or, where the global
/// fit reads a push loosely ([`pushes_loose`]), up to [`MISFIT_LIMIT`].
/// The fallback is kept only where the contact model reads every push to
/// [`LOOSE_PUSH`] or better (its own u): what the global fit could not. (On
/// the compliant random draw's seed 1065, 100 Hz, the fifth push's reading
/// was ± 6.5 % and 10.8 % off, and taken, the test was ok at 2.65 pp off.)
fn choose(a: &Analysis, read: &[ContactPeak]) -> Option<Vec<Replacement>> {
    let tight = |new: &Vec<Replacement>| new.iter().all(|r| r.reading_u_mm_s <= LOOSE_PUSH * r.velocity_mm_s.abs());
    replacements(a, read, NOISE_ONLY).or_else(|| pushes_loose(a).then(|| replacements(a, read, MISFIT_LIMIT)).flatten().filter(tight))
}

/// The replacements of every odd peak, or None where one of them has no
/// contact reading at the noise (or, with `misfit_limit` above 0, none with
/// χ²/ν up to it: [`super::late::ContactReading::scaled_to_misfit`]) or the new peaks
/// would gain energy.
fn replacements(a: &Analysis, read: &[ContactPeak], misfit_limit: f64) -> Option<Vec<Replacement>> {
    let n = a.peaks.len();
    let new = (1..n)
        .step_by(2)
        .map(|k| {
            let c = read.iter().find(|q| q.k == k)?.reading.and_then(|c| c.scaled_to_misfit(misfit_limit))?;
            replacement(a, k, c)
        })
        .collect::<Option<Vec<_>>>()?;
    (!new.is_empty() && !gains_energy(a, &new)).then_some(new)
}

/// Peak k of the global fit replaced by the contact reading `c`, its u as the
/// module docs say; None where the reading's sign differs or its u is not finite.
fn replacement(a: &Analysis, k: usize, c: ContactReading) -> Option<Replacement> {
    let global = a.peaks[k];
    let v = c.reading.velocity_mm_s;
    let same_sign = v * global.velocity_mm_s > 0.0;
    let d = global.velocity_mm_s - v;
    // The contact reading's u with its model-form term (module docs, "Uncertainty").
    let u_c = c.reading.u_mm_s.hypot(crate::impacts::CONTACT_READING_FORM * v);
    // The global fit's own variance of this peak, where it does not read it.
    let own = a.fit_covariance.as_ref().map(|f| f[k][k].max(0.0));
    let undetermined = own.filter(|own| own.sqrt() > UNDETERMINED * global.velocity_mm_s.abs());
    // The readings' disagreement: the truth anywhere between the two
    // (d²/3), or the part the global fit's own variance does not explain.
    let apart = match undetermined {
        Some(own) => (d * d - own).max(0.0),
        None => d * d / 3.0,
    };
    let shared = SHARED_FORM * v;
    let u = (u_c * u_c + apart + shared * shared).sqrt();
    (same_sign && u.is_finite()).then_some(Replacement {
        k,
        time_s: c.reading.time_s,
        velocity_mm_s: v,
        u_mm_s: u,
        shared_mm_s: shared,
        reading_u_mm_s: c.reading.u_mm_s,
    })
}

/// Whether the peaks with `new` in place would make some ratio of consecutive
/// peaks exceed 1 (a wall gaining energy).
fn gains_energy(a: &Analysis, new: &[Replacement]) -> bool {
    let mut v: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
    new.iter().for_each(|r| v[r.k] = r.velocity_mm_s);
    v.windows(2).any(|w| w[1].abs() > w[0].abs())
}

/// The late landings of the table (k even, from [`FIRST_LATE_LANDING`] on)
/// whose global fit's residuals stand out ([`Analysis::local_misfit`] at least
/// [`LANDING_STANDS_OUT`]) and whose contact reading fits the samples to the
/// noise: those readings (module docs, "Late landings"). At a landing whose
/// impact the deferred reason names ([`Analysis::deferred_misfit`]: the global
/// fit's residuals there stand out at 8 σ, and the test is flagged unless the
/// contact model reads the peak), a reading up to χ²/ν = [`MISFIT_LIMIT`] is
/// taken, its u scaled by √(χ²/ν), if that u is within [`LOOSE_PUSH`] of the
/// speed: the pushes' fallback, where the global reading cannot be vouched
/// for (module docs, "A misfit landing").
fn late_landings(a: &Analysis, read: &[ContactPeak]) -> Vec<Replacement> {
    let named = |k: usize| a.deferred_misfit.as_ref().is_some_and(|m| m.impacts.contains(&k));
    (FIRST_LATE_LANDING..a.peaks.len())
        .step_by(2)
        .filter(|&k| a.local_misfit.get(k).copied().flatten().is_some_and(|z| z >= LANDING_STANDS_OUT))
        .filter_map(|k| {
            let c = read.iter().find(|q| q.k == k)?.reading?;
            let c = if named(k) {
                c.scaled_to_misfit(MISFIT_LIMIT)
                    .filter(|c| c.reading.u_mm_s <= LOOSE_PUSH * c.reading.velocity_mm_s.abs())?
            } else {
                Some(c).filter(|c| c.fits_noise())?
            };
            replacement(a, k, c)
        })
        .collect()
}

/// Put the replacements into the analysis: the peaks, their methods and the
/// covariance's rows and columns, which become the readings' own: each
/// replaced peak's variance its u², its covariance with another replaced
/// peak the product of their shared parts, with every other peak 0.
fn apply(a: &mut Analysis, new: &[Replacement]) {
    for r in new {
        let p = &mut a.peaks[r.k];
        p.time_s = r.time_s;
        p.velocity_mm_s = r.velocity_mm_s;
        p.velocity_u_mm_s = Some(r.u_mm_s);
        if let Some(m) = a.methods.get_mut(r.k) {
            *m = ReadingMethod::ContactModel;
        }
    }
    if let Some(cov) = a.peak_covariance.as_mut() {
        for r in new {
            cov.iter_mut().for_each(|row| row[r.k] = 0.0);
            cov[r.k].iter_mut().for_each(|c| *c = 0.0);
        }
        for r in new {
            for q in new {
                cov[r.k][q.k] = if r.k == q.k {
                    r.u_mm_s * r.u_mm_s
                } else {
                    r.shared_mm_s * q.shared_mm_s
                };
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peaks::late::{ContactReading, Reading};
    use crate::peaks::{acquisition::ResponseUsed, Peak, Quality};

    fn analysis(v: &[f64], u: f64) -> Analysis {
        Analysis {
            release_time_s: 0.0,
            peaks: v
                .iter()
                .enumerate()
                .map(|(k, &v)| Peak {
                    time_s: k as f64,
                    velocity_mm_s: v,
                    velocity_u_mm_s: Some(u),
                })
                .collect(),
            impacts: Vec::new(),
            displacement_mm: Vec::new(),
            velocity_mm_s: Vec::new(),
            fit_curve: Vec::new(),
            noise_mm: 0.01,
            spikes_removed: 0,
            p_fit: None,
            lambda_fit: None,
            rms_mm: None,
            quality: Quality::Ok,
            peak_covariance: Some(
                (0..v.len())
                    .map(|i| (0..v.len()).map(|j| if i == j { u * u } else { 0.5 * u * u }).collect())
                    .collect(),
            ),
            fit_covariance: None,
            contact_phases: true,
            gamma_fit: None,
            small_arc: Some((2.0, 20.0)),
            local_peaks: Vec::new(),
            methods: vec![ReadingMethod::KinkModel; v.len()],
            response: ResponseUsed {
                source: "not detected",
                filter: None,
                fir_cutoff_hz: None,
            },
            acquisition_note: None,
            wide_rounding_read_as_contacts: None,
            contact_readings: None,
            local_misfit: Vec::new(),
            model_note: None,
            deferred_reason: None,
            deferred_misfit: None,
            wide_rounding: None,
        }
    }

    fn reading(k: usize, v: f64, u: f64, chi2: f64) -> ContactPeak {
        ContactPeak {
            k,
            start_s: k as f64 - 1.0,
            crossing_s: k as f64,
            apex_mm: 10.0,
            reading: Some(ContactReading {
                reading: Reading {
                    time_s: k as f64 - 0.01,
                    velocity_mm_s: v,
                    u_mm_s: u,
                },
                chi2,
                n: 60,
                params: 5,
            }),
        }
    }

    #[test]
    fn a_misfit_is_read_past_only_where_the_contact_model_reads_every_peak_that_ends_there() {
        let mut a = analysis(&[-100.0, 60.0, -50.0, 30.0, -25.0, 15.0], 1.0);
        a.methods[3] = ReadingMethod::ContactModel;
        a.methods[4] = ReadingMethod::ContactModel;
        assert!(reads_past(&a, &[3]));
        assert!(reads_past(&a, &[3, 4]));
        // Peak 2 keeps the global reading; impact 6 ends no peak of the table.
        assert!(!reads_past(&a, &[2, 3]));
        assert!(!reads_past(&a, &[4, 6]));
        a.methods[3] = ReadingMethod::KinkModel;
        assert!(!reads_past(&a, &[3]));
    }

    /// A late landing (peak 4) whose global fit's residuals stand out
    /// (`local_misfit` ≥ [`LANDING_STANDS_OUT`]) takes its contact reading where
    /// that fits the samples to the noise, its u the reading's with the
    /// readings' disagreement and the shared form; not where the residuals do
    /// not stand out, not at peak 2, not where the reading misses the noise.
    #[test]
    fn a_late_landing_the_global_fit_misses_is_read_by_the_contact_model() {
        let v = [-500.0, 400.0, -350.0, 300.0, -260.0, 220.0];
        let read = [reading(2, -345.0, 1.0, 50.0), reading(4, -250.0, 1.0, 50.0)];
        let with = |z2: f64, z4: f64| {
            let mut a = analysis(&v, 5.0);
            a.local_misfit = vec![None, None, Some(z2), None, Some(z4), None];
            a
        };
        let new = late_landings(&with(1.0, 3.0), &read);
        assert_eq!(new.len(), 1);
        assert_eq!((new[0].k, new[0].velocity_mm_s), (4, -250.0));
        // The reading's u² with its model-form term: 1 + 2.5² = 7.25; |d| = 10
        // (10²/3); the shared form 1.4 % of 250 (3.5²).
        assert!((new[0].u_mm_s - (7.25 + 100.0 / 3.0 + 12.25f64).sqrt()).abs() < 1e-12);
        let mut a = with(1.0, 3.0);
        apply(&mut a, &new);
        assert_eq!(a.methods[4], ReadingMethod::ContactModel);
        assert_eq!(a.peaks[4].velocity_mm_s, -250.0);
        assert!(late_landings(&with(1.0, 2.4), &read).is_empty());
        assert!(late_landings(&with(5.0, 1.0), &read).is_empty());
        // χ² = 500 over ν = 55: the reading misses the noise.
        assert!(late_landings(&with(1.0, 3.0), &[reading(4, -250.0, 1.0, 500.0)]).is_empty());
    }

    /// A landing whose impact the deferred reason names (the global fit's
    /// residuals stand out there at 8 σ) takes a contact reading that misses
    /// the noise up to χ²/ν = [`MISFIT_LIMIT`], its u scaled by √(χ²/ν); not
    /// where no reason names it, not beyond the limit, not where the scaled u
    /// exceeds [`LOOSE_PUSH`] of the speed.
    #[test]
    fn a_misfit_landing_is_read_only_where_the_deferred_reason_names_it() {
        let v = [-500.0, 400.0, -350.0, 300.0, -260.0, 220.0];
        let named = |impacts: Vec<usize>| {
            let mut a = analysis(&v, 5.0);
            a.local_misfit = vec![None, None, None, None, Some(3.0), None];
            a.deferred_misfit = Some(crate::peaks::DeferredMisfit {
                reason: "the residuals around impact 4 stand out".into(),
                impacts,
            });
            a
        };
        // χ² = 110 over ν = 55: χ²/ν = 2, past the noise's 86.5.
        let misfit = [reading(4, -250.0, 1.0, 110.0)];
        let new = late_landings(&named(vec![4]), &misfit);
        assert_eq!(new.len(), 1);
        assert_eq!((new[0].k, new[0].velocity_mm_s), (4, -250.0));
        assert!((new[0].reading_u_mm_s - 2f64.sqrt()).abs() < 1e-12);
        // u² = 2 + 2.5² (model form) + 10²/3 (the disagreement) + 3.5² (shared).
        assert!((new[0].u_mm_s - (8.25 + 100.0 / 3.0 + 12.25f64).sqrt()).abs() < 1e-12);
        // Another impact named, or none: the misfit reading is not taken.
        assert!(late_landings(&named(vec![2]), &misfit).is_empty());
        let mut unnamed = named(vec![4]);
        unnamed.deferred_misfit = None;
        assert!(late_landings(&unnamed, &misfit).is_empty());
        // χ²/ν = 6 is past the limit; a scaled u of 13.4 mm/s is past 5 % of 250.
        assert!(late_landings(&named(vec![4]), &[reading(4, -250.0, 1.0, 330.0)]).is_empty());
        assert!(late_landings(&named(vec![4]), &[reading(4, -250.0, 9.5, 110.0)]).is_empty());
    }

    /// Every odd peak read at the noise: replaced, each u the reading's own
    /// with the readings' disagreement and the shared form, correlated with
    /// the other replaced peaks only, by the shared form.
    #[test]
    fn every_odd_peak_read_at_the_noise_is_replaced() {
        let v = [-500.0, 400.0, -350.0, 300.0, -260.0, 220.0];
        let mut a = analysis(&v, 5.0);
        let read = [reading(1, 408.0, 1.0, 50.0), reading(3, 303.0, 1.0, 50.0), reading(5, 224.0, 1.0, 50.0)];
        let new = replacements(&a, &read, NOISE_ONLY).expect("replaced");
        apply(&mut a, &new);
        let got: Vec<f64> = a.peaks.iter().map(|p| p.velocity_mm_s).collect();
        assert_eq!(got, [-500.0, 408.0, -350.0, 303.0, -260.0, 224.0]);
        // Peak 1: the reading's u² with 1 % of its speed, 1 + 4.08² =
        // 17.6464; |d| = 8 (8²/3); shared 1.4 % of 408 = 5.712.
        let u1_sq = 17.6464 + 64.0 / 3.0 + 5.712f64.powi(2);
        assert!((a.peaks[1].velocity_u_mm_s.unwrap() - u1_sq.sqrt()).abs() < 1e-12);
        let cov = a.peak_covariance.as_ref().unwrap();
        assert!((cov[1][1] - u1_sq).abs() < 1e-9);
        // Peaks 1 and 3 share the contact model's form: 5.712 × 4.242.
        assert!((cov[1][3] - 5.712 * 4.242).abs() < 1e-9, "{}", cov[1][3]);
        assert_eq!(cov[1][3], cov[3][1]);
        // The global readings' correlations with them go; among themselves they stay.
        assert!([0, 2, 4].iter().all(|&j| cov[1][j] == 0.0 && cov[j][1] == 0.0));
        assert_eq!(cov[0][2], 12.5);
        assert_eq!(a.methods[1], ReadingMethod::ContactModel);
        assert_eq!(a.methods[2], ReadingMethod::KinkModel);
    }

    /// Peaks −500, 400, −350, 300, −260, 220 at u 5 (covariance 12.5), the
    /// global fit's own part 9 on every peak (covariance 4) but peak 3's,
    /// whose own variance is `own_3`; its u² is 16 + `own_3`.
    fn with_own_part(own_3: f64) -> Analysis {
        let mut a = analysis(&[-500.0, 400.0, -350.0, 300.0, -260.0, 220.0], 5.0);
        let mut own: Vec<Vec<f64>> = (0..6).map(|i| (0..6).map(|j| if i == j { 9.0 } else { 4.0 }).collect()).collect();
        own[3][3] = own_3;
        a.fit_covariance = Some(own);
        a.peak_covariance.as_mut().unwrap()[3][3] = 16.0 + own_3;
        a.peaks[3].velocity_u_mm_s = Some((16.0 + own_3).sqrt());
        a
    }

    /// Replace peaks 1, 3, 5 by contact readings of `speeds` at u 1 that fit
    /// the samples to the noise.
    fn replace_at_the_noise(a: &mut Analysis, speeds: [f64; 3]) {
        let read: Vec<ContactPeak> = [1, 3, 5].iter().zip(speeds).map(|(&k, v)| reading(k, v, 1.0, 50.0)).collect();
        let new = replacements(a, &read, NOISE_ONLY).expect("replaced");
        apply(a, &new);
    }

    /// The global reading's model-form terms do not carry over to the
    /// contact reading that replaces it: a global peak read to ± 13 % by
    /// its model-form terms (peak 3: u² = 1516, its own part 9) is replaced
    /// by a reading whose u is its own, the disagreement's and the shared
    /// form's.
    #[test]
    fn the_global_readings_terms_do_not_carry_over() {
        let mut a = with_own_part(9.0);
        a.peak_covariance.as_mut().unwrap()[3][3] = 1516.0;
        a.peaks[3].velocity_u_mm_s = Some(1516f64.sqrt());
        replace_at_the_noise(&mut a, [408.0, 303.0, 221.0]);
        // Peak 3: 1 + 3.03² (own and form), 3²/3 (the disagreement), (0.014 × 303)².
        let u3_sq = 1.0 + 3.03f64.powi(2) + 3.0 + 4.242f64.powi(2);
        assert!((a.peaks[3].velocity_u_mm_s.unwrap() - u3_sq.sqrt()).abs() < 1e-12);
        // Peaks not replaced keep their variance.
        let cov = a.peak_covariance.as_ref().unwrap();
        assert_eq!(cov[0][0], 25.0);
    }

    /// A push the global fit does not read (its own u above 20 % of its
    /// speed): once replaced, its u is the contact reading's with the
    /// contact model's form, the shared form and the part of the
    /// disagreement that the global fit's own variance does not explain.
    #[test]
    fn a_push_the_global_fit_does_not_read_is_the_contact_readings_alone() {
        // Peak 3: own u 300 (100 % of its speed), global u √(90000 + 16).
        let mut a = with_own_part(90_000.0);
        replace_at_the_noise(&mut a, [408.0, 303.0, 221.0]);
        // u² = 1 + (0.01 × 303)² + max(0, 3² − 90000) + (0.014 × 303)².
        let u3 = (1.0 + 3.03f64.powi(2) + 4.242f64.powi(2)).sqrt();
        assert!((a.peaks[3].velocity_u_mm_s.unwrap() - u3).abs() < 1e-12);
        // Where the disagreement exceeds what the own variance explains, the
        // excess counts: own u 70 (23 %), the reading 80 mm/s away.
        let w = [-500.0, 400.0, -350.0, 300.0, -200.0, 180.0];
        let mut b = analysis(&w, 5.0);
        let mut own: Vec<Vec<f64>> = (0..6).map(|i| (0..6).map(|j| if i == j { 9.0 } else { 0.0 }).collect()).collect();
        own[3][3] = 4900.0;
        b.fit_covariance = Some(own);
        b.peaks[3].velocity_u_mm_s = Some(4916f64.sqrt());
        b.peak_covariance.as_mut().unwrap()[3][3] = 4916.0;
        let far = [reading(1, 408.0, 1.0, 50.0), reading(3, 220.0, 1.0, 50.0), reading(5, 178.0, 1.0, 50.0)];
        let new = replacements(&b, &far, NOISE_ONLY).expect("replaced");
        let r3 = new.iter().find(|r| r.k == 3).unwrap();
        // u² = 1 + 2.2² + (80² − 4900) + (0.014 × 220)².
        assert!((r3.u_mm_s - (1.0 + 4.84 + 1500.0 + 3.08f64.powi(2)).sqrt()).abs() < 1e-9, "{}", r3.u_mm_s);
    }

    /// A global u of 0 (never stated so, but not a division by zero): the
    /// replaced peak's row and column hold the reading's own terms.
    #[test]
    fn a_zero_global_u_gives_the_reading_its_own_variance() {
        let v = [-500.0, 400.0, -350.0, 300.0, -260.0, 220.0];
        let mut a = analysis(&v, 5.0);
        a.peaks[1].velocity_u_mm_s = Some(0.0);
        let read = [reading(1, 400.0, 2.0, 50.0), reading(3, 300.0, 1.0, 50.0), reading(5, 220.0, 1.0, 50.0)];
        let new = replacements(&a, &read, NOISE_ONLY).expect("replaced");
        apply(&mut a, &new);
        let cov = a.peak_covariance.as_ref().unwrap();
        // The reading's u² with its model-form term, 2² + 4², and the shared 5.6².
        let u1_sq = 20.0 + 5.6f64.powi(2);
        assert!((a.peaks[1].velocity_u_mm_s.unwrap() - u1_sq.sqrt()).abs() < 1e-12);
        assert!((cov[1][1] - u1_sq).abs() < 1e-9);
        assert!([0, 2, 4].iter().all(|&j| cov[1][j] == 0.0 && cov[j][1] == 0.0));
        assert!(cov.iter().flatten().all(|x| x.is_finite()));
    }

    /// A push whose reading misses the noise (χ²/ν = 3): nothing is replaced
    /// where the global fit reads every push to 5 % or better; where it reads
    /// one to worse, every push is replaced, the misfit reading's u scaled by
    /// √3; beyond χ²/ν = 5, or where a replaced push would still be read to
    /// worse than 5 %, nothing is.
    #[test]
    fn a_misfit_push_is_taken_only_where_the_global_fit_reads_a_push_loosely() {
        let read = |chi2: f64| [reading(1, 398.0, 1.0, chi2), reading(3, 303.0, 1.0, 50.0), reading(5, 224.0, 1.0, 50.0)];
        // Peak 3's own part 1 (u 4.1, 1.4 %): every push read well.
        let mut precise = with_own_part(1.0);
        assert!(!read_inward(&mut precise, &read(165.0)));
        // Own part 400 (u √416, 6.8 %): loose.
        let mut loose = with_own_part(400.0);
        assert!(read_inward(&mut loose, &read(165.0)));
        assert_eq!(loose.peaks[1].velocity_mm_s, 398.0);
        // Peak 1: the reading's u² 3 (1 scaled by √3) + 3.98² (its model
        // form) = 18.8404, with 2²/3 (the disagreement) and (0.014 × 398)².
        let u1_sq = 18.8404 + 4.0 / 3.0 + 5.572f64.powi(2);
        assert!((loose.peaks[1].velocity_u_mm_s.unwrap() - u1_sq.sqrt()).abs() < 1e-12);
        assert_eq!(loose.peaks[3].velocity_mm_s, 303.0);
        let mut far = with_own_part(400.0);
        assert!(!read_inward(&mut far, &read(330.0)));
        // A reading that reads a push loosely (peak 5's own ± 12, 5.4 %) is not taken.
        let mut wide = with_own_part(400.0);
        let mut r = read(165.0);
        r[2] = reading(5, 224.0, 12.0, 50.0);
        assert!(!read_inward(&mut wide, &r));
    }

    /// [`choose`] on given readings, applied: whether the pushes were replaced.
    fn read_inward(a: &mut Analysis, read: &[ContactPeak]) -> bool {
        choose(a, read).map(|n| apply(a, &n)).is_some()
    }

    /// One odd peak not at the noise, a wall gaining energy, or a filter in
    /// the model: nothing is replaced.
    #[test]
    fn all_of_one_side_or_none() {
        let v = [-500.0, 400.0, -350.0, 300.0, -260.0, 220.0];
        let a = analysis(&v, 5.0);
        let misfit = [reading(1, 408.0, 1.0, 50.0), reading(3, 303.0, 1.0, 500.0), reading(5, 224.0, 1.0, 50.0)];
        assert!(replacements(&a, &misfit, NOISE_ONLY).is_none());
        let missing = [reading(1, 408.0, 1.0, 50.0), reading(5, 224.0, 1.0, 50.0)];
        assert!(replacements(&a, &missing, NOISE_ONLY).is_none());
        let gains = [reading(1, 408.0, 1.0, 50.0), reading(3, 303.0, 1.0, 50.0), reading(5, 270.0, 1.0, 50.0)];
        assert!(replacements(&a, &gains, NOISE_ONLY).is_none());
        let mut filtered = analysis(&v, 5.0);
        filtered.response.fir_cutoff_hz = Some(40.0);
        assert!(!eligible(&filtered));
        let mut suspect = analysis(&v, 5.0);
        suspect.quality = Quality::Suspect(vec!["x".into()]);
        assert!(!eligible(&suspect));
    }
}
