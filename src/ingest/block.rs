//! BLOCK.toml: a rocking wall for the solver. Documented in the README.
//!
//! ```toml
//! [block]
//! name = "façade"
//! height_m = 7.64          # rectangular geometry…
//! thickness_m = 0.80
//! width_m = 12.00
//! unit_weight_kn_m3 = 18.0
//! r_m = 3.84               # …and optional overrides of R, α, I_0, mass
//! alpha_rad = 0.10
//! # i0_kg_m2 = 2.6e6
//! # mass_kg = 1.3e5
//! [restraint]              # optional: transverse walls, acting for θ < 0
//! unit_stiffness_mn_m2 = 750.0   # K'_c (MN/m per m of height)
//! contact_height_m = 7.64
//! # rotational_stiffness_mnm_rad = 1.1e5   # or k_θ directly
//! [[tie_rod]]              # optional, any number
//! stiffness_kn_m = 20000.0
//! height_m = 7.0
//! yield_force_kn = 150.0   # optional: elastic–perfectly-plastic
//! [impact]                 # optional defaults for simulate
//! e_in = 0.59
//! e_out = 0.68
//! overturn_limit_rad = 0.10
//! ```

use std::path::Path;

use serde::Deserialize;

use crate::error::{FileError, FileKind};
use crate::ingest::text::{parse_toml, read_text};
use crate::limits;
pub use crate::solver::block::{BlockSpec, ImpactDefaults};
use crate::solver::{Block, Restraint, TieRod};
use crate::wall::Rectangle;

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawFile {
    block: RawBlock,
    restraint: Option<RawRestraint>,
    #[serde(default)]
    tie_rod: Vec<RawTie>,
    impact: Option<RawImpact>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawBlock {
    name: Option<String>,
    height_m: f64,
    thickness_m: f64,
    width_m: f64,
    unit_weight_kn_m3: f64,
    r_m: Option<f64>,
    alpha_rad: Option<f64>,
    i0_kg_m2: Option<f64>,
    mass_kg: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRestraint {
    unit_stiffness_mn_m2: Option<f64>,
    contact_height_m: Option<f64>,
    rotational_stiffness_mnm_rad: Option<f64>,
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTie {
    stiffness_kn_m: f64,
    height_m: f64,
    yield_force_kn: Option<f64>,
}

type RawImpact = ImpactDefaults;

type Result<T> = std::result::Result<T, FileError>;

/// `v` within its physical range (issue 22: [`crate::limits`]).
fn within(path: &Path, key: &str, v: f64, range: limits::Range) -> Result<f64> {
    range.check(key, v).map_err(|m| FileError::invalid(path, m))
}

/// The rectangular block with the overrides of R, α, I_0 and mass, and which were
/// given.
fn block(b: &RawBlock, path: &Path) -> Result<(Block, Vec<String>)> {
    let geom = Rectangle::new(
        within(path, "[block].height_m", b.height_m, limits::LENGTH_M)?,
        within(path, "[block].thickness_m", b.thickness_m, limits::LENGTH_M)?,
    );
    let mut block = Block::rectangular(
        geom,
        within(path, "[block].width_m", b.width_m, limits::LENGTH_M)?,
        within(path, "[block].unit_weight_kn_m3", b.unit_weight_kn_m3, limits::UNIT_WEIGHT_KN_M3)?,
    );
    let mut overrides = Vec::new();
    if let Some(m) = b.mass_kg {
        block.mass_kg = within(path, "[block].mass_kg", m, limits::MASS_KG)?;
        overrides.push("mass_kg".into());
    }
    if let Some(r) = b.r_m {
        block.r_m = within(path, "[block].r_m", r, limits::LENGTH_M)?;
        overrides.push("r_m".into());
    }
    if let Some(a) = b.alpha_rad {
        if !(a > 0.0 && a < std::f64::consts::FRAC_PI_2) {
            return Err(FileError::invalid(path, format!("[block].alpha_rad = {a}: expected 0 < α < π/2")));
        }
        block.alpha = a;
        overrides.push("alpha_rad".into());
    }
    // I_0 = 4/3 m R² with the final m and R unless given.
    block.i0 = match b.i0_kg_m2 {
        Some(i) => {
            overrides.push("i0_kg_m2".into());
            let m_r2 = block.mass_kg * block.r_m * block.r_m;
            within(path, "[block].i0_kg_m2 / (m R²)", i / m_r2, limits::I0_OVER_M_R2).map_err(|_| {
                FileError::invalid(
                    path,
                    format!(
                        "[block].i0_kg_m2 = {}: expected a value from {m_r2:.4e} to {:.4e} kg m² (1 to 10 × m R²)",
                        limits::show(i),
                        10.0 * m_r2
                    ),
                )
            })?;
            i
        }
        None => Block::rectangular_i0(block.mass_kg, block.r_m),
    };
    Ok((block, overrides))
}

/// `[restraint]`: a spring bed (also returned as (K'_c, h) for the ensembles) or
/// a rotational stiffness; none without the table.
fn restraint(r: Option<&RawRestraint>, path: &Path) -> Result<(Restraint, Option<(f64, f64)>)> {
    let Some(r) = r else {
        return Ok((Restraint::None, None));
    };
    match (r.unit_stiffness_mn_m2, r.contact_height_m, r.rotational_stiffness_mnm_rad) {
        (Some(k), Some(h), None) => Ok((
            Restraint::spring_bed(
                within(path, "[restraint].unit_stiffness_mn_m2", k, limits::STIFFNESS)? * 1e6,
                within(path, "[restraint].contact_height_m", h, limits::LENGTH_M)?,
            ),
            Some((k, h)),
        )),
        (None, None, Some(k)) => Ok((
            Restraint::Rotational {
                k_nm_per_rad: within(path, "[restraint].rotational_stiffness_mnm_rad", k, limits::STIFFNESS)? * 1e6,
            },
            None,
        )),
        _ => Err(FileError::invalid(
            path,
            "[restraint]: give unit_stiffness_mn_m2 with contact_height_m, or rotational_stiffness_mnm_rad alone",
        )),
    }
}

fn tie_rod(t: &RawTie, path: &Path) -> Result<TieRod> {
    Ok(TieRod {
        stiffness_n_m: within(path, "[[tie_rod]].stiffness_kn_m", t.stiffness_kn_m, limits::STIFFNESS)? * 1e3,
        height_m: within(path, "[[tie_rod]].height_m", t.height_m, limits::LENGTH_M)?,
        yield_force_n: t
            .yield_force_kn
            .map(|f| within(path, "[[tie_rod]].yield_force_kn", f, limits::STIFFNESS).map(|v| v * 1e3))
            .transpose()?,
    })
}

/// The reader of a block file (the type is the solver's).
impl BlockSpec {
    pub fn load(path: &Path) -> Result<BlockSpec> {
        Self::parse(&read_text(path, FileKind::Block)?, path)
    }

    pub fn parse(text: &str, path: &Path) -> Result<BlockSpec> {
        Self::validate(parse_toml(text, path)?, path).map_err(|e| e.located(path, text))
    }

    fn validate(raw: RawFile, path: &Path) -> Result<BlockSpec> {
        let (block, overrides) = block(&raw.block, path)?;
        let (restraint, spring_bed) = restraint(raw.restraint.as_ref(), path)?;
        let ties = raw.tie_rod.iter().map(|t| tie_rod(t, path)).collect::<Result<Vec<_>>>()?;
        Ok(BlockSpec {
            name: raw
                .block
                .name
                .clone()
                .unwrap_or_else(|| path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default()),
            block,
            restraint,
            ties,
            impact: raw.impact.unwrap_or_default(),
            spring_bed,
            overrides,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn facade_fixture() {
        let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("fixtures/facade/block.toml");
        let b = BlockSpec::load(&p).unwrap();
        assert_eq!(b.block.r_m, 3.84);
        assert_eq!(b.block.alpha, 0.10);
        // m = 18 kN/m³ · 7.64 · 0.80 · 12.00 m³ / g
        let m = 18e3 * 7.64 * 0.80 * 12.0 / crate::G;
        assert!((b.block.mass_kg / m - 1.0).abs() < 1e-12);
        assert!((b.block.i0 / (4.0 / 3.0 * m * 3.84 * 3.84) - 1.0).abs() < 1e-12);
        match b.restraint {
            Restraint::Rotational { k_nm_per_rad } => assert!((k_nm_per_rad / (750e6 * 7.64f64.powi(3) / 3.0) - 1.0).abs() < 1e-12),
            _ => panic!("spring bed expected"),
        }
    }

    #[test]
    fn unknown_key_rejected() {
        let e = BlockSpec::parse(
            "[block]\nheight_m=1\nthickness_m=0.1\nwidth_m=1\nunit_weight_kn_m3=18\nhieght=2\n",
            Path::new("b.toml"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("hieght"), "{e}");
    }
}
