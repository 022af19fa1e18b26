//! The physical ranges the inputs are validated against where they enter (issue
//! 22): each input edge checks its values with [`Range::check`], whose refusal
//! states the accepted range, and the edge names the file and key or line.
//!
//! The ranges are wide on purpose — they admit every realistic lab wall, façade
//! and record (and the fixtures' extremes with a margin of 10× or more) — and
//! narrow enough that the numeric core stays finite and its iterations bounded:
//! a block of 10⁻³⁰⁰ m, an I₀ of 10⁻³⁰⁸ kg m² or a record of 10³⁰ g made
//! NaN or a run without end before they were refused.

/// A number as a person writes it: `1e308`, `1e-12`, `0.001`, `2.7` (Rust's `{}`
/// would spell 1e308 with 309 digits, a value the user never wrote).
pub fn show(v: f64) -> String {
    if v != 0.0 && v.is_finite() && !(1e-4..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

/// A closed range of a physical input, with its unit for messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Range {
    pub lo: f64,
    pub hi: f64,
    pub unit: &'static str,
}

impl Range {
    pub const fn new(lo: f64, hi: f64, unit: &'static str) -> Range {
        Range { lo, hi, unit }
    }
    /// Finite and within [lo, hi].
    pub fn contains(&self, v: f64) -> bool {
        v.is_finite() && v >= self.lo && v <= self.hi
    }
    /// "from 0.01 to 1000 m".
    pub fn describe(&self) -> String {
        let unit = if self.unit.is_empty() {
            String::new()
        } else {
            format!(" {}", self.unit)
        };
        format!("from {} to {}{unit}", show(self.lo), show(self.hi))
    }
    /// `v`, or a message "`what` = v: expected a value from lo to hi unit".
    pub fn check(&self, what: &str, v: f64) -> Result<f64, String> {
        if self.contains(v) {
            Ok(v)
        } else {
            Err(format!("{what} = {}: expected a value {}", show(v), self.describe()))
        }
    }
}

/// Lengths of a wall or a block, heights of restraints and LVDTs: 1 mm to 1 km.
pub const LENGTH_M: Range = Range::new(1e-3, 1e3, "m");
/// Unit weight of masonry (and of anything a block is made of): 1 to 100 kN/m³.
pub const UNIT_WEIGHT_KN_M3: Range = Range::new(1.0, 100.0, "kN/m³");
/// Mass of a block: 1 g to 10⁹ kg.
pub const MASS_KG: Range = Range::new(1e-3, 1e9, "kg");
/// I₀ about the pivot over m R²: ≥ 1 by the parallel-axis theorem (I₀ = I_G + m R²),
/// 4/3 for a uniform rectangle; up to 10 for any mass distribution of a block.
pub const I0_OVER_M_R2: Range = Range::new(1.0, 10.0, "× m R²");
/// Stiffness of a spring bed (MN/m²), of a rotational spring (MN m/rad), of a tie
/// (kN/m), and a tie's yield force (kN).
pub const STIFFNESS: Range = Range::new(1e-9, 1e9, "");
/// Magnification of a ground motion (a study's, `--scale`, an IDA scale).
pub const MAGNIFICATION: Range = Range::new(1e-3, 100.0, "");
/// Relative tolerance of the integrator as a study or `--rtol` gives it (the
/// façade's 100× tighter and looser re-runs stay within 10⁻¹⁴ … 10⁻¹).
pub const RTOL: Range = Range::new(1e-12, 1e-3, "");
/// Absolute tolerance of the integrator (rad, rad/s).
pub const ATOL: Range = Range::new(1e-15, 1e-3, "");
/// The tolerances the solver itself accepts (after the façade's 100× changes).
pub const SOLVER_TOL: Range = Range::new(1e-15, 1e-1, "");
/// Seconds simulated after a record.
pub const T_EXTRA_S: Range = Range::new(0.0, 3600.0, "s");
/// |acceleration| of a record sample in g: the largest recorded are ~4 g.
pub const RECORD_ACCEL_G: Range = Range::new(0.0, 20.0, "g");
/// Time step of a ground-motion record: 10 µs to 1 s.
pub const RECORD_DT_S: Range = Range::new(1e-5, 1.0, "s");
/// Samples of a record.
pub const RECORD_SAMPLES: usize = 10_000_000;
/// Sampling rate of a displacement log: 1 Hz to 1 MHz.
pub const LOG_RATE_HZ: Range = Range::new(1.0, 1e6, "Hz");
/// Ensemble size per record × set × polarity, and IDA samples per point.
pub const MAX_SAMPLES: usize = 100_000;
/// Points of an IDA (`--scales FROM:TO:N`).
pub const MAX_SCALES: usize = 1000;
/// Impacts in a calibration's fitted window (`calibrate --impacts`): the fit of
/// e_in and e_out needs two; more than a test resolves leaves it out, saying so.
pub const CALIBRATION_IMPACTS: Range = Range::new(2.0, 1000.0, "impacts");
/// Overturning limit: 0 < θ ≤ π/2 rad.
pub const ANGLE_RAD: Range = Range::new(1e-6, std::f64::consts::FRAC_PI_2, "rad");

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_refusal_states_the_range() {
        assert_eq!(LENGTH_M.check("[block].height_m", 2.7), Ok(2.7));
        assert_eq!(
            LENGTH_M.check("[block].height_m", 1e-300).unwrap_err(),
            "[block].height_m = 1e-300: expected a value from 0.001 to 1000 m"
        );
        assert_eq!(
            RTOL.check("[study].rtol", 1e308).unwrap_err(),
            "[study].rtol = 1e308: expected a value from 1e-12 to 0.001"
        );
        assert!(!RTOL.contains(f64::NAN) && !RTOL.contains(1e308) && !RTOL.contains(1e-308));
    }
}
