//! The wall as the core knows it: the rocking kind, the side of a rotation (which
//! is also the pivot), the rectangular block and its slenderness α, Housner's
//! coefficient e_H (paper Eq. 2) and the rocking parameters of the part above the
//! hinge, each with where it came from. These domain types are shared by the
//! estimator, the solver, the calibration and the input edge (which only builds them).

use crate::G;

/// One-sided (transverse walls restrain the inward side) or two-sided rocking.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Rocking {
    OneSided,
    TwoSided,
}

impl Rocking {
    pub fn as_str(self) -> &'static str {
        match self {
            Rocking::OneSided => "one-sided",
            Rocking::TwoSided => "two-sided",
        }
    }
}

impl std::fmt::Display for Rocking {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Side of the wall (SPEC: θ > 0 is outward, θ < 0 inward): where a segment of a
/// log lies, which side an impact enters, and the pivot the wall rocks on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Side {
    Outward,
    Inward,
}

impl Side {
    /// s = +1 outward, −1 inward (the s of paper Eq. 1 in [`crate::solver::model`]).
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Side::Outward => 1.0,
            Side::Inward => -1.0,
        }
    }

    /// The side of a non-zero signed quantity (θ, θ' or ü_g): outward when > 0.
    #[inline]
    pub fn of(x: f64) -> Side {
        if x > 0.0 {
            Side::Outward
        } else {
            Side::Inward
        }
    }

    /// The other side.
    #[inline]
    pub fn opposite(self) -> Side {
        match self {
            Side::Outward => Side::Inward,
            Side::Inward => Side::Outward,
        }
    }

    /// ±1 as serialised in the solver's events (`entering`, `side`: SPEC).
    pub fn serialize_as_sign<S: serde::Serializer>(side: &Side, ser: S) -> Result<S::Ok, S::Error> {
        ser.serialize_i8(side.sign() as i8)
    }
}

/// A rectangular block: height h and thickness b (the rocking part of a tested
/// wall above its hinge, or the façade). The one place its geometry is written.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Rectangle {
    pub height_m: f64,
    pub thickness_m: f64,
}

impl Rectangle {
    pub fn new(height_m: f64, thickness_m: f64) -> Rectangle {
        Rectangle { height_m, thickness_m }
    }

    /// Slenderness α = atan(b / h).
    pub fn slenderness(&self) -> f64 {
        (self.thickness_m / self.height_m).atan()
    }

    /// Half-diagonal R = ½ √(h² + b²): distance from a pivot to the centre of mass.
    pub fn half_diagonal(&self) -> f64 {
        0.5 * self.height_m.hypot(self.thickness_m)
    }

    /// Frequency parameter p² = m g R / I_0 = 3 g / (4 R) (I_0 = 4/3 m R²).
    pub fn p_squared(&self) -> f64 {
        3.0 * G / (4.0 * self.half_diagonal())
    }
}

/// The tested wall of a campaign: its geometry, the hinge, and α and e_H with
/// where each came from (computed, or the manifest's override).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Wall {
    pub height_m: f64,
    pub thickness_m: f64,
    pub hinge_height_m: f64,
    /// α for e_H (SPEC: atan(thickness / height) of the wall as given).
    pub alpha_rad: f64,
    pub alpha_source: Provenance,
    /// e_H, paper Eq. 2, or the manifest's override.
    pub e_housner: f64,
    pub e_housner_source: Provenance,
}

impl Wall {
    /// The rocking part above the hinge.
    pub fn rocking_part(&self) -> Rectangle {
        Rectangle::new(self.height_m - self.hinge_height_m, self.thickness_m)
    }
}

/// Where a value came from, printed next to it in every report.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Provenance {
    /// Computed from the geometry (the formula is in the text).
    Computed(String),
    /// Given in the manifest (the key is in the text).
    Override(String),
}

impl std::fmt::Display for Provenance {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Provenance::Computed(s) => write!(f, "computed: {s}"),
            Provenance::Override(s) => write!(f, "manifest override: {s}"),
        }
    }
}

/// Slenderness α = atan(thickness / height) (SPEC: the wall as given, 0.133 rad for
/// 0.36 / 2.70).
pub fn slenderness(thickness_m: f64, height_m: f64) -> f64 {
    Rectangle::new(height_m, thickness_m).slenderness()
}

/// Housner's coefficient of restitution, paper Eq. 2: e_H = 1 − 1.5 sin²α.
pub fn housner_e(alpha: f64) -> f64 {
    1.0 - 1.5 * alpha.sin().powi(2)
}

/// Frequency parameter of a rectangular block, p² = m g R / I_0 = 3 g / (4 R), with
/// R = ½ √(h² + b²) the half-diagonal of the rocking part (height h, thickness b).
pub fn p_squared_rectangular(height_m: f64, thickness_m: f64) -> f64 {
    Rectangle::new(height_m, thickness_m).p_squared()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn housner_of_the_tested_wall_is_0_974() {
        // Paper §3.3: α = 0.133 gives e_H = 0.974 (three decimals printed).
        let a = slenderness(0.36, 2.70);
        assert!((a - 0.1326).abs() < 5e-5, "alpha {a}");
        let e = housner_e(a);
        assert!((e - 0.974).abs() < 5e-4, "e_H {e}");
    }

    #[test]
    fn housner_of_the_facade() {
        // SPEC: Eq. 2 with α = 0.10 gives 0.985 (the paper prints 0.980).
        assert!((housner_e(0.10) - 0.985).abs() < 5e-4);
    }

    #[test]
    fn p_squared_matches_truth_of_the_demo_wall() {
        // truth.json of the demo campaigns: h = 2.47 m, b = 0.36 m, R = 1.24805 m →
        // p² = 5.8952 s⁻² with g = 9.81; we use standard gravity 9.80665, so the
        // expected value is scaled by 9.80665 / 9.81 (exact to 1e-6 relative).
        let expected = 5.8952037022716 * G / 9.81;
        assert!((p_squared_rectangular(2.47, 0.36) / expected - 1.0).abs() < 1e-6);
    }
}
