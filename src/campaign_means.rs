//! The campaign means of the ratios (the mean rows of paper Tables 1–3), which leave out the tests
//! flagged `exclude_from_mean` and the tests that could not be reduced, and say so.

use crate::restitution::Coefficients;

/// One row of the campaign: a test id, whether it counts in the mean, its values.
#[derive(Debug, Clone)]
pub struct Row {
    pub id: String,
    pub exclude_from_mean: bool,
    pub coefficients: Option<Coefficients>,
    /// Why the estimator cannot vouch for the values (a suspect test is left out
    /// of the means).
    pub suspect: Option<String>,
}

/// Campaign means of the ratios.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Means {
    pub r: f64,
    pub r_plus: f64,
    pub r_minus: f64,
    pub r1: f64,
    pub r1_plus: f64,
    pub r1_minus: f64,
    pub r2: f64,
}

/// Means over the included rows, with the ids of the included and left-out tests.
#[derive(Debug, Clone)]
pub struct CampaignMeans {
    pub means: Option<Means>,
    /// Standard uncertainty of each mean from the test-to-test scatter, s/√N
    /// (N ≥ 2 included tests): it holds the measurement noise and the real
    /// differences between tests.
    pub means_u: Option<Means>,
    pub included: Vec<String>,
    /// (id, why) of every test left out.
    pub left_out: Vec<(String, String)>,
}

impl CampaignMeans {
    /// "50_1 (exclude_from_mean), 100_2 (not reduced)".
    pub fn left_out_text(&self) -> String {
        left_out_text(&self.left_out)
    }
}

/// "50_1 (exclude_from_mean), 100_2 (not reduced)" of (id, why) pairs.
pub fn left_out_text(left_out: &[(String, String)]) -> String {
    left_out.iter().map(|(id, why)| format!("{id} ({why})")).collect::<Vec<_>>().join(", ")
}

/// A statistic of one quantity over the included tests (its mean, its standard error).
type Statistic<'a> = dyn Fn(&dyn Fn(&Coefficients) -> f64) -> f64 + 'a;

pub fn campaign_means(rows: &[Row]) -> CampaignMeans {
    let mut included = Vec::new();
    let mut left_out = Vec::new();
    let mut vals: Vec<Coefficients> = Vec::new();
    for row in rows {
        match (&row.coefficients, row.exclude_from_mean) {
            (_, true) => left_out.push((row.id.clone(), "exclude_from_mean".into())),
            (None, false) => left_out.push((row.id.clone(), "not reduced".into())),
            (Some(_), false) if row.suspect.is_some() => left_out.push((row.id.clone(), "suspect".into())),
            (Some(c), false) => {
                included.push(row.id.clone());
                vals.push(*c);
            }
        }
    }
    let n = vals.len() as f64;
    let mean_of = |f: &dyn Fn(&Coefficients) -> f64| vals.iter().map(f).sum::<f64>() / n;
    let sem_of = |f: &dyn Fn(&Coefficients) -> f64| {
        let m = mean_of(f);
        (vals.iter().map(|c| (f(c) - m).powi(2)).sum::<f64>() / (n - 1.0) / n).sqrt()
    };
    let build = |g: &Statistic| Means {
        r: g(&|c| c.r),
        r_plus: g(&|c| c.r_plus),
        r_minus: g(&|c| c.r_minus),
        r1: g(&|c| c.r1),
        r1_plus: g(&|c| c.r1_plus),
        r1_minus: g(&|c| c.r1_minus),
        r2: g(&|c| c.r2),
    };
    let means = (!vals.is_empty()).then(|| build(&mean_of));
    let means_u = (vals.len() >= 2).then(|| build(&sem_of));
    CampaignMeans {
        means,
        means_u,
        included,
        left_out,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(id: &str, rp: f64, rm: f64, r: f64, excl: bool) -> Row {
        Row {
            id: id.into(),
            exclude_from_mean: excl,
            coefficients: Some(Coefficients {
                e: r,
                e_plus: rp,
                e_minus: rm,
                r,
                r_plus: rp,
                r_minus: rm,
                r1: 0.0,
                r1_plus: 0.0,
                r1_minus: 0.0,
                r2: 0.0,
            }),
            suspect: None,
        }
    }

    /// A suspect test is left out of the means and named with the reason.
    #[test]
    fn suspect_tests_are_left_out() {
        let mut bad = row("150_3", 9.0, 9.0, 9.0, false);
        bad.suspect = Some("the fit merged two impacts".into());
        let m = campaign_means(&[row("150_1", 0.6, 0.5, 0.55, false), bad]);
        assert_eq!(m.means.unwrap().r_plus, 0.6);
        assert_eq!(m.left_out, vec![("150_3".to_string(), "suspect".to_string())]);
    }

    #[test]
    fn paper_table_1_means_without_50_1() {
        // Paper Table 1 (r+, r-, r); §5.2: the means without 50_1 are 0.68 outward
        // and 0.59 inward.
        let rows = vec![
            row("150_1", 0.67, 0.59, 0.57, false),
            row("150_2", 0.65, 0.57, 0.59, false),
            row("150_3", 0.71, 0.61, 0.66, false),
            row("100_1", 0.68, 0.58, 0.63, false),
            row("50_1", 0.62, 0.59, 0.59, true),
        ];
        let m = campaign_means(&rows);
        let means = m.means.unwrap();
        assert_eq!(format!("{:.2}", means.r_minus), "0.59");
        assert_eq!(format!("{:.2}", means.r_plus), "0.68");
        assert_eq!(m.left_out, vec![("50_1".to_string(), "exclude_from_mean".to_string())]);
        assert_eq!(m.included.len(), 4);
    }
}
