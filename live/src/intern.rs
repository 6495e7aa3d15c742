//! `'static` strings for names loaded at run time.
//!
//! The runtime's errors and profiles carry `&'static str` (generated code has literals). A map
//! loaded at run time has a finite set of names — register ids, units, parameter numbers — so
//! each distinct string is leaked once and reused: memory is bounded by the maps loaded.

use std::collections::HashSet;
use std::sync::{Mutex, OnceLock};

static NAMES: OnceLock<Mutex<HashSet<&'static str>>> = OnceLock::new();

/// The interned `'static` copy of `s`.
pub fn intern(s: &str) -> &'static str {
    let set = NAMES.get_or_init(|| Mutex::new(HashSet::new()));
    let mut set = match set.lock() {
        Ok(guard) => guard,
        Err(poisoned) => poisoned.into_inner(),
    };
    if let Some(existing) = set.get(s) {
        return existing;
    }
    let leaked: &'static str = Box::leak(s.to_owned().into_boxed_str());
    set.insert(leaked);
    leaked
}
