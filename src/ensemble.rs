//! Uncertainty ensembles for the façade study: what an input's distribution is,
//! how each sample of the ensemble draws its inputs, and what the ensemble says
//! (P(overturn) with its Wilson interval, the distribution of the peak, the median
//! overturning time).
//!
//! Seeding: sample i of the ensemble for (record, polarity row) draws the inputs the
//! coefficient sets share (magnification, geometry, restraint, a random polarity)
//! from the stream keyed by (seed, record, polarity row, scale index, i, input), and
//! the set's own e_in/e_out from the stream keyed by (seed, record, polarity row,
//! scale index, i, set, input); a law set draws the four standard normals of its
//! parameters ([`RestitutionLaw::sample`]) from one such stream. Every draw is a pure function of its key
//! ([`SplitMix64::for_key`]), so the numbers do not depend on the thread count or
//! on the order of the runs, and the sets are compared under common random
//! numbers: sample i of Housner's set and sample i of the calibrated set see the
//! same ground motion, geometry and restraint, and differ only in e (a paired
//! comparison). Records and sets are keyed by a hash of their names, so
//! reordering the study file changes nothing.

use crate::restitution_law::{LawReading, RestitutionLaw};
use crate::stats::{quantile_sorted, sorted, wilson, SplitMix64, Z95};
use crate::wall::{housner_e, Side};

/// The distribution of one uncertain input.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Dist {
    Fixed {
        value: f64,
    },
    /// Normal, truncated to the input's valid range by redrawing.
    Normal {
        mean: f64,
        sd: f64,
    },
    Uniform {
        lo: f64,
        hi: f64,
    },
}

impl Dist {
    /// A draw inside (lo, hi]: a normal draw outside is redrawn (up to 1000
    /// times, then clamped; only reached when almost all the mass is outside).
    pub fn sample(&self, rng: &mut SplitMix64, lo: f64, hi: f64) -> f64 {
        match *self {
            Dist::Fixed { value } => value,
            Dist::Uniform { lo: a, hi: b } => a + (b - a) * rng.uniform(),
            Dist::Normal { mean, sd } => {
                for _ in 0..1000 {
                    let x = mean + sd * rng.normal();
                    if x > lo && x <= hi {
                        return x;
                    }
                }
                mean.clamp(lo, hi)
            }
        }
    }

    /// The centre of the distribution (mean, or mid-range).
    pub fn centre(&self) -> f64 {
        match *self {
            Dist::Fixed { value } => value,
            Dist::Normal { mean, .. } => mean,
            Dist::Uniform { lo, hi } => 0.5 * (lo + hi),
        }
    }

    /// Whether the distribution has any spread.
    pub fn is_random(&self) -> bool {
        match *self {
            Dist::Fixed { .. } => false,
            Dist::Normal { sd, .. } => sd > 0.0,
            Dist::Uniform { lo, hi } => hi > lo,
        }
    }

    /// "0.59", "N(0.59, 0.03)", "U[1.25, 1.29]" (4 significant digits).
    pub fn describe(&self) -> String {
        match *self {
            Dist::Fixed { value } => short(value),
            Dist::Normal { mean, sd } => format!("N({}, {})", short(mean), short(sd)),
            Dist::Uniform { lo, hi } => format!("U[{}, {}]", short(lo), short(hi)),
        }
    }
}

/// A number with 4 significant digits, without trailing zeros (2.65e6 as 2650000).
pub fn short(x: f64) -> String {
    if x == 0.0 || !x.is_finite() {
        return format!("{x}");
    }
    let digits = (3 - x.abs().log10().floor() as i32).max(0) as usize;
    let s = format!("{x:.digits$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

/// How the polarity of the record enters the ensemble.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum PolarityMode {
    /// One ensemble per polarity of the study (rows +1 and −1).
    Each,
    /// One ensemble whose samples draw +1 or −1 with probability ½.
    Random,
}

/// The uncertain inputs the coefficient sets share. `None`: the nominal value.
#[derive(Debug, Clone, Default, serde::Serialize)]
pub struct Uncertainty {
    pub magnification: Option<Dist>,
    pub r_m: Option<Dist>,
    pub alpha_rad: Option<Dist>,
    pub i0_kg_m2: Option<Dist>,
    /// K'_c of the spring bed (MN/m²).
    pub unit_stiffness_mn_m2: Option<Dist>,
    /// Contact height of the transverse walls (m).
    pub contact_height_m: Option<Dist>,
}

impl Uncertainty {
    /// Names and descriptions of the inputs that vary.
    pub fn describe(&self) -> Vec<(String, String)> {
        let mut v = Vec::new();
        for (k, d) in [
            ("magnification", self.magnification),
            ("r_m", self.r_m),
            ("alpha_rad", self.alpha_rad),
            ("i0_kg_m2", self.i0_kg_m2),
            ("unit_stiffness_mn_m2", self.unit_stiffness_mn_m2),
            ("contact_height_m", self.contact_height_m),
        ] {
            if let Some(d) = d {
                v.push((k.to_string(), d.describe()));
            }
        }
        v
    }
}

/// The coefficients of a set as distributions: one e both ways (two-sided
/// rocking, Housner), e_in and e_out, or a restitution law.
// The law variant is larger than the others (two sides' 3×3 covariances where a
// side has an energy term); a study holds a handful of sets, and boxing the law
// would lose `Copy`, on which the draws rely.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CoefficientDist {
    Single(Dist),
    Pair {
        e_in: Dist,
        e_out: Dist,
    },
    /// e = min(1, r(side, a)·e_H) at each impact, a the apex |θ|/α of the
    /// half-cycle it ends ([`crate::solver::impact`]); e_H as given, else Eq. 2
    /// with the sample's α. When `drawn`, each sample draws the law's parameters
    /// from their covariance ([`RestitutionLaw::sample`]).
    Law {
        law: RestitutionLaw,
        e_housner: Option<f64>,
        drawn: bool,
        /// Where the solver reads the law (the apex, or the impact's speed).
        reading: LawReading,
    },
}

impl CoefficientDist {
    /// Whether a sample draws e (a spread on either coefficient, or on the law).
    pub fn is_random(&self) -> bool {
        match self {
            CoefficientDist::Single(d) => d.is_random(),
            CoefficientDist::Pair { e_in, e_out } => e_in.is_random() || e_out.is_random(),
            CoefficientDist::Law { law, drawn, .. } => {
                let p = &law.parameters;
                let energy = [p.inward.energy, p.outward.energy].into_iter().flatten().flat_map(|e| e.cov).flatten();
                *drawn
                    && p.inward
                        .cov
                        .iter()
                        .chain(&p.outward.cov)
                        .flatten()
                        .copied()
                        .chain(energy)
                        .any(|v| v != 0.0)
            }
        }
    }
}

/// Nominal values the shared draws replace.
#[derive(Debug, Clone, Copy)]
pub struct Nominal {
    pub magnification: f64,
    pub r_m: f64,
    pub alpha: f64,
    pub i0: f64,
    /// (K'_c in MN/m², contact height in m) of the spring bed, if the block has one.
    pub spring_bed: Option<(f64, f64)>,
}

/// The inputs of one sample.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Inputs {
    pub magnification: f64,
    pub polarity: f64,
    pub r_m: f64,
    pub alpha: f64,
    pub i0: f64,
    /// (K'_c MN/m², contact height m) when the block has a spring bed.
    pub spring_bed: Option<(f64, f64)>,
    /// The set's e_in and e_out; for a law set, the drawn law's e at a = 1 (the
    /// amplitude of overturning), e_in of an impact entering inward.
    pub e_in: f64,
    pub e_out: f64,
    /// A law set's drawn law and the e_H it is applied with.
    #[serde(skip)]
    pub law: Option<(RestitutionLaw, f64)>,
}

/// FNV-1a of a name: a stable key for records and sets.
pub fn name_key(name: &str) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in name.bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Where in the study a sample sits (the key of its random streams).
#[derive(Debug, Clone, Copy)]
pub struct SampleKey {
    pub seed: u64,
    pub record: u64,
    /// 1, 2 for the polarity rows +1, −1; 0 for a random polarity.
    pub row: u64,
    /// Index of the scale factor (0 outside an IDA).
    pub scale: u64,
    pub sample: u64,
}

impl SampleKey {
    fn stream(&self, extra: &[u64]) -> SplitMix64 {
        let mut w = vec![self.seed, self.record, self.row, self.scale, self.sample];
        w.extend_from_slice(extra);
        SplitMix64::for_key(&w)
    }
}

const TAG_SHARED: u64 = 0x5348_4152_4544; // "SHARED"
const TAG_SET: u64 = 0x0053_4554; // "SET"

/// Draw the inputs of one sample. `polarity`: the row's polarity, or `None` for
/// a random one. Each input has its own stream, so adding an uncertain input does
/// not change the draws of the others.
pub fn draw(key: &SampleKey, unc: &Uncertainty, nominal: &Nominal, set_name: &str, set: &CoefficientDist, polarity: Option<f64>) -> Inputs {
    let shared = |i: u64, d: Option<Dist>, nom: f64, lo: f64, hi: f64| match d {
        Some(d) => d.sample(&mut key.stream(&[TAG_SHARED, i]), lo, hi),
        None => nom,
    };
    let inf = f64::INFINITY;
    let magnification = shared(0, unc.magnification, nominal.magnification, 0.0, inf);
    let r_m = shared(1, unc.r_m, nominal.r_m, 0.0, inf);
    let alpha = shared(2, unc.alpha_rad, nominal.alpha, 0.0, std::f64::consts::FRAC_PI_2);
    let i0 = shared(3, unc.i0_kg_m2, nominal.i0, 0.0, inf);
    let spring_bed = nominal.spring_bed.map(|(k, h)| {
        (
            shared(4, unc.unit_stiffness_mn_m2, k, 0.0, inf),
            shared(5, unc.contact_height_m, h, 0.0, inf),
        )
    });
    let polarity = polarity.unwrap_or_else(|| if key.stream(&[TAG_SHARED, 6]).uniform() < 0.5 { 1.0 } else { -1.0 });
    let s = name_key(set_name);
    let e = |i: u64, d: Dist| d.sample(&mut key.stream(&[TAG_SET, s, i]), 0.0, 1.0);
    let (e_in, e_out, law) = match *set {
        CoefficientDist::Single(d) => {
            let v = e(0, d);
            (v, v, None)
        }
        CoefficientDist::Pair { e_in, e_out } => (e(1, e_in), e(2, e_out), None),
        CoefficientDist::Law { law, e_housner, drawn, .. } => {
            let e_h = e_housner.unwrap_or_else(|| housner_e(alpha));
            let law = if drawn {
                let mut rng = key.stream(&[TAG_SET, s, 3]);
                law.sample_with(|| rng.normal())
            } else {
                law
            };
            (law.e(Side::Inward, 1.0, e_h), law.e(Side::Outward, 1.0, e_h), Some((law, e_h)))
        }
    };
    Inputs {
        magnification,
        polarity,
        r_m,
        alpha,
        i0,
        spring_bed,
        e_in,
        e_out,
        law,
    }
}

/// The outcome of one sample.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Outcome {
    pub overturned: bool,
    pub overturn_time_s: Option<f64>,
    /// max θ/α (the overturning limit over α for an overturned run).
    pub max_theta_over_alpha: f64,
}

/// What an ensemble says.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct EnsembleStats {
    pub samples: usize,
    pub overturned: usize,
    /// P(overturn) = overturned / samples.
    pub p_overturn: f64,
    /// 95 % Wilson interval of P(overturn).
    pub p_overturn_ci95: [f64; 2],
    /// "overturns" (P > 95 %), "survives" (P < 5 %) or "uncertain".
    pub verdict: &'static str,
    /// Median and 5–95 % range of max θ/α over all samples (an overturned sample
    /// counts with the limit over α).
    pub max_theta_over_alpha_median: f64,
    pub max_theta_over_alpha_p05: f64,
    pub max_theta_over_alpha_p95: f64,
    /// Median overturning time of the samples that overturn.
    pub overturn_time_median_s: Option<f64>,
}

/// A verdict is robust only when P(overturn) is below 5 % or above 95 %.
pub fn verdict(p: f64) -> &'static str {
    if p > 0.95 {
        "overturns"
    } else if p < 0.05 {
        "survives"
    } else {
        "uncertain"
    }
}

/// Summarise the outcomes of an ensemble.
pub fn summarise(outcomes: &[Outcome]) -> EnsembleStats {
    let n = outcomes.len();
    let k = outcomes.iter().filter(|o| o.overturned).count();
    let p = if n == 0 { f64::NAN } else { k as f64 / n as f64 };
    let (lo, hi) = wilson(k, n, Z95);
    let peaks = sorted(&outcomes.iter().map(|o| o.max_theta_over_alpha).collect::<Vec<_>>());
    let times = sorted(&outcomes.iter().filter_map(|o| o.overturn_time_s).collect::<Vec<_>>());
    EnsembleStats {
        samples: n,
        overturned: k,
        p_overturn: p,
        p_overturn_ci95: [lo, hi],
        verdict: verdict(p),
        max_theta_over_alpha_median: quantile_sorted(&peaks, 0.5),
        max_theta_over_alpha_p05: quantile_sorted(&peaks, 0.05),
        max_theta_over_alpha_p95: quantile_sorted(&peaks, 0.95),
        overturn_time_median_s: (!times.is_empty()).then(|| quantile_sorted(&times, 0.5)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn nominal() -> Nominal {
        Nominal {
            magnification: 1.27,
            r_m: 3.84,
            alpha: 0.1,
            i0: 2.6e6,
            spring_bed: Some((750.0, 7.64)),
        }
    }

    fn key(sample: u64) -> SampleKey {
        SampleKey {
            seed: 7,
            record: name_key("r"),
            row: 1,
            scale: 0,
            sample,
        }
    }

    #[test]
    fn draws_are_pure_functions_of_the_key() {
        let unc = Uncertainty {
            magnification: Some(Dist::Uniform { lo: 1.25, hi: 1.29 }),
            alpha_rad: Some(Dist::Normal { mean: 0.1, sd: 0.002 }),
            ..Default::default()
        };
        let set = CoefficientDist::Pair {
            e_in: Dist::Normal { mean: 0.59, sd: 0.03 },
            e_out: Dist::Normal { mean: 0.68, sd: 0.03 },
        };
        let a = draw(&key(3), &unc, &nominal(), "cal", &set, None);
        let b = draw(&key(3), &unc, &nominal(), "cal", &set, None);
        assert_eq!(a, b);
        let c = draw(&key(4), &unc, &nominal(), "cal", &set, None);
        assert_ne!(a.magnification, c.magnification);
        // Common random numbers: another set shares the magnification and geometry.
        let h = draw(
            &key(3),
            &unc,
            &nominal(),
            "housner",
            &CoefficientDist::Single(Dist::Fixed { value: 0.98 }),
            None,
        );
        assert_eq!((h.magnification, h.alpha, h.polarity), (a.magnification, a.alpha, a.polarity));
        assert_eq!((h.e_in, h.e_out), (0.98, 0.98));
        assert!((1.25..=1.29).contains(&a.magnification));
        assert_eq!(a.r_m, 3.84);
        // Adding an uncertain input leaves the others' draws alone.
        let more = Uncertainty {
            r_m: Some(Dist::Uniform { lo: 3.8, hi: 3.9 }),
            ..unc.clone()
        };
        let d = draw(&key(3), &more, &nominal(), "cal", &set, None);
        assert_eq!((d.magnification, d.alpha, d.e_in), (a.magnification, a.alpha, a.e_in));
    }

    /// e drawn from a normal is truncated to (0, 1].
    #[test]
    fn coefficients_stay_in_range() {
        let set = CoefficientDist::Single(Dist::Normal { mean: 0.98, sd: 0.05 });
        let mut above = 0;
        for i in 0..2000 {
            let x = draw(&key(i), &Uncertainty::default(), &nominal(), "h", &set, Some(1.0));
            assert!(x.e_in > 0.0 && x.e_in <= 1.0 && x.e_in == x.e_out);
            above += (x.e_in > 0.98) as usize;
        }
        // Truncation at 1 (0.4 sd above the mean) leaves P(e > 0.98) =
        // (Φ(0.4) − ½)/Φ(0.4) = 0.2365; 4 binomial sd = 0.038.
        let f = above as f64 / 2000.0;
        assert!((f - 0.2365).abs() < 0.038, "{f}");
    }

    #[test]
    fn random_polarity_is_balanced() {
        let set = CoefficientDist::Single(Dist::Fixed { value: 0.9 });
        let plus = (0..4000)
            .filter(|&i| draw(&key(i), &Uncertainty::default(), &nominal(), "h", &set, None).polarity > 0.0)
            .count();
        // 4 binomial sd at n = 4000: 0.0316.
        assert!((plus as f64 / 4000.0 - 0.5).abs() < 0.0316, "{plus}");
    }

    #[test]
    fn summary_counts_and_verdicts() {
        let o = |ov: bool, peak: f64| Outcome {
            overturned: ov,
            overturn_time_s: ov.then_some(10.0 + peak),
            max_theta_over_alpha: if ov { 1.0 } else { peak },
        };
        let mut v: Vec<Outcome> = (0..19).map(|i| o(false, 0.01 * i as f64)).collect();
        v.push(o(true, 0.5));
        let s = summarise(&v);
        assert_eq!((s.samples, s.overturned), (20, 1));
        assert_eq!(s.p_overturn, 0.05);
        assert_eq!(s.verdict, "uncertain");
        assert_eq!(s.overturn_time_median_s, Some(10.5));
        assert!((s.max_theta_over_alpha_median - 0.095).abs() < 1e-12);
        assert_eq!(verdict(0.049), "survives");
        assert_eq!(verdict(0.951), "overturns");
        assert_eq!(verdict(0.95), "uncertain");
    }
}
