//! The input edge: the campaign manifest and the displacement logs.

pub mod block;
pub mod log;
pub mod manifest;

pub use log::{Decimal, Delimiter, LogData, LogFormat, LogReader};
pub use manifest::{Campaign, Rocking, TestSpec};
