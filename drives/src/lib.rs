//! generated drive modules
