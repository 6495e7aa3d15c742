//! Finding maps: by file, or by drive id under the maps directory.

use std::path::{Path, PathBuf};

use clap::Args as ClapArgs;
use drivemap_codegen::{Diagnostics, Drive, validate::Context};

/// Where maps are looked up.
#[derive(ClapArgs, Debug, Clone)]
pub struct MapsDir {
    /// Directory holding `<drive id>.yaml` maps.
    #[arg(long, default_value = "maps", env = "DRIVEMAP_MAPS")]
    pub maps: PathBuf,
}

impl MapsDir {
    pub fn path_of(&self, id: &str) -> Result<PathBuf, String> {
        let path = self.maps.join(format!("{id}.yaml"));
        if path.is_file() {
            return Ok(path);
        }
        let known = drivemap_codegen::find_maps(&self.maps)
            .map(|v| {
                v.iter()
                    .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
                    .collect::<Vec<_>>()
                    .join(", ")
            })
            .unwrap_or_default();
        Err(format!(
            "no map for drive `{id}` in {} (known: {known})",
            self.maps.display()
        ))
    }

    /// Reads, expands and validates a map.
    pub fn read(&self, path: &Path) -> Result<Drive, Diagnostics> {
        drivemap_codegen::read_map(path, &context_for(path))
    }
}

/// Validation context for a map file: the manuals directory near it, if any.
pub fn context_for(path: &Path) -> Context {
    let dir = path.parent().unwrap_or(Path::new("."));
    match drivemap_codegen::default_manuals_dir(dir) {
        Some(m) => Context::with_manuals(&m),
        None => Context::default(),
    }
}

/// The manuals directory for a map file: `$DRIVEMAP_MANUALS`, else `shared/manuals` beside an
/// ancestor of the map's directory.
pub fn manuals_dir_for(path: &Path) -> Option<PathBuf> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    drivemap_codegen::default_manuals_dir(dir)
}
