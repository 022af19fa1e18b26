//! rocklab: coefficients of restitution of rocking masonry walls from free-vibration
//! tests, and a rocking solver (Giresini & Croce, COMPDYN 2021).
//!
//! Conventions (SPEC): rotation θ > 0 is OUTWARD (away from the transverse walls),
//! θ < 0 is INWARD. Velocity peaks v_0, v_1, … alternate in sign, v_0 is the first
//! (inward) peak after release; v_{k+1}/v_k is the coefficient of the impact that
//! follows peak k.
//!
//! Where the paper is:
//! - Eq. 1 (the rocking equation of motion): [`solver::model`], integrated by the
//!   Dormand–Prince 5(4) scheme in [`solver::integrator`], event by event in
//!   [`solver::run`] (impacts, rest, uplift, overturning).
//! - Eq. 2 (Housner's e_H = 1 − 1.5 sin²α): [`wall::housner_e`].
//! - Eqs. 3–6 (e from the ratios of successive velocity peaks, e⁺ and e⁻ by
//!   side, r = e / e_H; Tables 1–3's r₁, r₂) and their uncertainties:
//!   [`restitution`].
//! - The estimator of the velocity peaks (damped arcs fitted to the free-rocking
//!   segments): [`peaks`], called per test by [`reduction`]; the campaign means
//!   in [`campaign_means`].
//! - The calibration of e by replaying the tests with the solver: [`calibrate`]
//!   on [`fit`] (Levenberg–Marquardt); the façade study: [`facade`], one run in
//!   [`study`], ensembles in [`ensemble`], fragility curves in [`fragility`].
//!
//! Layout: the numeric core (every module but [`ingest`], [`report`], [`archive`],
//! `cli` and [`atomic`]) touches no files and names no clap, plotters or anyhow type;
//! the domain types ([`wall::Rocking`], [`wall::Side`], [`wall::Rectangle`],
//! [`wall::Wall`]) live there. The edges depend on it, never the reverse
//! (`tests/architecture.rs` checks it): [`ingest`] is the only reader of inputs,
//! [`report`] renders and writes, [`archive`] keeps a lab's archive of reductions
//! (Parquet tables queried with SQL, on polars), `cli` is the binary.

pub mod archive;
pub mod atomic;
pub mod calibrate;
pub mod campaign_means;
pub mod ensemble;
pub mod error;
pub mod facade;
pub mod fit;
pub mod fragility;
pub mod ground_motion;
pub mod impacts;
pub mod ingest;
pub mod law_fit;
pub mod law_replay;
pub mod limits;
pub mod outcomes;
pub mod peaks;
pub mod reduction;
pub mod report;
pub mod restitution;
pub mod restitution_law;
pub mod signal;
pub mod solver;
pub mod stats;
pub mod study;
pub mod synth;
pub mod wall;

/// A campaign's reduction from its files (in [`ingest`]: it reads the logs).
pub use ingest::reduce;

/// Standard gravity, m/s² (also what ESM uses: g = 980.665 cm/s²).
pub const G: f64 = 9.80665;
