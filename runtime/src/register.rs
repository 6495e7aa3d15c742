//! The seam between generated register types and the clients: the vocabulary crate's
//! [`drivemap_core::register`] and [`drivemap_core::plan`], re-exported.

pub use drivemap_core::plan::*;
pub use drivemap_core::register::*;
pub use drivemap_core::width::{Width, WordOrder};
