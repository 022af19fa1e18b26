//! The input edge, the only reader of files: the campaign manifest, the
//! displacement logs (and the campaign's reduction from them, [`reduce`]), the
//! block file, the façade study, calibration.toml, a restitution law file and
//! the ground-motion records.

pub mod block;
pub mod calibration;
pub mod formats;
pub mod law;
pub mod log;
pub mod manifest;
pub mod record;
pub mod reduce;
pub mod scaffold;
pub mod study;
pub mod text;

pub use log::{Decimal, Delimiter, LogData, LogFormat, LogReader};
pub use manifest::{Campaign, Rocking, TestSpec};
