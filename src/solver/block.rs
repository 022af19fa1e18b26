//! A rigid rocking block: geometry → R, α, m, I_0 and p² (with overrides).

use super::model::{Restraint, TieRod};
use crate::wall::Rectangle;
use crate::G;

/// The block's dynamic properties.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Block {
    /// Half-diagonal R (m): distance from a pivot to the centre of mass.
    pub r_m: f64,
    /// Slenderness α (rad).
    pub alpha: f64,
    /// Mass (kg).
    pub mass_kg: f64,
    /// Polar moment of inertia about a pivot, I_0 (kg m²).
    pub i0: f64,
}

impl Block {
    /// Rectangular block `geom` (height h, thickness b) of width w and unit weight
    /// γ (kN/m³): R = ½√(h² + b²), α = atan(b/h), m = γ h b w / g, I_0 = 4/3 m R².
    pub fn rectangular(geom: Rectangle, width_m: f64, unit_weight_kn_m3: f64) -> Block {
        let r = geom.half_diagonal();
        let mass = unit_weight_kn_m3 * 1e3 * geom.height_m * geom.thickness_m * width_m / G;
        Block {
            r_m: r,
            alpha: geom.slenderness(),
            mass_kg: mass,
            i0: Block::rectangular_i0(mass, r),
        }
    }

    /// I_0 = 4/3 m R² of a rectangular block of mass m and half-diagonal R.
    pub fn rectangular_i0(mass_kg: f64, r_m: f64) -> f64 {
        4.0 / 3.0 * mass_kg * r_m * r_m
    }

    /// p² = m g R / I_0 (s⁻²); 3g/(4R) for a rectangular block.
    pub fn p2(&self) -> f64 {
        self.mass_kg * G * self.r_m / self.i0
    }
}

/// A rocking wall for the solver: the block, the inward restraint, the tie-rods
/// and the impact defaults (read from a block file by `rocklab::ingest::block`).
#[derive(Debug, Clone)]
pub struct BlockSpec {
    pub name: String,
    pub block: Block,
    pub restraint: Restraint,
    pub ties: Vec<TieRod>,
    pub impact: ImpactDefaults,
    /// (K'_c in MN/m², contact height in m) when the restraint is given as a
    /// spring bed (the façade ensembles vary them).
    pub spring_bed: Option<(f64, f64)>,
    /// Which of R, α, I_0, mass were overridden.
    pub overrides: Vec<String>,
}

impl BlockSpec {
    /// Ω/p of the inward restraint: the angular frequency of a push against it,
    /// Ω = √(k_θ/I₀), over p (where the spring dominates gravity, a push of apex a
    /// ends at ω⁻ ≈ Ω a α); None without a restraint. A law's pushes were measured
    /// at the campaign's Ω/p ([`crate::restitution_law::PushSpeed`]).
    pub fn push_speed_ratio(&self) -> Option<f64> {
        match self.restraint {
            Restraint::Rotational { k_nm_per_rad } => Some((k_nm_per_rad / self.block.i0 / self.block.p2()).sqrt()),
            Restraint::None => None,
        }
    }
}

/// Optional impact defaults of a block file.
#[derive(Debug, Clone, Copy, Default, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImpactDefaults {
    pub e: Option<f64>,
    pub e_in: Option<f64>,
    pub e_out: Option<f64>,
    pub overturn_limit_rad: Option<f64>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rectangular_p2_is_3g_over_4r() {
        let b = Block::rectangular(Rectangle::new(7.64, 0.80), 12.0, 18.0);
        assert!((b.p2() - 3.0 * G / (4.0 * b.r_m)).abs() < 1e-12);
        assert!((b.r_m - 3.8409).abs() < 1e-4);
        assert!((b.alpha - 0.10437).abs() < 1e-4);
    }

    /// The façade's nominal block (fixtures/facade/block.toml: K'_c 750 MN/m² over
    /// 7.64 m, I₀ = 4/3 m R² with R = 3.84 m): k_θ = K'_c h³/3 and
    /// Ω/p = √(k_θ/(I₀ p²)), the 148.3 that tools/facade_push_transfer.py printed
    /// (fifty-sixth session) from the same file in Python.
    #[test]
    fn push_speed_ratio_of_a_spring_bed() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/block.toml");
        let spec = BlockSpec::load(&path).unwrap();
        let (k, h) = spec.spring_bed.unwrap();
        let want = (k * 1e6 * h.powi(3) / 3.0 / spec.block.i0 / spec.block.p2()).sqrt();
        let got = spec.push_speed_ratio().unwrap();
        assert!((got / want - 1.0).abs() < 1e-12, "{got} vs {want}");
        assert!((got - 148.3).abs() < 0.05, "{got}");
        let free = BlockSpec {
            restraint: Restraint::None,
            ..spec
        };
        assert_eq!(free.push_speed_ratio(), None);
    }
}
