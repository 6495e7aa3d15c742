//! Helpers shared by several test modules of this binary (`crate::<helper>` in each).

pub mod bridge_support;
pub mod common;
pub mod new_map;
