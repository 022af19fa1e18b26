//! What a suspect test means to the engineer who has to act on it. The estimator's
//! checks ([`crate::peaks::checks`]) say in its own words why it cannot vouch for a
//! fit; each reason is sorted here into a [`Kind`], and each kind says in the lab's
//! words what went wrong, which plot shows it, how far off the values may be (as
//! measured on the random draws of `tests/suspect_reasons.rs`, see
//! docs/accuracy.md) and what to re-run. The report prints a test's reasons once,
//! in its quality section; the tables carry a short mark.

/// The kinds of suspect reasons, one per check of [`crate::peaks::checks`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Kind {
    MergedImpacts,
    Alternation,
    EnergyGain,
    ImpactGainsSpeed,
    Misfit,
    ImpactResiduals,
    Disagreement,
    LongContact,
    ContactOvershoot,
    ZeroReadings,
    /// No filter stated, and two responses (two filter families, or a filter and
    /// compliant contacts) fit the log with ratios that differ.
    FilterUnknown,
    /// A one-sided wall whose contacts last, with inward half-cycles of fewer
    /// than 9 samples ([`crate::peaks::checks::inward_arcs_unresolved`]).
    ShortInwardArcs,
    /// A ratio of the tables read to more than ± 5 pp
    /// ([`crate::restitution::RATIO_U_MAX`]).
    Unresolved,
    /// A reason this module does not know (a new check): shown as the estimator says it.
    Other,
}

/// The phrase each check's reason ends with.
const PHRASES: &[(&str, Kind)] = &[
    ("the fit merged two impacts", Kind::MergedImpacts),
    ("the peaks do not alternate", Kind::Alternation),
    ("free rocking cannot gain energy", Kind::EnergyGain),
    ("the fit cannot place this impact", Kind::ImpactGainsSpeed),
    ("the fit misses the log", Kind::Misfit),
    ("the impact is not where the fit puts it", Kind::ImpactResiduals),
    ("the two estimates disagree", Kind::Disagreement),
    ("the contact model does not describe this log", Kind::LongContact),
    ("the contact model overshoots", Kind::ContactOvershoot),
    ("does not settle where the half-cycle ends", Kind::ZeroReadings),
    ("the logger's filter is not stated and the log cannot tell", Kind::FilterUnknown),
    (crate::peaks::checks::SHORT_INWARD_ARCS, Kind::ShortInwardArcs),
    ("a ratio read to more than", Kind::Unresolved),
];

/// The kind of one reason of the estimator.
pub fn kind(reason: &str) -> Kind {
    PHRASES.iter().find(|(p, _)| reason.contains(p)).map_or(Kind::Other, |(_, k)| *k)
}

/// The reasons of a suspect test as the estimator joins them ("a; b; c"). A reason
/// never holds "; " itself.
pub fn split(reasons: &str) -> Vec<&str> {
    reasons.split("; ").map(str::trim).filter(|r| !r.is_empty()).collect()
}

/// What a kind of reason means, in the lab's words.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Advice {
    /// One line: what is wrong.
    pub title: &'static str,
    /// Which plot of the test shows it, and what to look for.
    pub look: &'static str,
    /// How far off the values may be.
    pub how_far: &'static str,
    /// What to change and re-run.
    pub rerun: &'static str,
}

const NOT_MEASURED: &str = "Not measured: no test of the random draws tripped this check. Do not use the values until the plot is explained.";

/// What the two misfit kinds add for one-sided walls with soft transverse walls
/// (docs/accuracy.md, "Twenty-ninth session": eight engine-made campaigns).
macro_rules! soft_restraint {
    () => {
        " On a one-sided wall whose pushes into the transverse walls reach about half its free arcs (soft transverse walls), the restraint model does not describe the log: on eight such engine-made campaigns 30 of 40 tests were flagged (1.1–6.2 pp off, one 27 pp), and rocklab reduce --method savgol came within 2.2 pp of every test, with no uncertainty (docs/accuracy.md, \"Twenty-ninth session\")."
    };
}

/// The advice for a kind of reason.
pub fn advice(kind: Kind) -> Advice {
    match kind {
        Kind::MergedImpacts => Advice {
            title: "Two impacts run into one: the fit found two impacts less than two samples apart.",
            look: "the velocity panel of the motion plot, at the impact named: is there one jump or two?",
            how_far: "On 200 synthetic tests with compliant contacts, the 2 flagged for this were off by 9.04 pp each (the worst of the seven values of each test): do not use the values.",
            rerun: "log at a higher rate if the wall rattles; else compare with rocklab reduce --method savgol.",
        },
        Kind::Alternation => Advice {
            title: "The velocity peaks do not alternate inward, outward: a half-cycle was missed or invented.",
            look: "the velocity panel of the motion plot: count the half-cycles against the red dots.",
            how_far: NOT_MEASURED,
            rerun: "check outward_sign and the displacement column in the manifest; trim a log that starts before the release.",
        },
        Kind::EnergyGain => Advice {
            title: "A velocity peak is faster than the one before: a free-rocking wall cannot gain energy.",
            look: "the velocity panel of the motion plot, at the peak named, and the ratios plot (a ratio above 1).",
            how_far: "Not measured on the random draws (no test tripped it). The ratio across that peak comes out above 1, which no impact gives: do not use the values that involve it.",
            rerun: "check that nothing pushed the wall during the test; re-run with rocklab reduce --method savgol to compare.",
        },
        Kind::ImpactGainsSpeed => Advice {
            title: "An impact leaves the wall faster than it found it (e > 1): the fit has the impact's time wrong.",
            look: "the displacement panel of the motion plot around the impact named: a rounded, slow contact.",
            how_far: "No test of the random draws tripped it. A one-sided engine-made wall logged at 100 Hz and reduced alone, the one test found, was 3.73 pp off (r₁, with its peaks up to 12 % off); read with its campaign's contact phases, 1.04 pp (docs/accuracy.md).",
            rerun: "a higher logging rate resolves the contact; at the same rate compare with rocklab reduce --method savgol.",
        },
        Kind::Misfit => Advice {
            title: "The model does not follow the log: the residuals are several times the sensor's noise.",
            look: "the displacement panel of the motion plot: where does the red fit leave the grey log?",
            how_far: "On 200 synthetic tests with compliant contacts, the 4 flagged for this were off by 6.75 pp at the median and 7.18 pp at worst (the worst of the seven values of each test): do not use the values.",
            rerun: concat!(
                "check the wall's geometry and hinge height in [wall], and the sensor's height; a log with drift or a moving base needs trimming.",
                soft_restraint!()
            ),
        },
        Kind::ImpactResiduals => Advice {
            title: "The log around an impact is not where the fit puts it.",
            look: "the displacement panel of the motion plot, zoomed on the impact named.",
            how_far: "On 200 synthetic tests with compliant contacts, the 9 flagged for this were off by 2.20 pp at the median and 7.18 pp at worst (the worst of the seven values of each test). On a one-sided wall, residuals that stand out only where the wall leaves the transverse walls are not a reason (the peaks are not read from there; docs/estimator.md); around an entry they are, unless the entry comes right after such an exit and the peaks do not move when the fit leaves out the samples around both.",
            rerun: concat!(
                "look for a spike or a dropout near the impact in the raw log; a higher logging rate helps.",
                soft_restraint!()
            ),
        },
        Kind::Disagreement => Advice {
            title: "Two ways of reading a peak disagree: the whole-record fit and a fit of that half-cycle alone, or the log's slope into its crossing.",
            look: "the velocity panel of the motion plot at the peak named: does the blue fit follow the grey velocity into the impact?",
            how_far: "No test of the random draws tripped it. The reason gives both readings: the peak may lie anywhere between them, and the ratios that use it move with it. On a one-sided engine-made wall logged at 100 Hz, the two tests found (one read through an estimated FIR) had their free arcs' ends read 2–10 % high and r⁻ 1.58 and 1.68 pp off (docs/accuracy.md).",
            rerun: "compare with rocklab reduce --method savgol; a higher logging rate narrows the disagreement.",
        },
        Kind::LongContact => Advice {
            title: "The contact at an impact lasts too long for an impact: the wall is not rocking freely there.",
            look: "the displacement panel of the motion plot around the impact named: a slow, rounded turn instead of a kink.",
            how_far: "On 200 synthetic tests with compliant contacts, the 10 flagged for this were off by 2.33 pp at the median and 7.18 pp at worst (the worst of the seven values of each test).",
            rerun: "check that the wall is free to rock (no mortar bridge or friction at the hinge); trim the log to the clean impacts.",
        },
        Kind::ContactOvershoot => Advice {
            title: "Inside a contact the fitted speed overshoots the free swing: the contact model does not fit this impact.",
            look: "the velocity panel of the motion plot at the peak named: is the blue curve above the grey one?",
            how_far: "On 200 synthetic tests with compliant contacts, the 7 flagged for this were off by 2.78 pp at the median and 6.75 pp at worst (the worst of the seven values of each test).",
            rerun: "compare with rocklab reduce --method savgol; a higher logging rate resolves the contact.",
        },
        Kind::ZeroReadings => Advice {
            title: "The peak depends on where the wall's rest position is taken: the fitted zero and the final rest differ.",
            look: "the displacement panel of the motion plot: is the final rest level with the zero the fit crosses?",
            how_far: "Not measured on the random draws (no test tripped it). The peak moves by the amount the reason gives (more than 20 % of it) between the two readings; the ratios that use it may be off by as much.",
            rerun: "log a longer rest after the wall stops, so the rest line is well defined.",
        },
        Kind::FilterUnknown => Advice {
            title: "The logger's filter is not stated, and two explanations of the rounded impacts fit the log equally well but give different coefficients.",
            look: "the displacement panel of the motion plot around the impacts: rounded turns; the reason names both explanations and how far their ratios differ.",
            how_far: "On 200 synthetic tests with compliant contacts and no filter stated, the 6 flagged for this were off by 2.00 pp at the median and 5.75 pp at worst (the worst of the seven values of each test); on 500 idealised tests, the one flagged for this was 0.04 pp off (docs/accuracy.md).",
            rerun: "state the logger's filter in the manifest's [acquisition] (type, order and cut-off from the logger's data sheet; filter = \"none\" if it has none) and re-run reduce.",
        },
        Kind::ShortInwardArcs => Advice {
            title: "The excursions into the transverse walls span too few samples for a wall whose contacts last.",
            look: "the motion plot over the short excursions below zero (the inward half-cycles; in the velocity panel, each steep rise): the reason says how many samples span the shortest, the fit is drawn over them, and the push at each excursion's end, the velocity's top, falls between two of them.",
            how_far: "On engine-made one-sided walls with fewer than 9 samples per excursion (all logged at 100 Hz), 8 of the 25 tests that passed every other check read a value 1.0–2.7 pp off, each within 2 of its stated u; with 9 samples or more, 16 of 180 were more than 1 pp off (docs/accuracy.md, \"Thirty-sixth session\").",
            rerun: "log at the rate the reason names or higher (9 samples or more per excursion); until then the values hold only as far as their u says.",
        },
        Kind::Unresolved => Advice {
            title: "Some ratios are read too loosely to use: their standard uncertainty is above 5 pp.",
            look: "the velocity panel of the motion plot at the peaks named: how many samples span each, and how large the noise is beside them.",
            how_far: "As far as their u says, and no closer: on a one-sided engine-made wall logged at 100 Hz, whose inward excursions span a few samples, r₁ read 0.76 ± 0.64 against the engine's 0.68 (docs/accuracy.md).",
            rerun: "log at a higher rate, so that the half-cycles named span more samples; the ratios the reason does not name are as resolved as their u says.",
        },
        Kind::Other => Advice {
            title: "The estimator cannot vouch for this test.",
            look: "the motion and ratios plots of the test.",
            how_far: NOT_MEASURED,
            rerun: "compare with rocklab reduce --method savgol.",
        },
    }
}

/// The campaign-level sentence where no test is in the means (every one suspect,
/// excluded or not reduced): there is then no campaign mean and no restitution
/// law, and a person who reads only the head of the report must learn that
/// there, with the commonest reason among the suspect tests. `suspect` holds each
/// suspect test's reasons as the estimator joins them; `n_tests` counts every
/// test. None where some test is in the means.
pub fn none_vouched(n_included: usize, n_tests: usize, suspect: &[&str]) -> Option<String> {
    if n_included > 0 || n_tests == 0 {
        return None;
    }
    let mut counts: Vec<(Kind, usize)> = Vec::new();
    for reasons in suspect {
        let mut kinds: Vec<Kind> = split(reasons).into_iter().map(kind).collect();
        kinds.sort();
        kinds.dedup();
        for k in kinds {
            match counts.iter_mut().find(|(c, _)| *c == k) {
                Some((_, n)) => *n += 1,
                None => counts.push((k, 1)),
            }
        }
    }
    // The most frequent kind; among equals, the first in Kind's order.
    counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let which = match n_tests {
        1 => "The campaign's one test is not in the means (it is suspect, excluded or not reduced)".to_string(),
        n => format!("None of the campaign's {n} tests is in the means (each is suspect, excluded or not reduced)"),
    };
    let head = format!("{which}: there is no campaign mean and no restitution law.");
    Some(match counts.first() {
        Some((k, n)) if *k != Kind::Other => format!(
            "{head} The commonest reason ({n} of {} suspect tests): {}",
            suspect.len(),
            advice(*k).title
        ),
        _ => head,
    })
}

/// [`none_vouched`] of a reduced campaign.
pub fn none_vouched_in(res: &crate::reduce::CampaignResult) -> Option<String> {
    let reasons: Vec<String> = res.tests.iter().filter_map(|t| t.result.as_ref().ok()?.suspect_reason()).collect();
    let reasons: Vec<&str> = reasons.iter().map(String::as_str).collect();
    none_vouched(res.means.included.len(), res.tests.len(), &reasons)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::peaks::{acquisition, checks};

    /// Every check's reason is sorted into its own kind: a reworded reason fails
    /// here instead of falling through to `Other` in the report.
    #[test]
    fn every_check_has_its_kind() {
        let cases = [
            (checks::merged_impacts(&[1.0, 1.001], 0.005), Kind::MergedImpacts),
            (checks::alternation(&[-5.0, -4.0]), Kind::Alternation),
            (checks::energy_gain(&[-5.0, 9.0], &[0.0, 0.0]), Kind::EnergyGain),
            (checks::impact_gains_speed(&[-5.0], &[Some(9.0)], &[0.0, 0.0]), Kind::ImpactGainsSpeed),
            (checks::misfit(&[1.0, -1.0, 1.0, -1.0], 0.01), Kind::Misfit),
            (
                checks::structured_near_impacts(&[0.99, 1.0, 1.01], &[1.0, -1.0, 1.0], &[1.0], 0.01, 0.01),
                Kind::ImpactResiduals,
            ),
            (checks::disagreement(&[-100.0], &[0.1], &[Some((-50.0, 0.1))]), Kind::Disagreement),
            (
                checks::contact_too_long(&[(0.05, 0.05)], &[0.1, 0.1], &[false, false], usize::MAX),
                Kind::LongContact,
            ),
            (checks::contact_overshoot(&[-100.0], &[-50.0], &[0.1], &[false]), Kind::ContactOvershoot),
            (checks::zero_readings_disagree(&[-100.0], &[40.0]), Kind::ZeroReadings),
            (
                acquisition::contact_check(
                    acquisition::Generic::Bessel4,
                    20.0,
                    &[-100.0, 50.0],
                    &[-100.0, 40.0],
                    -1.0,
                    &acquisition::Lean {
                        trend: None,
                        preferred: true,
                    },
                ),
                Kind::FilterUnknown,
            ),
            (
                checks::inward_arcs_unresolved(&[0.5, 0.56, 1.0, 1.06, 1.4, 1.46], 6, 0.01, true),
                Kind::ShortInwardArcs,
            ),
            (unresolved_case(), Kind::Unresolved),
        ];
        for (reason, want) in cases {
            let reason = reason.unwrap_or_else(|| panic!("the {want:?} case does not trip its check"));
            assert_eq!(kind(&reason), want, "{reason}");
            assert!(!reason.contains("; "), "a reason holds the separator: {reason}");
        }
        assert_eq!(kind("something new"), Kind::Other);
    }

    /// Six peaks whose peak 1 is read to ± 80 %: r₁ and the ratios through it.
    fn unresolved_case() -> Option<String> {
        let v: [f64; 6] = [-500.0, 400.0, -320.0, 260.0, -200.0, 160.0];
        let mut cov = vec![vec![0.0; 6]; 6];
        for (k, row) in cov.iter_mut().enumerate() {
            row[k] = (if k == 1 { 0.8 * v[k] } else { 0.005 * v[k] }).powi(2);
        }
        let u = crate::restitution::uncertainties(&v, &cov, 0.97)?;
        crate::restitution::unresolved_reason(&u, &v, &cov)
    }

    #[test]
    fn a_campaign_with_no_test_in_the_means_says_so_with_its_commonest_reason() {
        let misfit = "the fit misses the log: the residuals spread 0.1 mm, 4 × the noise (0.03 mm)";
        let both =
            format!("{misfit}; the residuals around impact 2 stand out (spread 0.5 mm, 17 × the noise): the impact is not where the fit puts it");
        let residuals = "the residuals around impact 0 stand out (spread 0.2 mm, 9 × the noise): the impact is not where the fit puts it";
        let s = none_vouched(0, 3, &[&both, residuals, misfit]).unwrap();
        assert!(s.starts_with("None of the campaign's 3 tests is in the means"), "{s}");
        // Misfit and ImpactResiduals both count 2 of 3; Misfit comes first in Kind's order.
        assert!(s.contains("(2 of 3 suspect tests)") && s.contains(advice(Kind::Misfit).title), "{s}");
        assert_eq!(none_vouched(1, 3, &[misfit]), None);
        assert_eq!(none_vouched(0, 0, &[]), None);
        // Every test excluded by the lab: no reason to name.
        assert_eq!(
            none_vouched(0, 2, &[]).unwrap(),
            "None of the campaign's 2 tests is in the means (each is suspect, excluded or not reduced): there is no campaign mean and no restitution law."
        );
    }

    #[test]
    fn reasons_split_on_the_estimators_separator() {
        assert_eq!(split("a: b; c"), vec!["a: b", "c"]);
        assert!(split("").is_empty());
    }
}
