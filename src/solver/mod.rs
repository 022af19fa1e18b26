//! The rocking solver: paper Eq. 1 with one-sided restraint (transverse walls as a
//! compression-only spring bed), tie-rods, direction-dependent impacts (a constant
//! pair or a restitution law of the amplitude, [`impact`]), rest and uplift, and
//! overturning, integrated by an adaptive Dormand–Prince 5(4) scheme whose events
//! (impacts, overturning, uplift) are located on the dense output.
//!
//! Why our own integrator: the crates that were considered either have no event
//! location (ode_solvers, russell_ode) or bring a second linear-algebra stack
//! (diffsol drags faer and another nalgebra). The scheme is ~200 lines with its
//! own tests (`integrator.rs`), and the rocking loop needs to control every step
//! (never straddling a record sample, where the forcing has a kink).

pub mod block;
pub mod impact;
pub mod integrator;
pub mod model;
pub mod run;

pub use block::{Block, BlockSpec};
pub use impact::{ImpactLaw, Restitution};
pub use model::{Ground, Restraint, RockingModel, TieRod};
pub use run::{simulate, simulate_at, Event, Settings, Simulation, Stop};
