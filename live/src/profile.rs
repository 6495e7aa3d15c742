//! The runtime [`Profile`] of a map loaded at run time: the one the lowering pass decided
//! ([`drivemap_map::lower`]), as generated code has it.
//!
//! The client takes `&'static Profile` (generated code has statics). The plan, profile included,
//! is lowered once per loaded map and lives as long as the process.

use drivemap_map::Map;
use drivemap_runtime::core::profile::Profile;

/// The runtime profile of `drive`, with `'static` lifetime (see the module docs).
pub fn leak_profile(drive: &Map) -> &'static Profile {
    drive.plan().profile
}
