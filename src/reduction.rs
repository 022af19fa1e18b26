//! One test's reduction, in memory: the velocity peaks of its log (the estimator,
//! [`crate::peaks`]), then the coefficients (paper Eqs. 3–6, [`crate::restitution`])
//! and their uncertainties. The log arrives already read ([`crate::ingest`] reads
//! files; the Python binding passes arrays); a failure is a typed [`ReduceError`].

use crate::impacts::{impact_table, Geometry, ImpactTable};
use crate::peaks::{analyse, Analysis, PeakError, PeakOptions, Physics, Quality};
use crate::restitution::{coefficients, uncertainties, Coefficients};
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
    /// How many peaks the analysis behind `impacts` fitted (`impacts` has one fewer).
    pub impact_peaks: usize,
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
    let analysis = analyse(&log.time_s, &log.disp_mm, phys, options)?;
    let v: Vec<f64> = analysis.peaks.iter().map(|p| p.velocity_mm_s).collect();
    let c = coefficients(&v, e_housner).ok_or(ReduceError::TooFewPeaks { found: v.len() })?;
    let u = analysis.peak_covariance.as_ref().and_then(|cov| uncertainties(&v, cov, e_housner));
    Ok(Reduced {
        log,
        analysis,
        coefficients: c,
        uncertainty: u,
        impacts: ImpactTable::default(),
        impact_peaks: 0,
    })
}

/// The most peaks any log is fitted with for its impacts (eleven impacts, as many as
/// the engine-made campaigns list).
pub const MAX_IMPACT_PEAKS: usize = 12;

/// Every impact the log resolves: the table's analysis (first `options.n_peaks`
/// peaks) is refitted with 2, 4, … more peaks, up to [`MAX_IMPACT_PEAKS`], for as
/// long as the log has the half-cycles and the refit keeps status ok (the
/// plausibility checks of [`crate::peaks::checks`]); the last such fit gives the
/// impacts ([`crate::impacts`]). A test whose longer fits all fail keeps the table's
/// n − 1 impacts; a suspect test's impacts are those of its own analysis. Only the
/// default estimator is refitted (the Savitzky–Golay one keeps its own peaks).
pub fn resolve_impacts(red: &mut Reduced, phys: &Physics, e_housner: f64, alpha_rad: f64, options: &PeakOptions) {
    let geo = |a: &Analysis, t: &[f64]| {
        impact_table(
            a,
            &Geometry {
                time_s: t,
                lever_arm_mm: phys.lever_arm_mm,
                alpha_rad,
            },
            e_housner,
        )
    };
    let mut best = (geo(&red.analysis, &red.log.time_s), red.analysis.peaks.len());
    let refit = options.method == crate::peaks::Method::Segments && red.analysis.quality.is_ok();
    let mut n = options.n_peaks + 2;
    while refit && n <= MAX_IMPACT_PEAKS {
        let opts = PeakOptions { n_peaks: n, ..*options };
        match analyse(&red.log.time_s, &red.log.disp_mm, phys, &opts) {
            Ok(a) if a.quality.is_ok() && a.peaks.len() == n => best = (geo(&a, &red.log.time_s), n),
            _ => break,
        }
        n += 2;
    }
    (red.impacts, red.impact_peaks) = best;
}

/// Contact phases are a property of the wall, not of one test: whether most of a
/// campaign's tests show them (a strict majority of those with status ok, at
/// least two). Returns (tests with contact phases, tests with status ok) when
/// they do; a test of that campaign whose own log did not ask for contact phases
/// is then re-analysed with [`crate::peaks::ContactModel::Expected`]
/// (`rocklab::reduce::campaign_result`).
pub fn campaign_shows_contacts<'a>(analyses: impl IntoIterator<Item = &'a Analysis>) -> Option<(usize, usize)> {
    let ok: Vec<&Analysis> = analyses.into_iter().filter(|a| a.quality.is_ok()).collect();
    let with = ok.iter().filter(|a| a.contact_phases).count();
    (ok.len() >= 2 && 2 * with > ok.len()).then_some((with, ok.len()))
}
