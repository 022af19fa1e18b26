//! What the façade study's runs add up to, for its tables and plots: a run found
//! by its key (record, coefficient set, polarity as ±1, never by comparing
//! floats), and the incremental dynamic analysis (IDA) per coefficient set — the
//! fraction of records × polarities that overturn at each scale, and each record
//! and polarity's max θ/α against the scale.

use crate::facade::{IdaPoint, StudyRun};

/// The key of a polarity: +1 or −1, the same conversion the study's runs use
/// (`StudyRun::polarity`, `IdaPoint::polarity`).
pub fn polarity_key(p: f64) -> i8 {
    p as i8
}

/// The run of `record` under `set` at polarity `polarity`.
pub fn find_run<'a>(runs: &'a [StudyRun], record: &str, set: &str, polarity: i8) -> Option<&'a StudyRun> {
    runs.iter()
        .find(|r| r.record == record && r.coefficients == set && r.polarity == polarity)
}

/// The share of an IDA's runs under one coefficient set that overturned at one
/// scale (a row of ida_fraction.csv).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct IdaFraction {
    pub coefficients: String,
    pub scale: f64,
    pub fraction_overturned: f64,
    pub runs: usize,
}

/// The fraction of runs that overturned per coefficient set and scale (the
/// scales in the order given; an empty group counts as 0 of 1).
pub fn ida_fractions(points: &[IdaPoint], sets: &[&str], scales: &[f64]) -> Vec<IdaFraction> {
    let mut out = Vec::new();
    for set in sets {
        for (k, &sc) in scales.iter().enumerate() {
            let here: Vec<&IdaPoint> = points
                .iter()
                .filter(|p| p.coefficients == *set && scale_index(scales, p.scale) == Some(k))
                .collect();
            let overturned = here.iter().filter(|p| p.overturned).count();
            out.push(IdaFraction {
                coefficients: set.to_string(),
                scale: sc,
                fraction_overturned: overturned as f64 / here.len().max(1) as f64,
                runs: here.len(),
            });
        }
    }
    out
}

/// Which of `scales` a point was run at (the points carry a copy of the scale
/// they were run at, so the comparison is exact).
fn scale_index(scales: &[f64], scale: f64) -> Option<usize> {
    scales.iter().position(|s| s.to_bits() == scale.to_bits())
}

/// max θ/α (1 once overturned) against the scale for one set, record and polarity,
/// in the order the IDA ran them.
pub fn ida_curve(points: &[IdaPoint], set: &str, record: &str, polarity: i8) -> Vec<(f64, f64)> {
    points
        .iter()
        .filter(|x| x.coefficients == set && x.record == record && x.polarity == polarity)
        .map(|x| (x.scale, x.max_theta_over_alpha.min(1.0)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(set: &str, record: &str, polarity: i8, scale: f64, peak: f64) -> IdaPoint {
        IdaPoint {
            record: record.into(),
            coefficients: set.into(),
            polarity,
            scale,
            max_theta_over_alpha: peak,
            overturned: peak >= 1.0,
        }
    }

    #[test]
    fn fractions_count_the_overturned_runs_per_set_and_scale() {
        let pts = [
            point("a", "r1", 1, 0.5, 0.2),
            point("a", "r1", -1, 0.5, 1.0),
            point("a", "r1", 1, 1.5, 1.0),
            point("a", "r1", -1, 1.5, 1.0),
            point("b", "r1", 1, 0.5, 0.1),
        ];
        let f = ida_fractions(&pts, &["a", "b"], &[0.5, 1.5]);
        let got: Vec<(f64, usize)> = f.iter().map(|x| (x.fraction_overturned, x.runs)).collect();
        assert_eq!(got, vec![(0.5, 2), (1.0, 2), (0.0, 1), (0.0, 0)]);
        assert_eq!(ida_curve(&pts, "a", "r1", -1), vec![(0.5, 1.0), (1.5, 1.0)]);
    }

    #[test]
    fn polarity_keys_are_plus_and_minus_one() {
        assert_eq!((polarity_key(1.0), polarity_key(-1.0)), (1, -1));
    }
}
