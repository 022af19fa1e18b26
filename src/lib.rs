//! rocklab: coefficients of restitution of rocking masonry walls from free-vibration
//! tests, and a rocking solver (Giresini & Croce, COMPDYN 2021).
//!
//! Conventions (SPEC): rotation θ > 0 is OUTWARD (away from the transverse walls),
//! θ < 0 is INWARD. Velocity peaks v_0, v_1, … alternate in sign, v_0 is the first
//! (inward) peak after release; v_{k+1}/v_k is the coefficient of the impact that
//! follows peak k.
//!
//! Layout: the numeric core ([`signal`], [`peaks`], [`restitution`], [`tables`],
//! [`solver`], [`wall`]) touches no files; the edges ([`ingest`], [`report`], `cli`) depend on it, never the reverse.

pub mod atomic;
pub mod calibrate;
pub mod ensemble;
pub mod error;
pub mod facade;
pub mod fit;
pub mod fragility;
pub mod ground_motion;
pub mod ingest;
pub mod outcomes;
pub mod peaks;
pub mod reduce;
pub mod report;
pub mod restitution;
pub mod signal;
pub mod solver;
pub mod stats;
pub mod study;
pub mod synth;
pub mod tables;
pub mod wall;

/// Seconds.
pub type Seconds = f64;
/// Radians.
pub type Radians = f64;
/// Millimetres.
pub type Millimetres = f64;

/// Standard gravity, m/s² (also what ESM uses: g = 980.665 cm/s²).
pub const G: f64 = 9.80665;
