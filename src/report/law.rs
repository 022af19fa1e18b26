//! The per-impact outputs of `reduce` (issue 20): `impacts.csv` (every impact of
//! every test), the restitution-law plot (`plots/restitution_law.{png,svg}`) and its
//! section of report.html.

use super::plots::{self, Figure};
use super::table::escape;
use super::{Files, ReportError};
use crate::impacts::side_label;
use crate::law_fit::LawFit;
use crate::reduce::CampaignResult;
use crate::wall::Side;

/// `impacts.csv`: one row per impact with a coefficient, of every reduced test.
pub fn impacts_csv(res: &CampaignResult) -> Result<Vec<u8>, ReportError> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "test",
        "status",
        "k",
        "side",
        "amplitude_over_alpha",
        "speed_before_mm_s",
        "speed_after_mm_s",
        "e",
        "e_u",
        "r",
        "r_u",
        "lifts_off",
    ])?;
    let opt = |x: Option<f64>| x.map_or(String::new(), |v| format!("{v:.6}"));
    for t in &res.tests {
        let Ok(r) = &t.result else { continue };
        let status = if r.analysis.quality.is_ok() { "ok" } else { "suspect" };
        for i in &r.impacts.impacts {
            let lifts_off = r.law_end.as_ref().is_none_or(|(from, _)| i.k < *from);
            w.write_record([
                t.spec.id.clone(),
                status.into(),
                i.k.to_string(),
                side_label(i.side).into(),
                format!("{:.6}", i.amplitude_over_alpha),
                format!("{:.3}", i.speed_before_mm_s),
                format!("{:.3}", i.speed_after_mm_s),
                format!("{:.6}", i.e),
                opt(i.e_u),
                format!("{:.6}", i.r),
                opt(i.r_u),
                lifts_off.to_string(),
            ])?;
        }
    }
    super::csv_bytes(w)
}

/// The plot of r against amplitude: a panel per side (one for two-sided rocking).
pub fn law_figure(res: &CampaignResult, fit: &LawFit) -> Result<Figure, ReportError> {
    let groups: Vec<(&str, Vec<Side>, Side)> = if fit.law.parameters.shared {
        vec![("both sides", vec![Side::Inward, Side::Outward], Side::Inward)]
    } else {
        vec![
            ("entering the inward side", vec![Side::Inward], Side::Inward),
            ("entering the outward side", vec![Side::Outward], Side::Outward),
        ]
    };
    let curve = fit.law.curve(60);
    let panels: Vec<plots::Panel> = groups
        .iter()
        .map(|(name, sides, side)| {
            // Impacts a test keeps out of the law (the wall barely lifts off
            // around them, `law_end`) are drawn as one series of their own.
            let mut out_of_law: Vec<(f64, f64)> = Vec::new();
            let mut tests: Vec<(String, Vec<(f64, f64)>)> = res
                .tests
                .iter()
                .filter_map(|t| t.result.as_ref().ok().map(|r| (t, r)))
                .map(|(t, r)| {
                    let (pts, out): (Vec<&crate::impacts::ImpactCoefficient>, Vec<_>) = r
                        .impacts
                        .impacts
                        .iter()
                        .filter(|i| sides.contains(&i.side))
                        .partition(|i| r.law_end.as_ref().is_none_or(|(from, _)| i.k < *from));
                    out_of_law.extend(out.iter().map(|i| (i.amplitude_over_alpha, i.r)));
                    let pts: Vec<(f64, f64)> = pts.iter().map(|i| (i.amplitude_over_alpha, i.r)).collect();
                    let tag = if r.analysis.quality.is_ok() && !t.spec.exclude_from_mean {
                        ""
                    } else {
                        " (not fitted)"
                    };
                    (format!("test {}{tag}", t.spec.id), pts)
                })
                .collect();
            if !out_of_law.is_empty() {
                tests.push(("kept out of the law (barely lifts off)".to_string(), out_of_law));
            }
            let law: Vec<(f64, f64, f64)> = curve
                .iter()
                .map(|p| match side {
                    Side::Inward => (p.amplitude_over_alpha, p.r_in, p.r_in_u),
                    Side::Outward => (p.amplitude_over_alpha, p.r_out, p.r_out_u),
                })
                .collect();
            let constant = fit.constant.r(*side, 0.1);
            // The amplitudes this side's law was fitted on ("both" two-sided).
            let key = if fit.law.parameters.shared {
                "both"
            } else if *side == Side::Inward {
                "in"
            } else {
                "out"
            };
            let fitted = fit
                .sides
                .iter()
                .find(|(k, _)| k == key)
                .map_or((0.0, f64::INFINITY), |(_, f)| (f.amplitude_min, f.amplitude_max));
            plots::law_panel(
                &format!("{}: r of every impact, {name}", res.campaign.name),
                &tests,
                &law,
                constant,
                fitted,
            )
        })
        .collect();
    plots::render(&panels, 900, 420)
}

/// The law's section of report.html: what was fitted, the test against the constant,
/// the figure; or why there is no law.
pub fn law_section(res: &CampaignResult, figure: Option<&Figure>) -> String {
    let mut s = String::from("<h2>Restitution law (every impact)</h2>\n");
    let fit = match &res.law {
        Ok(f) => f,
        Err(e) => return s + &format!("<p>No law fitted: {}.</p>\n", escape(&e.to_string())),
    };
    let p = &fit.law.parameters;
    let side = |name: &str, l: &crate::restitution_law::SideLaw| {
        let g = match l.g {
            crate::restitution_law::Shape::Free => "√(a(2 − a))",
            crate::restitution_law::Shape::Push => "a",
        };
        // A rise (c < 0) reads "+ |c|", not "− -c".
        let mut t = format!(
            "{name}: r(a) = {:.4} (± {:.4}) {} {:.5} (± {:.5}) / {g}",
            l.r_inf,
            l.cov[0][0].sqrt(),
            if l.c < 0.0 { "+" } else { "−" },
            l.c.abs(),
            l.cov[1][1].sqrt(),
        );
        if let Some(e) = &l.energy {
            let g2 = match l.g {
                crate::restitution_law::Shape::Free => "(a(2 − a))",
                crate::restitution_law::Shape::Push => "a²",
            };
            t.push_str(&format!(
                " − {:.3e} (± {:.1e}) / {g2} (its tangent outside a = {:.4}–{:.3})",
                e.c2,
                e.cov[2][2].max(0.0).sqrt(),
                l.g.eval_inverse(e.g_hi),
                l.g.eval_inverse(e.g_lo)
            ));
        }
        t
    };
    let text = if p.shared {
        side("both sides", &p.inward)
    } else {
        format!("{}; {}", side("in", &p.inward), side("out", &p.outward))
    };
    s.push_str(&format!(
        "<p>Form {}: r = r∞ − c/√(a(2 − a)), a fixed loss of angular speed per impact on top of a proportional one{}{} (docs/restitution-law.md). {}. Fitted to the impacts of {} (status ok, in the means), amplitudes {:.3}–{:.3}.</p>\n",
        fit.law.form.as_str(),
        if p.outward.g == crate::restitution_law::Shape::Push {
            "; the outward side of a one-sided wall r = r∞ − c/a (its impacts end a push against the transverse walls, speed ∝ amplitude)"
        } else {
            ""
        },
        if fit.law.form == crate::restitution_law::LawForm::SpeedAndEnergyLoss {
            "; where Akaike's criterion prefers it, a fixed loss of energy per impact besides, − c₂ g² (the loss grows faster as the amplitude falls)"
        } else {
            ""
        },
        escape(&text),
        escape(&fit.tests_used.join(", ")),
        p.amplitude_min,
        p.amplitude_max
    ));
    let tests: Vec<String> = fit
        .sides
        .iter()
        .map(|(name, f)| {
            format!(
                "{name}: F = {:.2}, p = {:.2e} ({} impacts, χ²/ν = {:.2}; constant r = {:.4} ± {:.4})",
                f.statistic,
                f.p_value,
                f.impacts,
                f.chi2_law / f.dof.max(1) as f64,
                f.constant_r,
                f.constant_u
            )
        })
        .collect();
    let verdict = if fit.rejects_constant {
        "The data reject a constant coefficient"
    } else {
        "The data do not reject a constant coefficient"
    };
    s.push_str(&format!(
        "<p>{verdict} (level {} split over the sides): {}. A side applies the speed-loss form where Akaike's criterion prefers it to the constant (F &gt; {}), which answers what r to predict rather than whether the data prove a trend; the notes say which side does and why.</p>\n",
        crate::law_fit::ALPHA_TEST,
        escape(&tests.join("; ")),
        crate::law_fit::AIC_PENALTY
    ));
    s.push_str("<p>What the law vouches for:</p>\n<ul>\n");
    for n in &fit.notes {
        s.push_str(&format!("<li>{}</li>\n", escape(n)));
    }
    s.push_str("</ul>\n");
    s.push_str(&impacts_end_list(res));
    if let Some(f) = figure {
        s.push_str(&format!(
            "<figure>{}<figcaption>r = e/e_H of every impact against the amplitude of the half-cycle it ends, by test; the law with its ±1 u band and the constant for comparison.</figcaption></figure>\n",
            f.svg
        ));
    }
    s
}

/// Where each test's list of impacts ends and why (tests with status ok whose
/// late readings extended it), as a list for report.html; empty if none.
fn impacts_end_list(res: &CampaignResult) -> String {
    let items: Vec<String> = res
        .tests
        .iter()
        .filter_map(|t| {
            let r = t.result.as_ref().ok().filter(|r| r.analysis.quality.is_ok())?;
            let end = r.impacts.end.as_deref()?;
            let out_of_law = r.law_end.as_ref().map_or(String::new(), |(_, why)| format!("; {}", escape(why)));
            Some(format!(
                "<li>{}: {} reported; {}{out_of_law}</li>\n",
                escape(&t.spec.id),
                r.impacts.impacts.len(),
                escape(end)
            ))
        })
        .collect();
    if items.is_empty() {
        return String::new();
    }
    format!(
        "<p>Where each test's impacts end (an impact the readings cannot vouch for is not in the table):</p>\n<ul>\n{}</ul>\n",
        items.concat()
    )
}

/// Adds impacts.csv and the law's plot to `files`; returns the report section.
pub fn law_files(res: &CampaignResult, with_plots: bool, files: &mut Files) -> Result<String, ReportError> {
    files.add("impacts.csv", impacts_csv(res)?);
    let figure = match (&res.law, with_plots) {
        (Ok(fit), true) => Some(law_figure(res, fit)?),
        _ => None,
    };
    if let Some(f) = &figure {
        f.add_to(files, "plots/restitution_law");
    }
    Ok(law_section(res, figure.as_ref()))
}
