//! Paper Eq. 1 divided by I_0, with s = +1 on the outward pivot (θ > 0) and s = −1
//! on the inward pivot (θ < 0), p² = m g R / I_0:
//!
//!   θ'' = −p² s sin(α − sθ) − T_L(θ)/I_0 − T_t(θ)/I_0 + (p²/g) ü_g(t) cos(α − sθ)
//!
//! - T_L: transverse walls, a compression-only spring bed acting for θ < 0 only:
//!   with unit stiffness K'_c (N/m per m of height) over the contact height h,
//!   T_L = K'_c h³ θ / 3 (the bed's springs at height y stretch by y θ and act
//!   with lever arm y: ∫₀ʰ K'_c y² θ dy). A rotational stiffness may be given
//!   directly instead.
//! - T_t: horizontal tie-rods of axial stiffness K at height h_t, tension only
//!   (θ > 0): elongation δ = h_t sin θ, force F = K (δ − δ_p) ≥ 0, capped at the
//!   yield force F_y (elastic–perfectly-plastic; δ_p is the plastic elongation),
//!   moment T_t = F h_t cos θ.
//! - Ground acceleration ü_g: record × magnification × polarity, linear between
//!   samples.

use super::impact::ImpactLaw;
use crate::wall::Side;
use crate::G;

/// The inward restraint by the transverse walls.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Restraint {
    /// Two-sided rocking: no restraint.
    None,
    /// Rotational stiffness k_θ (N m/rad) acting for θ < 0: T_L = k_θ θ.
    Rotational { k_nm_per_rad: f64 },
}

impl Restraint {
    /// Spring bed of unit stiffness K'_c (N/m²) over the contact height h (m):
    /// k_θ = K'_c h³ / 3.
    pub fn spring_bed(unit_stiffness_n_m2: f64, contact_height_m: f64) -> Restraint {
        Restraint::Rotational {
            k_nm_per_rad: unit_stiffness_n_m2 * contact_height_m.powi(3) / 3.0,
        }
    }
}

/// A horizontal tie-rod: axial stiffness (N/m) at height h_t (m) above the pivot,
/// optional yield force (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TieRod {
    pub stiffness_n_m: f64,
    pub height_m: f64,
    pub yield_force_n: Option<f64>,
}

/// Ground acceleration record: uniform samples (m/s², already scaled).
#[derive(Debug, Clone)]
pub struct Ground {
    pub t0: f64,
    pub dt: f64,
    pub acc: Vec<f64>,
}

impl Ground {
    /// Time of sample i.
    pub fn time(&self, i: usize) -> f64 {
        self.t0 + self.dt * i as f64
    }
    /// End of the record.
    pub fn end(&self) -> f64 {
        self.time(self.acc.len().saturating_sub(1))
    }
    /// Index of the sample interval holding t (clamped).
    pub fn interval(&self, t: f64) -> usize {
        let i = ((t - self.t0) / self.dt).floor();
        if i < 0.0 {
            0
        } else {
            (i as usize).min(self.acc.len().saturating_sub(2))
        }
    }
    /// The linear piece of ü_g that holds just after t: (t, ü_g(t), slope), zero
    /// outside the record.
    pub fn linear_piece(&self, t: f64) -> (f64, f64, f64) {
        if self.acc.len() < 2 || t < self.t0 || t >= self.end() {
            return (t, 0.0, 0.0);
        }
        let i = ((t - self.t0) / self.dt * (1.0 + 1e-12) + 1e-9).floor() as usize;
        let i = i.min(self.acc.len() - 2);
        let slope = (self.acc[i + 1] - self.acc[i]) / self.dt;
        (t, self.at(t), slope)
    }

    /// ü_g at t, linear between samples, zero outside the record.
    pub fn at(&self, t: f64) -> f64 {
        if self.acc.len() < 2 || t < self.t0 || t > self.end() {
            return 0.0;
        }
        let i = self.interval(t);
        let f = (t - self.time(i)) / self.dt;
        self.acc[i] + f * (self.acc[i + 1] - self.acc[i])
    }
}

/// The full model.
#[derive(Debug, Clone)]
pub struct RockingModel {
    pub alpha: f64,
    pub p2: f64,
    pub i0: f64,
    pub restraint: Restraint,
    pub ties: Vec<TieRod>,
    /// Coefficient applied when entering the inward side (θ' < 0 at θ = 0).
    pub e_in: f64,
    pub e_out: f64,
    /// A restitution law applied instead of (e_in, e_out): e = r(side, a)·e_H with
    /// a the apex |θ|/α of the half-cycle that ends ([`super::impact`]).
    pub law: Option<ImpactLaw>,
    /// Overturning limit on |θ| (rad): outward always; inward when unrestrained.
    pub overturn_limit: f64,
    /// Use sin x ≈ x, cos x ≈ 1 (the linearised equation; for verification).
    pub linearized: bool,
}

impl RockingModel {
    /// θ'' on pivot `side` (s = ±1), rotation θ, ground acceleration a (m/s²) and
    /// the tie-rods' plastic elongations.
    #[inline]
    pub fn accel(&self, side: Side, theta: f64, a: f64, plastic: &[f64]) -> f64 {
        let s = side.sign();
        let x = self.alpha - s * theta;
        let (sn, cs) = if self.linearized { (x, 1.0) } else { x.sin_cos() };
        let mut acc = -self.p2 * s * sn + self.p2 / G * a * cs;
        if theta < 0.0 {
            if let Restraint::Rotational { k_nm_per_rad } = self.restraint {
                acc -= k_nm_per_rad * theta / self.i0;
            }
        } else if theta > 0.0 && !self.ties.is_empty() {
            acc -= self.tie_moment(theta, plastic) / self.i0;
        }
        acc
    }

    /// Moment of the tie-rods at θ > 0 (N m).
    pub fn tie_moment(&self, theta: f64, plastic: &[f64]) -> f64 {
        let (st, ct) = theta.sin_cos();
        self.ties
            .iter()
            .zip(plastic)
            .map(|(tie, dp)| {
                let delta = tie.height_m * st;
                let mut f = (tie.stiffness_n_m * (delta - dp)).max(0.0);
                if let Some(fy) = tie.yield_force_n {
                    f = f.min(fy);
                }
                f * tie.height_m * ct
            })
            .sum()
    }

    /// The coefficient of an impact entering `entering` at angular speed
    /// `omega_before` that ends a half-cycle of apex |θ| = `apex` (rad), and the
    /// amplitude a law was read at: the law's min(1, r(side, a)·e_H) with a the
    /// apex/α or, read by speed, [`ImpactLaw::read_at`]'s; else e_in or e_out
    /// (and the apex/α).
    #[inline]
    pub fn coefficient(&self, entering: Side, apex: f64, omega_before: f64) -> (f64, f64) {
        let a = apex / self.alpha;
        match (&self.law, entering) {
            (Some(law), _) => {
                let read = law.read_at(entering, a, omega_before, self.p2.sqrt(), self.alpha);
                (law.e(entering, read), read)
            }
            (None, Side::Inward) => (self.e_in, a),
            (None, Side::Outward) => (self.e_out, a),
        }
    }

    /// Update the plastic elongations after an accepted step at rotation θ.
    pub fn update_plastic(&self, theta: f64, plastic: &mut [f64]) {
        for (tie, dp) in self.ties.iter().zip(plastic.iter_mut()) {
            if let Some(fy) = tie.yield_force_n {
                let delta = tie.height_m * theta.max(0.0).sin();
                if tie.stiffness_n_m * (delta - *dp) > fy {
                    *dp = delta - fy / tie.stiffness_n_m;
                }
            }
        }
    }

    /// Uplift threshold |ü_g| > g tan α (at θ = 0 the restraints exert no moment).
    pub fn uplift_threshold(&self) -> f64 {
        G * self.alpha.tan()
    }

    /// The overturning level of θ on pivot `side` (None: the inward side of a
    /// restrained wall, which cannot overturn inward).
    pub fn overturn_level(&self, side: Side) -> Option<f64> {
        if side == Side::Outward {
            Some(self.overturn_limit)
        } else if matches!(self.restraint, Restraint::None) {
            Some(-self.overturn_limit)
        } else {
            None
        }
    }

    /// Energy per unit I_0 in free rocking (no forcing, no restraint):
    /// ½ θ'² + p² cos(α − sθ).
    pub fn energy(&self, theta: f64, omega: f64) -> f64 {
        let s = if theta >= 0.0 { 1.0 } else { -1.0 };
        0.5 * omega * omega + self.p2 * (self.alpha - s * theta).cos()
    }
}
