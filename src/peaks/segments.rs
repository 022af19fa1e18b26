//! The default estimator's driver: starting values, several starts, the choice
//! between instantaneous impacts and contact phases, and the uncertainty of the
//! peaks.
//!
//! # Model choice
//! The model with instantaneous impacts is fitted first (several starts of the
//! inward λ in one-sided rocking, where one start can land in a wrong minimum).
//! Isolated spikes the spike filter missed are then left out ([`reject_outliers`]).
//! Where it misses the samples around its impacts (RMS > 1.2 σ), the model with
//! contact phases (three more parameters per direction) is then fitted from it,
//! twice: windows of two samples and of 10 ms. It replaces the
//! first only when the data ask for it clearly: the Bayesian information
//! criterion, (cost₁ − cost₂)/σ² > k ln n (σ the measured noise, k the extra
//! parameters, n the samples). On logs made with instantaneous impacts the
//! simple model is kept (and the estimator stays what it was, exact on ideal
//! data); on logs with finite-duration contacts (MuJoCo, the compliant
//! generator) the misfit around each impact is hundreds of σ² and the contact
//! model wins. (Until the gravity arcs carried their large-angle correction, a
//! contact phase could absorb the misfit of a 0.7 α release and a floor of
//! 100 σ² on the gain was needed; it is gone.) Where contact phases are chosen,
//! the instantaneous model's peaks are kept: their distance to the chosen ones
//! is the model-form part of the peaks' uncertainty.

use super::model::{fit_model, ix, Fitted, Layout, Model};
use super::{ContactModel, Impact, PeakError, Physics, Side};
use crate::signal::median;
use crate::wall::Rocking;

/// Result of the global fit, in the form the analysis reports.
#[derive(Debug, Clone)]
pub struct SegmentFit {
    pub fitted: Fitted,
    pub rms: f64,
    pub lever_mm: f64,
    pub rest: f64,
    /// The fitted window: times and readings in L θ space.
    pub tw: Vec<f64>,
    pub yw: Vec<f64>,
    /// Whether the contact-phase model was chosen.
    pub contacts: bool,
    /// Isolated samples left out of the fit ([`reject_outliers`]).
    pub outliers: usize,
    /// The peaks of the instantaneous-impact model where contact phases were
    /// chosen (the model-form spread).
    pub alternative: Option<Vec<f64>>,
    /// The peaks of another minimum of the one-sided contact fit that the data
    /// do not reject ([`restart_damping`]): a model-form spread carried into u.
    pub rival_minimum: Option<Vec<f64>>,
    /// An unstated filter found and estimated, and the peaks of the fits at its
    /// cut-off ± one standard uncertainty (the spread carried into u).
    pub estimated: Option<(super::acquisition::Estimate, Vec<Vec<f64>>)>,
    /// Where an unstated filter was estimated and then dropped for the wall's
    /// contacts' signature, why ([`super::acquisition::rival`]).
    pub filter_dropped: Option<String>,
    /// The peaks of a contact-phase fit that the data lean towards without
    /// asking for it ([`leaning_contacts`]): a model-form spread.
    pub leaning: Option<Vec<f64>>,
}

/// Inputs of the fit.
pub struct FitInput<'a> {
    pub t: &'a [f64],
    pub x: &'a [f64],
    /// Samples left out of the fit (indices into `t`, increasing): those the
    /// spike filter replaced beside an impact (`peaks::beside_impacts`).
    pub replaced: &'a [usize],
    pub rest: f64,
    pub sigma: f64,
    pub departure: usize,
    pub crossings: &'a [f64],
    pub phys: &'a Physics,
    pub n_peaks: usize,
    pub contacts: ContactModel,
    /// The logger's filter, where stated ([`super::acquisition`]).
    pub filter: Option<std::sync::Arc<dyn super::model::Instrument>>,
    /// No filter stated: look for one ([`super::acquisition::estimate`]).
    pub estimate_filter: bool,
}

impl SegmentFit {
    pub fn run(inp: &FitInput) -> Result<SegmentFit, PeakError> {
        let (t, x, rest, crossings) = (inp.t, inp.x, inp.rest, inp.crossings);
        let lever = inp.phys.lever_arm_mm;
        let m = crossings.len().min(inp.n_peaks + 1);
        let one_sided = inp.phys.rocking == Rocking::OneSided;
        // Window: from a little before the release to the last impact used.
        let dt = (t[t.len() - 1] - t[0]) / (t.len() - 1) as f64;
        let t_dep = t[inp.departure];
        let t0 = crossings[0];
        let start_t = t_dep - 0.5 * (t0 - t_dep).max(10.0 * dt);
        let end_t = crossings[m - 1] - 0.25 * dt;
        let i0 = t.partition_point(|&v| v < start_t);
        let i1 = t.partition_point(|&v| v <= end_t);
        let kept: Vec<usize> = (i0..i1).filter(|i| inp.replaced.binary_search(i).is_err()).collect();
        let mut tw: Vec<f64> = kept.iter().map(|&i| t[i]).collect();
        // L θ from the sensor's L sin θ.
        let mut yw: Vec<f64> = kept
            .iter()
            .map(|&i| rest + lever * ((x[i] - rest) / lever).clamp(-1.0, 1.0).asin())
            .collect();
        if tw.len() < 3 * m + 8 {
            return Err(PeakError::FitWindow(tw.len()));
        }
        let base = starting_model(inp, &tw, &yw, m, one_sided, t_dep, start_t, dt);
        let simple = best_simple_fit(&base, &tw, &yw, crossings, m, one_sided)?;
        let (simple, outliers) = reject_outliers(simple, &mut tw, &mut yw, inp.sigma);
        let n = tw.len() as f64;
        let sigma2 = inp.sigma.powi(2).max(1e-12);
        let extra = if one_sided { 6.0 } else { 3.0 };
        let mut chosen = simple.clone();
        let mut contacts = false;
        // The best contact-phase fit, chosen or not: the rival of an estimated filter.
        let mut best_contacts: Option<Fitted> = None;
        // Contact phases are chosen only where the instantaneous-impact model
        // misses the samples around its impacts by more than 1.2 σ (RMS):
        // finite-duration contacts show there first.
        let expected = inp.contacts == ContactModel::Expected;
        let misses = misses_around_impacts(&simple.model, &tw, &yw, dt, inp.sigma);
        // Fitted to the noise: contact phases are still fitted, as a rival
        // only ([`leaning_contacts`]), from the wider starting window alone
        // (one fit: 348 → 520 ms on the 2,000,000-row benchmark, docs/speed.md).
        let probe = !(expected || misses);
        // Two starting windows, one where 2Δt ≥ 10 ms (≤ 200 Hz): the same fit twice.
        let w = [2.0 * dt, 0.01f64.max(2.0 * dt)];
        let windows: Vec<f64> = if probe {
            vec![w[1]]
        } else if w[1] > w[0] {
            w.to_vec()
        } else {
            vec![w[0]]
        };
        let mut probed: Option<Fitted> = None;
        for &window in &windows {
            let Some(c) = fit_model(simple.model.with_contacts(window), &tw, &yw, 100) else {
                continue;
            };
            if probe {
                probed = Some(c);
                continue;
            }
            // The data must ask for contact phases clearly: the Bayesian
            // information criterion, (cost₁ − cost₂)/σ² > k ln n. (The
            // Akaike criterion, 2k, was tried: on logs with instantaneous
            // impacts it chose contact phases often enough to miss 2.2 % of
            // the idealised draw, one test by 5 pp.)
            // Where the campaign has shown contacts (`ContactModel::Expected`),
            // any gain will do.
            let gain = (simple.fit.cost - c.fit.cost) / sigma2;
            let needed = if expected { 0.0 } else { extra * n.ln() };
            if gain > needed && c.fit.cost < chosen.fit.cost {
                chosen = c.clone();
                contacts = true;
            }
            if best_contacts.as_ref().is_none_or(|b| c.fit.cost < b.fit.cost) {
                best_contacts = Some(c);
            }
        }
        // Where contact phases were chosen, the instantaneous model's peaks give
        // the model-form spread. (Where they were not, the contact fit's are not
        // used: on the idealised draw that raised the median stated u of a
        // table value from 0.27 to 0.34 pp, against a median error of 0.02 pp.)
        let mut alternative = contacts.then(|| (0..m).map(|k| simple.model.peak(k).1).collect());
        let leaning = probed.and_then(|c| leaning_contacts(&simple, &c, sigma2, inp.n_peaks));
        // No filter stated: a low-pass rounds the kinks too.
        let penalty = if contacts && !expected { extra * n.ln() } else { 0.0 };
        let rivals = super::acquisition::Rivals {
            plain: &simple,
            chosen: &chosen,
            penalty,
            contacts: best_contacts.as_ref(),
        };
        let (estimated, filter_dropped) = match rival_filter(inp.estimate_filter && misses, &rivals, (&tw, &yw), dt, inp.sigma) {
            Ok(found) => (Some(found), None),
            Err(why) => (None, why),
        };
        if let Some((e, _)) = &estimated {
            (chosen, contacts, alternative) = (e.fitted.clone(), false, None);
        }
        // Two-sided contact phases that follow the impacts' speeds
        // ([`Model::speed_scale`]), where the data prefer them.
        if !one_sided && contacts && estimated.is_none() && chosen.model.filter.is_none() {
            chosen = contacts_by_speed(chosen, &tw, &yw, extra * n.ln() * sigma2);
        }
        // One-sided contact fits start from an undamped restraint (γ = 0); a
        // restraint with its damping can sit in a second, lower minimum.
        let mut rival_minimum = None;
        if one_sided && contacts {
            (chosen, rival_minimum) = restart_damping(chosen, &tw, &yw, extra * n.ln() * sigma2);
        }
        // (An estimated filter has set `contacts` false above.)
        if !one_sided && contacts && windows.len() == 1 {
            rival_minimum = restart_window(&simple.model, &chosen, dt, &tw, &yw, extra * n.ln() * sigma2);
        }
        Ok(SegmentFit {
            rms: (chosen.fit.cost / n).sqrt(),
            fitted: chosen,
            lever_mm: lever,
            rest,
            tw,
            yw,
            contacts,
            outliers,
            alternative,
            rival_minimum,
            estimated,
            filter_dropped,
            leaning,
        })
    }

    pub fn model(&self) -> &Model {
        &self.fitted.model
    }

    pub fn impacts(&self) -> Vec<Impact> {
        let m = self.model();
        (0..m.m())
            .map(|k| {
                let (_, after) = m.speeds(k);
                let (t_peak, before) = m.peak(k);
                Impact {
                    k,
                    time_s: t_peak,
                    entering: if k % 2 == 0 { Side::Inward } else { Side::Outward },
                    v_before_mm_s: before,
                    v_after_mm_s: after,
                }
            })
            .collect()
    }

    /// Replace the velocity inside the fitted window by the fit's derivative.
    pub fn fill_velocity(&self, t: &[f64], v: &mut [f64]) {
        let tr = self.model().release_time();
        let from = t.partition_point(|&ti| ti < tr);
        for (vi, m) in v[from..].iter_mut().zip(self.model().eval_many(&t[from..])) {
            if let Some((_, s)) = m {
                *vi = s;
            }
        }
    }

    /// Fitted displacement (back in sensor space, L sin θ) and velocity on a grid of
    /// 200 points per piece.
    pub fn curve(&self) -> Vec<(f64, f64, f64)> {
        let m = self.model();
        let mut out = Vec::new();
        let mut start = m.release_time();
        for k in 0..m.m() {
            let end = if k + 1 < m.m() { m.release_from_contact(k) } else { m.onset(k) };
            for q in 0..200 {
                let tq = start + (end - start) * q as f64 / 200.0;
                if let Some((lt, v)) = m.eval(tq) {
                    let x = self.rest + self.lever_mm * ((lt - self.rest) / self.lever_mm).sin();
                    out.push((tq, x, v));
                }
            }
            start = end;
        }
        out
    }

    /// The first `n` peaks of the chosen model re-fitted without the samples
    /// within `half_width` (s) of any of `onsets` (mm/s; `None` where the
    /// re-fit fails): how far the peaks depend on those samples
    /// (`peaks::exits_only_misfit`).
    pub fn peaks_without(&self, onsets: &[f64], half_width: f64, n: usize) -> Option<Vec<f64>> {
        let keep = |t: &f64| onsets.iter().all(|o| (t - o).abs() > half_width);
        let (tw, yw): (Vec<f64>, Vec<f64>) = self.tw.iter().zip(&self.yw).filter(|(t, _)| keep(t)).unzip();
        let f = fit_model(self.model().clone(), &tw, &yw, 100)?;
        Some((0..n.min(f.model.m())).map(|k| f.model.peak(k).1).collect())
    }

    /// Residuals of the chosen fit over its window.
    pub fn residuals(&self) -> Vec<f64> {
        let mut r = Vec::new();
        self.model().residuals(&self.tw, &self.yw, &mut r);
        r
    }
}

/// The gain (σ²) above which a contact-phase fit the data did not ask for is
/// carried in u ([`leaning_contacts`]): the Akaike criterion 2k of the
/// one-sided contact model (k = 6). Two-sided (k = 3) its 2k = 6 σ² was
/// measured too: on `synth`'s idealised draw (400 seeds, instantaneous
/// impacts) it applied to 21 % of the two-sided tests, at 12 σ² to 8 %
/// (one-sided 6.5 %), and on the compliant draw it took the two-sided peaks
/// within 2 u to 96 % against 93 % at 12 σ².
pub(crate) const LEANING_GAIN: f64 = 12.0;

/// The peaks of the contact-phase fit `c` of a log that the
/// instantaneous-impact fit `simple` describes to the noise, where the data
/// lean towards the contacts without asking for them: a cost gain above
/// [`LEANING_GAIN`], which the Bayesian criterion (k ln n) does not reach.
///
/// A one-sided wall's compliant restraint starts to slow it before θ = 0,
/// by a contact angle about the same at every inward impact, so the free
/// arc's speed extrapolated to θ = 0 reads its inward peaks high by a
/// fraction that grows as 1/v²; at 200–500 Hz the log shows that only
/// faintly. Reduced alone (no campaign to say that its walls' contacts are
/// compliant), the public MuJoCo test P1_150_1 (200 Hz) read v₀, v₂, v₄
/// +1.0, +2.5 and +6.3 % high and r⁻ 1.03 pp off at u 0.22 pp (4.8 u), and
/// the penalty engine's E1_160_1 (500 Hz) +1.1, +1.8, +3.1 %, r⁻ 0.44 pp at
/// u 0.07 (6.4 u). Their contact-phase fits read v₄ within 0.7 % and 0.05 %
/// and gained 12.5 and 25.4 σ² (the Bayesian criterion asks 35.4 and 42.4).
/// Two-sided walls do the same on `synth`'s compliant draw: of its two-sided
/// tests fitted to the noise, peaks read up to 26 of their u off (22 % of
/// the ok tests' peaks beyond 2 u, their ratios within it).
/// Their peaks are carried as the other model of the contacts
/// (`uncertainty::add_model_spread_partly`), never chosen: on the idealised
/// draw the Akaike criterion chose contact phases often enough to miss
/// 2.2 % of the tests. Only a contact fit whose contact phases are short
/// beside the half-cycles they join ([`super::checks::contacts_too_long`], the
/// check a chosen one must pass) is a credible reading: on daq-public-bessel-1
/// T1_3 with its filter not stated, a contact fit with a contact longer than
/// that gained 21.6 σ² and read peak 5 at 26 mm/s (the instantaneous fit: 95),
/// and carried in u it left the test suspect for a u of ± 8 pp on r (it is
/// 0.47 pp off).
///
/// Nor is one that reads a table peak faster than the instantaneous fit does,
/// by more than [`LEANING_FASTER`]: a contact that sets in before θ = 0 brakes
/// the wall there, so the speed at its onset is below the free arc's
/// extrapolated to θ = 0 ([`braking_only`]).
fn leaning_contacts(simple: &Fitted, c: &Fitted, sigma2: f64, table: usize) -> Option<Vec<f64>> {
    let gain = (simple.fit.cost - c.fit.cost) / sigma2;
    let m = &c.model;
    let short = m
        .contact_windows()
        .is_none_or(|w| super::checks::contacts_too_long(m, &w, table).is_none());
    if gain <= LEANING_GAIN || !short {
        return None;
    }
    let peaks: Vec<f64> = (0..m.m()).map(|k| m.peak(k).1).collect();
    let plain: Vec<f64> = (0..simple.model.m().min(table)).map(|k| simple.model.peak(k).1).collect();
    braking_only(&plain, &peaks).then_some(peaks)
}

/// How much faster than the instantaneous-impact fit a leaning contact fit may
/// read a table peak (a fraction of the instantaneous reading) and still be
/// carried in u ([`leaning_contacts`]).
///
/// Measured (forty-ninth session, release, a scratch harness around
/// `synth::score`): on the compliant draw's seeds 1000–1199 the rule carried
/// 25 contact fits, and none read a peak faster than the instantaneous fit by
/// more than 0.2 % (the others 0.3–4.9 % slower), as a contact that sets in
/// before θ = 0 must. On the idealised draw it carried 15 on seeds 1000–1499
/// and 15 on seeds + 400000, of which 7 and 6 read some peak faster by
/// 1.2–21 %: quintic contact phases shorter than a sample whose speed
/// overshoots the arc's, a shape the samples cannot see. Three of them were
/// flagged for a u of ± 5.9–9.4 pp on r₁, read within 0.1 pp. 1 % is above
/// the largest excess of an idealised test whose readings agree otherwise
/// (+0.9 %) and five times the compliant draw's largest.
pub(crate) const LEANING_FASTER: f64 = 0.01;

/// Whether every reading in `contact` of a peak that `plain` reads is no
/// faster than it by more than [`LEANING_FASTER`].
fn braking_only(plain: &[f64], contact: &[f64]) -> bool {
    plain.iter().zip(contact).all(|(p, c)| c.abs() <= p.abs() * (1.0 + LEANING_FASTER))
}

/// Where `look` (no filter stated, the plain fit misses the samples around its
/// impacts): an estimated low-pass, if it beats `chosen` ([`super::acquisition::rival`]).
type Rival = Result<(super::acquisition::Estimate, Vec<Vec<f64>>), Option<String>>;
fn rival_filter(look: bool, rivals: &super::acquisition::Rivals, (tw, yw): (&[f64], &[f64]), dt: f64, sigma: f64) -> Rival {
    if !look {
        return Err(None);
    }
    super::acquisition::rival(rivals, tw, yw, dt, sigma)
}

/// Isolated spikes the spike filter missed: a spike next to an impact, where the
/// kink of the record hides it from the second differences, bends the whole fit
/// (one 37 σ spike before an impact of a 100 Hz log moved its last peaks by
/// 8–13 %). While the largest residual exceeds 8 σ (σ the measured noise; never
/// reached by Gaussian noise) and 3 times both its neighbours (a spike, not the
/// smooth misfit of a contact the model lacks), that sample is left out and
/// the model re-fitted from where it was; at most 8 samples.
fn reject_outliers(mut fitted: Fitted, tw: &mut Vec<f64>, yw: &mut Vec<f64>, sigma: f64) -> (Fitted, usize) {
    let mut dropped = 0;
    let mut r = Vec::new();
    while dropped < 8 {
        if !fitted.model.residuals(tw, yw, &mut r) || r.len() < 3 {
            break;
        }
        let Some(i) = (1..r.len() - 1).max_by(|&a, &b| r[a].abs().total_cmp(&r[b].abs())) else {
            break;
        };
        let isolated = r[i].abs() > 3.0 * r[i - 1].abs().max(r[i + 1].abs());
        if r[i].abs() <= 8.0 * sigma || !isolated {
            break;
        }
        let (t_i, y_i) = (tw.remove(i), yw.remove(i));
        match fit_model(fitted.model.clone(), tw, yw, 60) {
            Some(f) => {
                fitted = f;
                dropped += 1;
            }
            None => {
                tw.insert(i, t_i);
                yw.insert(i, y_i);
                break;
            }
        }
    }
    (fitted, dropped)
}

/// Whether the residuals within ±3 samples of the impacts have an RMS above
/// 1.2 σ (σ the measured noise).
fn misses_around_impacts(model: &Model, tw: &[f64], yw: &[f64], dt: f64, sigma: f64) -> bool {
    let mut r = Vec::new();
    if !model.residuals(tw, yw, &mut r) {
        return false;
    }
    let impacts: Vec<f64> = (0..model.m()).map(|k| model.impact(k)).collect();
    let near: Vec<f64> = tw
        .iter()
        .zip(&r)
        .filter(|(t, _)| impacts.iter().any(|tk| (**t - tk).abs() <= 3.0 * dt))
        .map(|(_, r)| *r)
        .collect();
    if near.is_empty() {
        return false;
    }
    let rms = (near.iter().map(|v| v * v).sum::<f64>() / near.len() as f64).sqrt();
    rms > 1.2 * sigma
}

/// Restraint decay rates γ (s⁻¹) from which a one-sided contact fit is
/// started again ([`restart_damping`]): damping ratios γ/√λ of about 0.06 to
/// 0.4 at the λ = 1300–3000 s⁻² that the engine's one-sided logs fit.
const RESTART_GAMMAS: [f64; 4] = [3.0, 6.0, 10.0, 15.0];

/// The one-sided contact fit `f` started again from each of
/// [`RESTART_GAMMAS`]. The lowest cost replaces the first fit where it is
/// lower by more than `evidence` (what the fit demands before it adds contact
/// phases, 6 σ² ln n); otherwise the first fit stays. Returned with it: the
/// peaks of the minimum that differs most from it among those whose cost is
/// within `evidence` of it, if any (the data cannot choose between the two, and
/// their spread is a model-form term of u).
///
/// Every one-sided start begins with an undamped restraint (γ = 0; the starts
/// differ in λ only, [`best_simple_fit`]), and the cost has more than one
/// minimum. On the public-like MuJoCo stand-ins 8 of 20 tests read r₁
/// 0.43–1.25 pp low and r⁻ 0.71–1.68 pp high, and those whose γ was printed
/// had stopped at γ = 2.1–5.0 s⁻¹; on two of the stand-ins, started again
/// from 6 or 10 s⁻¹, three of the five such tests found γ = 9.2–9.8 s⁻¹ at a
/// lower cost, and their values within 0.36–0.80 pp (docs/accuracy.md,
/// "One-sided: the restraint's damping, started again"). On the compliant
/// random draw (seed 1064003192, 100 Hz) a restart reached a minimum 12 σ²
/// lower with the same γ but other contact shapes, whose odd peaks were 2–7 %
/// off at u 0.9 mm/s (the first fit's within 2.2 %): it is not taken, and its
/// spread widens the first fit's u. Run after the
/// logger filter's rivalry, so that a lower contact cost cannot displace an
/// estimated filter (on the unstated-Bessel draw, run before it, it let a
/// 100 Hz test through 2.04 pp off with status ok).
///
/// A restart whose table peaks read the wall gaining energy ([`gains_energy`])
/// neither replaces the first fit nor widens its u: free rocking only loses
/// speed at an impact. Thirty-first session: on the penalty engine's one-sided
/// seed 1, E1_160_1 (500 Hz), a restart within the evidence read the pushes at
/// 6581, 4712 and 3458 mm/s (the truth 552, 413, 294), and its spread put
/// ± 600 % on them (r₁ ± 527 pp); without it ± 14–20 %. On the MuJoCo
/// stand-in Q1-s1419's Q1_155_1 (100 Hz) the lowest restart read |v₂| and |v₄|
/// 0.4 and 0.8 % above |v₁| and |v₃|; taken, the test was ok at 2.17 pp off;
/// the first fit reads it within 0.94 pp (`tests/truth.rs`,
/// `a_restart_that_gains_energy_is_no_reading`). Over the 63 engine
/// campaigns at hand the ok tests' worst values otherwise move by at most
/// 0.13 pp, and one flagged test (the penalty seed 5's E1_140_1) is ok at
/// 0.38 pp (docs/accuracy.md, "Thirty-first session: restarts that gain
/// energy, and pushes the global fit reads loosely").
fn restart_damping(f: Fitted, tw: &[f64], yw: &[f64], evidence: f64) -> (Fitted, Option<Vec<f64>>) {
    let mut fits = vec![f];
    for g in RESTART_GAMMAS {
        let mut mdl = fits[0].model.clone();
        mdl.q[ix::GAMMA] = g;
        if let Some(c) = fit_model(mdl, tw, yw, 100) {
            fits.push(c);
        }
    }
    let m = fits[0].model.m();
    let mut read: Vec<(Fitted, Vec<f64>)> = fits
        .into_iter()
        .map(|f| {
            let p = (0..m).map(|k| f.model.peak(k).1).collect();
            (f, p)
        })
        .collect();
    // A restart whose peaks gain energy is no reading of free rocking.
    let credible = |p: &[f64]| !gains_energy(p);
    let lowest = (0..read.len())
        .filter(|&i| i == 0 || credible(&read[i].1))
        .min_by(|&a, &b| read[a].0.fit.cost.total_cmp(&read[b].0.fit.cost))
        .unwrap_or(0);
    // Another minimum replaces the first fit only where the data prefer it by
    // the evidence; otherwise the first fit stays and the other widens u.
    let chosen = if read[0].0.fit.cost - read[lowest].0.fit.cost > evidence {
        lowest
    } else {
        0
    };
    let (best, mine) = read.swap_remove(chosen);
    let rival = widest_rival(
        read.into_iter()
            .filter(|(f, p)| f.fit.cost - best.fit.cost <= evidence && credible(p))
            .map(|(_, p)| p),
        &mine,
    );
    (best, rival)
}

/// Of the `rivals`' peaks, those that differ most from `mine` (the largest
/// |difference| of a peak), where they differ at all: the second minimum
/// that widens u ([`restart_damping`], [`restart_window`]).
fn widest_rival(rivals: impl Iterator<Item = Vec<f64>>, mine: &[f64]) -> Option<Vec<f64>> {
    rivals
        .map(|p| (p.iter().zip(mine).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max), p))
        .filter(|(d, _)| d.is_finite() && *d > 0.0)
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, p)| p)
}

/// The starting windows of [`restart_window`], in sampling steps Δt: one
/// narrower and one wider than the single start 2Δt of a log at 200 Hz or
/// less.
const RESTART_WINDOWS: [f64; 2] = [1.0, 3.0];

/// A two-sided contact fit `chosen` that started from one window (2Δt ≥ 10
/// ms: 200 Hz or less) against the same contact model started from
/// [`RESTART_WINDOWS`]: the peaks of the restart that differ most from the
/// chosen fit's, among those whose cost is at most `evidence` above the chosen
/// fit's (any lower one included), as a second minimum for the u
/// ([`restart_damping`]'s rival). The chosen fit stays: at 100 Hz the lower
/// minima have wider contacts that the checks cannot vouch for (forty-fourth
/// session, docs/accuracy.md), but a log that leaves the minimum open does not
/// pin the peaks either.
fn restart_window(plain: &Model, chosen: &Fitted, dt: f64, tw: &[f64], yw: &[f64], evidence: f64) -> Option<Vec<f64>> {
    let m = chosen.model.m();
    let mine: Vec<f64> = (0..m).map(|k| chosen.model.peak(k).1).collect();
    let restarts = RESTART_WINDOWS
        .iter()
        .filter_map(|&w| fit_model(plain.with_contacts(w * dt), tw, yw, 100))
        .filter(|f| f.fit.cost - chosen.fit.cost <= evidence)
        .map(|f| (0..m).map(|k| f.model.peak(k).1).collect::<Vec<f64>>())
        .filter(|p| !gains_energy(p));
    widest_rival(restarts, &mine)
}

/// Whether a fit's peaks (all the model's) read the wall gaining energy: a
/// peak of the table faster than the one before it (|v_{k+1}| > |v_k|, an
/// impact with e > 1). The model's last peak, at the end of the fit's window,
/// is not one of the table's.
fn gains_energy(peaks: &[f64]) -> bool {
    let table = &peaks[..peaks.len().saturating_sub(1)];
    table.windows(2).any(|w| w[1].abs() > w[0].abs())
}

/// A two-sided contact fit `f` against the same fit with contact phases that
/// follow the impacts' speeds ([`Model::speed_scale`]), fitted from `f`: it
/// replaces `f` where it lowers the cost by more than `evidence` (the contact
/// model's Bayesian criterion, as for [`restart_damping`]: the same number of
/// parameters, another model). Fitted also from the contact fits' own starts,
/// it read the 15 two-sided engine campaigns alike (one campaign's worst ok
/// value 0.19 pp instead of 0.35) at 1.5 × the time.
///
/// Its contact phases are not required to be short here: where the data
/// prefer contacts that grow long as the wall slows, the checks on the chosen
/// fit (`checks::contacts_too_long`) then flag the test, where the time leads'
/// shorter contacts would have passed it with its late peaks read high (the
/// MuJoCo stand-in q2-s2502's Q2_70_1: v₅ +10.1 %, r⁺ +2.34 pp at u 1.37 pp,
/// status ok).
///
/// Not tried with a stated or estimated filter (the model then goes through
/// it, and the daq campaigns and the filter draws were measured without it).
/// Not one-sided: there the leads of the impacts entering the inward side
/// scaled so (β = ½, the pushes' own left alone) met issue 18's criterion on
/// as many MuJoCo stand-ins as before (20 of 25) but left one test ok at
/// 2.17 pp off (h1-s2952), and at β = 1 (the twenty-sixth session's probe)
/// they cost the criterion on 8 of 25 (docs/accuracy.md).
fn contacts_by_speed(f: Fitted, tw: &[f64], yw: &[f64], evidence: f64) -> Fitted {
    let mut m = f.model.clone();
    m.contacts_by_speed = true;
    fit_model(m, tw, yw, 100).filter(|s| f.fit.cost - s.fit.cost > evidence).unwrap_or(f)
}

/// Starting values from the geometry and the crossings.
#[allow(clippy::too_many_arguments)]
fn starting_model(inp: &FitInput, tw: &[f64], yw: &[f64], m: usize, one_sided: bool, t_dep: f64, start_t: f64, dt: f64) -> Model {
    let rest = inp.rest;
    let lever = inp.phys.lever_arm_mm;
    let hold = median(&yw[..tw.partition_point(|&v| v < t_dep).max(1)]) - rest;
    let p = inp.phys.p_guess;
    let a = amplitude_guess(tw, yw, rest, inp.crossings, p).unwrap_or(lever * 0.15);
    let h0 = hold.max(1e-3);
    let a0 = a.max(1.5 * h0);
    let t0 = inp.crossings[0];
    let tr = t0 - ((a0 / (a0 - h0)).acosh() / p).min(t0 - start_t - dt);
    let mut q = vec![0.0; ix::IMPACT0];
    q[ix::ZERO] = rest;
    q[ix::LN_A] = a.ln();
    q[ix::LN_P] = p.ln();
    q[ix::LAMBDA] = 10.0 * p * p;
    q[ix::LN_A0] = a0.ln();
    q[ix::LN_P0] = p.ln();
    q[ix::T_R] = tr;
    q.extend_from_slice(&inp.crossings[..m]);
    let plain = Model {
        one_sided,
        layout: Layout {
            impacts: m,
            contacts: false,
            by_direction: false,
        },
        t_ref: t0,
        min_len: 0.5 * dt,
        lever,
        q,
        filter: None,
        contacts_by_speed: false,
    };
    // A stated filter delays every kink of the log by about its group delay:
    // the crossings are that late, and so would the model's times be once the
    // model goes through the filter. Its fit starts that much earlier, as an
    // estimated filter's does. (Started at the crossings, on the stated Bessel
    // draw's seeds 2000–2600, three 100 Hz tests settled with two impacts
    // merged, one 24 pp off, flagged: 98.50 % ok within 1 pp, 98.83 % so.)
    match &inp.filter {
        Some(filter) => super::acquisition::delayed_start(&plain, filter.clone()),
        None => plain,
    }
}

/// A = L tan α_e from the first full outward arc (between crossings 1 and 2): a
/// gravity arc of length T and apex height h has h = A (1 − 1/cosh(p T/2)).
fn amplitude_guess(tw: &[f64], yw: &[f64], rest: f64, crossings: &[f64], p: f64) -> Option<f64> {
    let (a, b) = (*crossings.get(1)?, *crossings.get(2)?);
    let i0 = tw.partition_point(|&v| v < a);
    let i1 = tw.partition_point(|&v| v < b);
    let h = yw.get(i0..i1)?.iter().map(|y| y - rest).fold(f64::NEG_INFINITY, f64::max);
    let denom = 1.0 - 1.0 / (0.5 * p * (b - a)).cosh();
    (h > 0.0 && denom > 1e-6).then(|| h / denom)
}

/// λ from the inward arcs: a spring arc of length T spans about half a period,
/// so λ ≈ (π/T)²; 0.8 of it keeps the start inside the valid region.
fn lambda_guess(crossings: &[f64]) -> Option<f64> {
    let t = crossings.get(1)? - crossings.first()?;
    (t > 0.0).then(|| 0.8 * (std::f64::consts::PI / t).powi(2))
}

/// The instantaneous-impact model from several starts of λ (one-sided: the
/// restraint may be soft or stiff, and one start can land in a wrong minimum);
/// the lowest cost wins.
fn best_simple_fit(base: &Model, tw: &[f64], yw: &[f64], crossings: &[f64], m: usize, one_sided: bool) -> Result<Fitted, PeakError> {
    let p2 = base.p().powi(2);
    let mut starts: Vec<f64> = if one_sided {
        vec![-0.5, 0.5, 3.0, 8.0, 15.0, 30.0, 60.0]
    } else {
        vec![1.0]
    };
    if one_sided {
        if let Some(l) = lambda_guess(crossings) {
            starts.push(l / p2);
        }
    }
    let mut best: Option<Fitted> = None;
    for s in starts {
        let mut mdl = base.clone();
        mdl.q[ix::LAMBDA] = s * p2;
        // Keep the inward arcs below a quarter period at the start.
        if one_sided && s > 0.0 {
            let w = (s * p2).sqrt();
            let longest = (1..m).step_by(2).map(|k| crossings[k] - crossings[k - 1]).fold(0.0, f64::max);
            if w * longest >= 3.0 {
                continue;
            }
        }
        if let Some(f) = fit_model(mdl, tw, yw, 60) {
            if best.as_ref().is_none_or(|b| f.fit.cost < b.fit.cost) {
                best = Some(f);
            }
        }
    }
    best.ok_or(PeakError::NoValidStart)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A contact reading may be slower than the instantaneous one by any
    /// amount, faster only within [`LEANING_FASTER`], on either side's sign.
    #[test]
    fn a_leaning_contact_reading_may_brake_but_not_speed_up() {
        let plain = [-900.0, 560.0, -300.0];
        assert!(braking_only(&plain, &[-850.0, 540.0, -250.0]));
        assert!(braking_only(&plain, &[-905.0, 563.0, -300.0]));
        assert!(!braking_only(&plain, &[-1070.0, 560.0, -300.0]));
        assert!(!braking_only(&plain, &[-900.0, 570.0, -300.0]));
        // Readings past the table's peaks are not compared.
        assert!(braking_only(&plain, &[-900.0, 560.0, -300.0, 400.0]));
    }
}
