//! A drive's protocol profile: the vocabulary crate's [`drivemap_core::profile`], re-exported.

pub use drivemap_core::profile::*;
