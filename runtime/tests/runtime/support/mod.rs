//! Helpers shared by several test modules of this binary (`crate::<helper>` in each).

pub mod common;
