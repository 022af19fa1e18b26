//! The coefficient applied at an impact: a constant pair (e_in, e_out), or a
//! restitution law r(side, a) times the block's e_H (SPEC, "Per-impact
//! coefficients and the restitution law").
//!
//! At the impact that ends a half-cycle, with a = max |θ| / α over that half-cycle
//! (its apex; the release angle for the first half-cycle of a free-vibration run):
//!
//!   θ'⁺ = e θ'⁻,   e = r(side entered, a) · e_H
//!
//! The law is written in r = e / e_H (paper Eqs. 5–6) and in the dimensionless
//! amplitude a so that it carries from the tested wall to another wall, as the
//! paper carries r to the façade. The solver only asks the law for a number; the
//! law's form, its fit and its uncertainty live with the law
//! ([`RestitutionCurve`] here, the campaign's fitted law where it is given).

use std::sync::Arc;

use crate::wall::Side;

/// A restitution law as the solver sees it.
pub trait Restitution: Send + Sync + std::fmt::Debug {
    /// r = e / e_H at an impact entering `entering`, ending a half-cycle of apex
    /// a = |θ|/α.
    fn r(&self, entering: Side, amplitude_over_alpha: f64) -> f64;
}

/// A law applied to a block: e = r(side, a) · e_H.
#[derive(Debug, Clone)]
pub struct ImpactLaw {
    pub law: Arc<dyn Restitution>,
    /// The block's e_H (Eq. 2, or the value a study gives).
    pub e_housner: f64,
}

impl ImpactLaw {
    pub fn new(law: Arc<dyn Restitution>, e_housner: f64) -> ImpactLaw {
        ImpactLaw { law, e_housner }
    }

    /// e = r(side, a) · e_H.
    #[inline]
    pub fn e(&self, entering: Side, amplitude_over_alpha: f64) -> f64 {
        self.law.r(entering, amplitude_over_alpha) * self.e_housner
    }
}

/// A constant law: r_in, r_out at every amplitude (a constant is the nested case
/// of every law; the solver then matches the constant pair r·e_H bit for bit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantLaw {
    pub r_in: f64,
    pub r_out: f64,
}

impl Restitution for ConstantLaw {
    fn r(&self, entering: Side, _a: f64) -> f64 {
        match entering {
            Side::Inward => self.r_in,
            Side::Outward => self.r_out,
        }
    }
}

/// A law given as a table r_in(a), r_out(a) on increasing amplitudes (a
/// campaign's `restitution_law.curve` in `summary.json`), linear between the
/// points and constant beyond the ends (the law is not extrapolated past the
/// amplitudes the campaign observed; the study's docs say so).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct RestitutionCurve {
    pub amplitude_over_alpha: Vec<f64>,
    pub r_in: Vec<f64>,
    pub r_out: Vec<f64>,
    /// Standard uncertainties of r_in and r_out at each point.
    pub r_in_u: Vec<f64>,
    pub r_out_u: Vec<f64>,
}

/// Why a table is not a law.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CurveError {
    #[error("a law table needs at least 2 points, got {0}")]
    TooShort(usize),
    #[error("the columns have different lengths (amplitudes {a}, r_in {r_in}, r_out {r_out}, r_in_u {r_in_u}, r_out_u {r_out_u})")]
    Lengths {
        a: usize,
        r_in: usize,
        r_out: usize,
        r_in_u: usize,
        r_out_u: usize,
    },
    #[error("point {index}: amplitude_over_alpha = {value}: expected finite, ≥ 0 and increasing")]
    Amplitude { index: usize, value: f64 },
    #[error("point {index}: {key} = {value}: expected 0 < r and r·e_H ≤ 1 (r ≤ {max})")]
    Coefficient { index: usize, key: &'static str, value: f64, max: f64 },
    #[error("point {index}: {key} = {value}: expected a standard uncertainty ≥ 0")]
    Uncertainty { index: usize, key: &'static str, value: f64 },
}

impl RestitutionCurve {
    /// Check the table: at least two points, amplitudes increasing, 0 < r ≤ 1/e_H
    /// (so that e ≤ 1), uncertainties ≥ 0.
    pub fn validate(&self, e_housner: f64) -> Result<(), CurveError> {
        let n = self.amplitude_over_alpha.len();
        let lens = [self.r_in.len(), self.r_out.len(), self.r_in_u.len(), self.r_out_u.len()];
        if lens.iter().any(|&l| l != n) {
            return Err(CurveError::Lengths {
                a: n,
                r_in: lens[0],
                r_out: lens[1],
                r_in_u: lens[2],
                r_out_u: lens[3],
            });
        }
        if n < 2 {
            return Err(CurveError::TooShort(n));
        }
        for (i, &a) in self.amplitude_over_alpha.iter().enumerate() {
            if !(a.is_finite() && a >= 0.0) || (i > 0 && a <= self.amplitude_over_alpha[i - 1]) {
                return Err(CurveError::Amplitude { index: i, value: a });
            }
        }
        let max = 1.0 / e_housner;
        for (key, col) in [("r_in", &self.r_in), ("r_out", &self.r_out)] {
            if let Some((index, &value)) = col.iter().enumerate().find(|(_, r)| !(**r > 0.0 && **r <= max)) {
                return Err(CurveError::Coefficient { index, key, value, max });
            }
        }
        for (key, col) in [("r_in_u", &self.r_in_u), ("r_out_u", &self.r_out_u)] {
            if let Some((index, &value)) = col.iter().enumerate().find(|(_, u)| !(u.is_finite() && **u >= 0.0)) {
                return Err(CurveError::Uncertainty { index, key, value });
            }
        }
        Ok(())
    }

    /// Linear interpolation of `col` at a, constant beyond the ends.
    fn at(&self, col: &[f64], a: f64) -> f64 {
        let x = &self.amplitude_over_alpha;
        let n = x.len();
        if a <= x[0] {
            return col[0];
        }
        if a >= x[n - 1] {
            return col[n - 1];
        }
        let j = x.partition_point(|&v| v <= a).clamp(1, n - 1);
        let f = (a - x[j - 1]) / (x[j] - x[j - 1]);
        col[j - 1] + f * (col[j] - col[j - 1])
    }

    /// A draw of the law: r(a) + z_in u_in(a) inward and r(a) + z_out u_out(a)
    /// outward, each side shifted by one standard normal over all amplitudes
    /// (the band's values fully correlated along a: the table carries no
    /// covariance, and full correlation is the wider of the two limits for a
    /// quantity that integrates over many impacts), clamped to (0, r_max].
    pub fn draw(&self, z_in: f64, z_out: f64, r_max: f64) -> RestitutionCurve {
        let shift = |r: &[f64], u: &[f64], z: f64| -> Vec<f64> { r.iter().zip(u).map(|(r, u)| (r + z * u).clamp(1e-6, r_max)).collect() };
        RestitutionCurve {
            amplitude_over_alpha: self.amplitude_over_alpha.clone(),
            r_in: shift(&self.r_in, &self.r_in_u, z_in),
            r_out: shift(&self.r_out, &self.r_out_u, z_out),
            r_in_u: vec![0.0; self.r_in.len()],
            r_out_u: vec![0.0; self.r_out.len()],
        }
    }

    /// Whether any point has an uncertainty (an ensemble then draws the law).
    pub fn is_random(&self) -> bool {
        self.r_in_u.iter().chain(&self.r_out_u).any(|u| *u > 0.0)
    }

    /// The amplitude range the table spans.
    pub fn span(&self) -> (f64, f64) {
        (self.amplitude_over_alpha[0], *self.amplitude_over_alpha.last().unwrap_or(&0.0))
    }
}

impl Restitution for RestitutionCurve {
    fn r(&self, entering: Side, a: f64) -> f64 {
        match entering {
            Side::Inward => self.at(&self.r_in, a),
            Side::Outward => self.at(&self.r_out, a),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn curve() -> RestitutionCurve {
        RestitutionCurve {
            amplitude_over_alpha: vec![0.1, 0.5, 0.9],
            r_in: vec![0.6, 0.7, 0.9],
            r_out: vec![0.65, 0.8, 0.95],
            r_in_u: vec![0.01, 0.02, 0.03],
            r_out_u: vec![0.0, 0.0, 0.0],
        }
    }

    #[test]
    fn curve_interpolates_and_holds_its_ends() {
        let c = curve();
        assert_eq!(c.r(Side::Inward, 0.0), 0.6);
        assert_eq!(c.r(Side::Inward, 0.1), 0.6);
        assert!((c.r(Side::Inward, 0.3) - 0.65).abs() < 1e-15);
        assert!((c.r(Side::Outward, 0.7) - 0.875).abs() < 1e-15);
        assert_eq!(c.r(Side::Outward, 0.9), 0.95);
        assert_eq!(c.r(Side::Outward, 2.0), 0.95);
        assert!(c.validate(0.985).is_ok());
        assert!(c.is_random());
    }

    #[test]
    fn draws_shift_by_the_band() {
        let d = curve().draw(1.0, -2.0, 1.0 / 0.985);
        assert!((d.r(Side::Inward, 0.5) - 0.72).abs() < 1e-15);
        assert_eq!(d.r(Side::Outward, 0.5), 0.8);
        assert!(!d.is_random());
    }

    #[test]
    fn bad_tables_are_named() {
        let mut c = curve();
        c.amplitude_over_alpha[2] = 0.5;
        assert_eq!(c.validate(0.985), Err(CurveError::Amplitude { index: 2, value: 0.5 }));
        let mut c = curve();
        c.r_out[1] = 1.2;
        assert!(matches!(c.validate(0.985), Err(CurveError::Coefficient { index: 1, key: "r_out", .. })));
        let mut c = curve();
        c.r_in_u.pop();
        assert!(matches!(c.validate(0.985), Err(CurveError::Lengths { .. })));
    }
}
