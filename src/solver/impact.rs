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
//! paper carries r to the façade. The solver only asks the law for a number
//! ([`Restitution`]); the law's form, its fit and its uncertainty live with the
//! law ([`crate::restitution_law::RestitutionLaw`], the campaign's fitted law).
//! e is capped at 1, as [`RestitutionLaw::e`] does (a law read beyond the
//! amplitudes it was fitted on could otherwise add energy).
//!
//! A study may read a law by the impact's speed instead ([`LawReading::Speed`]):
//! at the amplitude whose campaign impact had the same ŵ = |θ'⁻|/(p α)
//! (crate::restitution_law, "Reading a law by the impact's speed").

use std::sync::Arc;

use crate::restitution_law::{LawReading, RestitutionLaw};
use crate::wall::Side;

/// A restitution law as the solver sees it.
pub trait Restitution: Send + Sync + std::fmt::Debug {
    /// r = e / e_H at an impact entering `entering`, ending a half-cycle of apex
    /// a = |θ|/α.
    fn r(&self, entering: Side, amplitude_over_alpha: f64) -> f64;

    /// The amplitude at which to read the law for an impact entering `entering`
    /// at the dimensionless speed ŵ = |θ'⁻|/(p α) on a block of slenderness
    /// `alpha` ([`LawReading::Speed`]); None where the law cannot say, and the
    /// apex is used.
    fn amplitude_at_speed(&self, _entering: Side, _speed_over_p_alpha: f64, _alpha: f64) -> Option<f64> {
        None
    }
}

/// A law applied to a block: e = r(side, a) · e_H, with a read as `reading` says.
#[derive(Debug, Clone)]
pub struct ImpactLaw {
    pub law: Arc<dyn Restitution>,
    /// The block's e_H (Eq. 2, or the value a study gives).
    pub e_housner: f64,
    /// Where the law is read: at the apex (the default) or at the impact's speed.
    pub reading: LawReading,
}

impl ImpactLaw {
    pub fn new(law: Arc<dyn Restitution>, e_housner: f64) -> ImpactLaw {
        ImpactLaw {
            law,
            e_housner,
            reading: LawReading::Amplitude,
        }
    }

    /// The same law read as `reading` says.
    pub fn read_by(self, reading: LawReading) -> ImpactLaw {
        ImpactLaw { reading, ..self }
    }

    /// e = min(1, r(side, a) · e_H).
    #[inline]
    pub fn e(&self, entering: Side, amplitude_over_alpha: f64) -> f64 {
        (self.law.r(entering, amplitude_over_alpha) * self.e_housner).min(1.0)
    }

    /// The amplitude the law is read at for an impact that ends a half-cycle of
    /// apex a = `apex_over_alpha` at angular speed `omega_before` on a block of
    /// slenderness `alpha` and p = `p`: the apex's, or (read by speed) the
    /// amplitude of the campaign's impacts of its ŵ = |ω⁻|/(p α).
    #[inline]
    pub fn read_at(&self, entering: Side, apex_over_alpha: f64, omega_before: f64, p: f64, alpha: f64) -> f64 {
        match self.reading {
            LawReading::Amplitude => apex_over_alpha,
            LawReading::Speed => {
                let w = omega_before.abs() / (p * alpha);
                self.law.amplitude_at_speed(entering, w, alpha).unwrap_or(apex_over_alpha)
            }
        }
    }
}

/// The campaign's law (`restitution_law` of summary.json) as the solver applies it.
impl Restitution for RestitutionLaw {
    fn r(&self, entering: Side, amplitude_over_alpha: f64) -> f64 {
        RestitutionLaw::r(self, entering, amplitude_over_alpha)
    }

    fn amplitude_at_speed(&self, entering: Side, speed_over_p_alpha: f64, alpha: f64) -> Option<f64> {
        RestitutionLaw::amplitude_at_speed(self, entering, speed_over_p_alpha, alpha)
    }
}
