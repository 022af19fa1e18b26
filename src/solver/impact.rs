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

use std::sync::Arc;

use crate::restitution_law::RestitutionLaw;
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

    /// e = min(1, r(side, a) · e_H).
    #[inline]
    pub fn e(&self, entering: Side, amplitude_over_alpha: f64) -> f64 {
        (self.law.r(entering, amplitude_over_alpha) * self.e_housner).min(1.0)
    }
}

/// The campaign's law (`restitution_law` of summary.json) as the solver applies it.
impl Restitution for RestitutionLaw {
    fn r(&self, entering: Side, amplitude_over_alpha: f64) -> f64 {
        RestitutionLaw::r(self, entering, amplitude_over_alpha)
    }
}
