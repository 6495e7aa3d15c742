//! Conversions between raw register words and engineering values: the vocabulary crate's
//! [`drivemap_core::scale`], re-exported so `drivemap_runtime::scale` keeps its path.

pub use drivemap_core::scale::*;
