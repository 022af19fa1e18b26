//! One test's reduction, in memory: the velocity peaks of its log (the estimator,
//! [`crate::peaks`]), then the coefficients (paper Eqs. 3–6, [`crate::restitution`])
//! and their uncertainties. The log arrives already read ([`crate::ingest`] reads
//! files; the Python binding passes arrays); a failure is a typed [`ReduceError`].

use crate::impacts::{extend_late_contacts, extend_late_two_sided, impact_table, law_end, reread_contacts, Geometry, ImpactTable};
use crate::peaks::late::{arc_contact_peaks, contact_peaks, nominal_arc, CONTACT_POST_S};
use crate::peaks::{analyse, Analysis, PeakError, PeakOptions, Physics, Quality};
use crate::restitution::{coefficients, uncertainties, unresolved_reason, Coefficients};
use crate::wall::{Rocking, Wall};

/// The two channels of one log, in seconds and millimetres, outward positive.
#[derive(Debug, Clone, Default)]
pub struct LogData {
    pub time_s: Vec<f64>,
    /// Displacement at the sensor, mm, positive OUTWARD (the file's sign × outward_sign).
    pub disp_mm: Vec<f64>,
    /// What was read and how, e.g. "delimiter ';' (detected)".
    pub notes: Vec<String>,
    /// Every warning raised while reading (a dropped truncated line, …).
    pub warnings: Vec<String>,
}

/// A reduced test.
#[derive(Debug, Clone)]
pub struct Reduced {
    pub log: LogData,
    pub analysis: Analysis,
    pub coefficients: Coefficients,
    /// Standard uncertainty of every value (propagated from the peaks' covariance;
    /// default estimator only).
    pub uncertainty: Option<Coefficients>,
    /// Every impact the log resolves ([`resolve_impacts`]; empty until it runs).
    pub impacts: ImpactTable,
    /// How many peaks `impacts` comes from, the late local readings included (`impacts` has one fewer).
    pub impact_peaks: usize,
    /// One-sided walls: the first impact of `impacts` kept out of the campaign's
    /// law and why (the wall lifts off for less than half of a half-cycle around
    /// it: [`crate::impacts::law_end`]).
    pub law_end: Option<(usize, String)>,
}

impl Reduced {
    /// Why the tool cannot vouch for this test's numbers, if it cannot.
    pub fn suspect_reason(&self) -> Option<String> {
        match &self.analysis.quality {
            Quality::Ok => None,
            Quality::Suspect(r) => Some(r.join("; ")),
        }
    }
}

/// Why a log in memory could not be reduced.
#[derive(Debug, Clone, thiserror::Error)]
pub enum ReduceError {
    /// The estimator found no usable peaks (no release, too few half-cycles, …).
    #[error(transparent)]
    Peaks(#[from] PeakError),
    /// Eqs. 3–6 need six peaks.
    #[error("too few peaks (n = {found} < 6)")]
    TooFewPeaks { found: usize },
    /// A displacement no rotation about the hinge can give (session 13: a log in
    /// mm read as m was reduced into "impacts 2.5 ms apart" and ratios of 300 %).
    #[error(
        "the displacement spans {span_mm:.0} mm, more than the sensor's lever arm about the hinge ({lever_mm:.0} mm): no rotation of the wall moves the sensor that far; is the displacement's unit right ([channels].displacement.unit: a log in mm read as m is 1000 times too large)?"
    )]
    BeyondLeverArm { span_mm: f64, lever_mm: f64 },
}

/// The physics the estimator starts from: the rocking kind, the sensor's lever arm
/// about the hinge and p of the rocking part above the hinge.
pub fn physics(rocking: Rocking, wall: &Wall, lever_arm_m: f64) -> Physics {
    Physics {
        rocking,
        lever_arm_mm: lever_arm_m * 1e3,
        p_guess: wall.rocking_part().p_squared().sqrt(),
    }
}

/// Reduce one log: `log` holds time in s and displacement in mm, outward positive.
pub fn reduce_log(log: LogData, phys: &Physics, e_housner: f64, options: &PeakOptions) -> Result<Reduced, ReduceError> {
    let (lo, hi) = log
        .disp_mm
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if hi - lo > phys.lever_arm_mm {
        return Err(ReduceError::BeyondLeverArm {
            span_mm: hi - lo,
            lever_mm: phys.lever_arm_mm,
        });
    }
    let mut analysis = analyse(&log.time_s, &log.disp_mm, phys, options)?;
    let v: Vec<f64> = analysis.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let c = coefficients(&v, e_housner).ok_or(ReduceError::TooFewPeaks { found: v.len() })?;
    let u = vouch(&mut analysis, e_housner);
    Ok(Reduced {
        log,
        analysis,
        coefficients: c,
        uncertainty: u,
        impacts: ImpactTable::default(),
        impact_peaks: 0,
        law_end: None,
    })
}

/// The table values' uncertainties from the peaks' covariance, and the
/// analysis's quality with what it cannot vouch for added: a ratio read to
/// more than ± 5 pp ([`unresolved_reason`]). What `reduce` reports, and what
/// the random draws score (`crate::synth::score_with`).
pub fn vouch(analysis: &mut Analysis, e_housner: f64) -> Option<Coefficients> {
    let v: Vec<f64> = analysis.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let cov = analysis.peak_covariance.as_ref()?;
    let u = uncertainties(&v, cov, e_housner)?;
    let why = unresolved_reason(&u, &v, cov);
    analysis.quality = std::mem::replace(&mut analysis.quality, Quality::Ok).with(why);
    Some(u)
}

/// The most peaks any log is read for its impacts (eleven impacts, as many as
/// the engine-made campaigns list).
pub const MAX_IMPACT_PEAKS: usize = 12;

/// Every impact the log resolves: the table's analysis gives the impacts
/// between its peaks (n − 1 of them), and the later ones come from the peaks
/// after it, each read from the samples around it
/// ([`crate::peaks::late`], [`crate::impacts::extend_late`]; one-sided walls
/// with the contact model, [`crate::peaks::late::contact_peaks`],
/// [`crate::impacts::extend_late_contacts`]), up to
/// [`MAX_IMPACT_PEAKS`]. Only the default estimator's ok tests are extended (a
/// suspect test keeps its own analysis' impacts; the Savitzky–Golay estimator
/// its own peaks).
pub fn resolve_impacts(red: &mut Reduced, phys: &Physics, e_housner: f64, alpha_rad: f64, options: &PeakOptions) {
    let geo = Geometry {
        time_s: &red.log.time_s,
        lever_arm_mm: phys.lever_arm_mm,
        alpha_rad,
    };
    let mut table = impact_table(&red.analysis, &geo, e_housner);
    let n = red.analysis.peaks.len();
    if options.method == crate::peaks::Method::Segments && red.analysis.quality.is_ok() && n >= 2 {
        let arc = red
            .analysis
            .small_arc
            .unwrap_or_else(|| nominal_arc(phys.p_guess, alpha_rad, phys.lever_arm_mm));
        if phys.rocking == crate::wall::Rocking::TwoSided {
            let late = red.analysis.late_peaks(&red.log.time_s, phys.lever_arm_mm, n - 1, MAX_IMPACT_PEAKS);
            let contacts = arc_contact_peaks(&red.analysis, &red.log.time_s, phys.lever_arm_mm, arc, MAX_IMPACT_PEAKS, CONTACT_POST_S);
            extend_late_two_sided(&mut table, &late, &contacts, e_housner, &geo, Some(arc));
        } else {
            // Read once: the pushes' rule (`peaks::inward`) read them with the
            // same arc (the fit's own), peaks and window where it ran.
            let contacts = match red.analysis.contact_readings.take() {
                Some(c) => c,
                None => contact_peaks(&red.analysis, &red.log.time_s, phys.lever_arm_mm, arc, MAX_IMPACT_PEAKS, CONTACT_POST_S),
            };
            extend_late_contacts(&mut table, &contacts, e_housner, &geo, Some(arc));
            reread_contacts(&mut table, &contacts, n, e_housner, &geo);
            red.law_end = law_end(&contacts, arc, &geo).filter(|(k, _)| *k < table.impacts.len());
        }
    }
    if table.end.is_some() && table.impacts.len() + 1 >= MAX_IMPACT_PEAKS {
        table.end = Some(format!(
            "impact {}: not read: the readings stop at {MAX_IMPACT_PEAKS} peaks ({} impacts)",
            table.impacts.len(),
            MAX_IMPACT_PEAKS - 1
        ));
    }
    red.impact_peaks = table.impacts.len() + 1;
    red.impacts = table;
}

/// Contact phases are a property of the wall, not of one test: whether most of a
/// campaign's tests show them (a strict majority of the tests that vote, at
/// least two: status ok, or suspect only for ratios read too loosely,
/// [`votes`]). A test read through an estimated filter does not vote: its
/// rounded impacts are what the filter and the contacts compete for, so it
/// says nothing either way (on the penalty engine's one-sided campaign, seed
/// 3, its vote kept 2 of 4 from a majority, and the 100 Hz test stayed ok
/// through a filter the logger never had, r₁ 3.03 pp off: `tests/truth.rs`,
/// `a_test_read_through_an_estimated_filter_does_not_vote_on_contacts`).
/// Returns (tests with contact phases, tests that vote) when they do; a test
/// of that campaign whose own log did not ask for contact phases is then
/// re-analysed with [`crate::peaks::ContactModel::Expected`]
/// (`rocklab::reduce::campaign_result`).
pub fn campaign_shows_contacts<'a>(analyses: impl IntoIterator<Item = &'a Analysis>) -> Option<(usize, usize)> {
    let (with, voters) = contact_votes(analyses);
    shows_contacts(with, voters).then_some((with, voters))
}

/// The majority of [`campaign_shows_contacts`] from its counts: at least two
/// voters, more than half of them with contact phases.
pub fn shows_contacts(with: usize, voters: usize) -> bool {
    voters >= 2 && 2 * with > voters
}

/// (tests with contact phases, tests that vote) of [`campaign_shows_contacts`],
/// majority or not.
pub fn contact_votes<'a>(analyses: impl IntoIterator<Item = &'a Analysis>) -> (usize, usize) {
    let voters: Vec<&Analysis> = analyses
        .into_iter()
        .filter(|a| votes(a) && a.response.source != "estimated" && a.wide_rounding_read_as_contacts.is_none())
        .collect();
    (voters.iter().filter(|a| a.contact_phases).count(), voters.len())
}

/// Whether a test's analysis says what its wall's contacts are: status ok, or
/// suspect only because its ratios are read too loosely
/// ([`crate::restitution::unresolved_reason`]: too few samples or too much
/// noise around some peaks), which says nothing against the fit's contact
/// phases. On the penalty engine's one-sided seed 6 such a test (E1_160_1,
/// r₁ ± 7.0 pp, contact phases) left 1 of 2 voters with contacts; with it 2 of
/// 3, and the 200 Hz E1_140_1, suspect for a filter it could not rule out
/// (values up to 3.55 pp off), is read with the wall's contacts and no
/// filter: ok, within 0.31 pp (twenty-eighth session).
fn votes(a: &Analysis) -> bool {
    match &a.quality {
        crate::peaks::Quality::Ok => true,
        crate::peaks::Quality::Suspect(r) => !r.is_empty() && r.iter().all(|w| crate::restitution::is_unresolved_reason(w)),
    }
}

#[cfg(test)]
mod tests {
    /// The per-impact table reuses the pushes' rule's contact readings
    /// (`Analysis::contact_readings`) only because both read the same peaks.
    #[test]
    fn the_pushes_rule_reads_as_many_peaks_as_the_impact_table() {
        assert_eq!(crate::peaks::inward::PEAKS_READ, super::MAX_IMPACT_PEAKS);
    }
}
