//! Finding maps: the shipped maps are built into the binary; `--maps DIR` (or `DRIVEMAP_MAPS`)
//! adds maps to them or replaces them by drive id; a map file can also be named directly.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args as ClapArgs;
use drivemap_map::{Diagnostics, Loader, Map};

include!(concat!(env!("OUT_DIR"), "/builtin_maps.rs"));

/// Where maps are looked up.
#[derive(ClapArgs, Debug, Clone, Default)]
pub(crate) struct MapsDir {
    /// Directory of `<drive id>.yaml` maps that add to the built-in maps or replace them by id.
    #[arg(long, value_name = "DIR", env = "DRIVEMAP_MAPS")]
    pub(crate) maps: Option<PathBuf>,
}

/// Where a drive's map comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) enum MapSource {
    /// A file of the maps directory.
    File(PathBuf),
    /// Built into the binary.
    Builtin(&'static str),
}

/// Why a drive's map cannot be had.
#[derive(Debug, thiserror::Error)]
pub(crate) enum MapError {
    /// No map of that id, built in or in the maps directory.
    #[error("no map for drive `{id}` (known: {known}{})", match dir {
        Some(d) => format!("; looked in {} and the built-in maps", d.display()),
        None => "; add maps with --maps DIR or DRIVEMAP_MAPS".into(),
    })]
    Unknown {
        /// The id asked for.
        id: String,
        /// The ids known, comma-separated.
        known: String,
        /// The maps directory looked in.
        dir: Option<PathBuf>,
    },
    /// A built-in map where a file is needed.
    #[error("drive `{0}` is built in, not a file; give --maps DIR for a map file")]
    BuiltIn(String),
    /// The map does not validate; each diagnostic says file:line:column.
    #[error("{what} does not validate:\n{diagnostics}")]
    Invalid {
        /// The file, or `built-in map <id>`.
        what: String,
        /// What is wrong, where.
        diagnostics: Diagnostics,
    },
}

/// The YAML of a built-in map.
pub(crate) fn builtin(id: &str) -> Option<&'static str> {
    BUILTIN_MAPS.iter().find(|(i, _)| *i == id).map(|(_, t)| *t)
}

impl MapsDir {
    /// The directory given, else `maps` (for commands that work on a directory of files:
    /// `check` without files, `diff --git`).
    pub(crate) fn dir(&self) -> PathBuf {
        self.maps.clone().unwrap_or_else(|| PathBuf::from("maps"))
    }

    /// Every drive id known and where its map comes from: built in, then the maps directory.
    pub(crate) fn known(&self) -> BTreeMap<String, MapSource> {
        let mut all: BTreeMap<String, MapSource> = BUILTIN_MAPS
            .iter()
            .map(|(id, text)| (id.to_string(), MapSource::Builtin(text)))
            .collect();
        if let Some(dir) = &self.maps {
            for p in drivemap_map::find_maps(dir).unwrap_or_default() {
                if let Some(id) = p.file_stem().map(|s| s.to_string_lossy().into_owned()) {
                    all.insert(id, MapSource::File(p));
                }
            }
        }
        all
    }

    /// Where the map of `id` comes from: `<maps>/<id>.yaml` when there, else built in.
    pub(crate) fn source_of(&self, id: &str) -> Result<MapSource, MapError> {
        if let Some(dir) = &self.maps {
            for ext in ["yaml", "yml"] {
                let path = dir.join(format!("{id}.{ext}"));
                if path.is_file() {
                    return Ok(MapSource::File(path));
                }
            }
        }
        if let Some(text) = builtin(id) {
            return Ok(MapSource::Builtin(text));
        }
        let known: Vec<String> = self.known().into_keys().collect();
        Err(MapError::Unknown {
            id: id.to_owned(),
            known: known.join(", "),
            dir: self.maps.clone(),
        })
    }

    /// The path of a drive's map file, for commands that need a file (built-in maps have none).
    pub(crate) fn path_of(&self, id: &str) -> Result<PathBuf, MapError> {
        match self.source_of(id)? {
            MapSource::File(p) => Ok(p),
            MapSource::Builtin(_) => Err(MapError::BuiltIn(id.to_owned())),
        }
    }

    /// Reads, expands and validates the map of a drive id; `extends` is resolved by id the
    /// same way (the maps directory first, then the built-in maps).
    pub(crate) fn load(&self, id: &str) -> Result<Map, MapError> {
        match self.source_of(id)? {
            MapSource::File(p) => self.read(&p).map_err(|diagnostics| MapError::Invalid {
                what: p.display().to_string(),
                diagnostics,
            }),
            MapSource::Builtin(text) => {
                self.read_builtin(id, text)
                    .map_err(|diagnostics| MapError::Invalid {
                        what: format!("built-in map {id}"),
                        diagnostics,
                    })
            }
        }
    }

    /// Reads, expands and validates a built-in map (its base too is looked up by id).
    pub(crate) fn read_builtin(&self, id: &str, text: &str) -> Result<Map, Diagnostics> {
        Loader::new()
            .bases(|base| self.base_text(base))
            .load_str(&format!("<built-in>/{id}.yaml"), text)
    }

    fn base_text(&self, id: &str) -> Option<(String, String)> {
        match self.source_of(id).ok()? {
            MapSource::File(p) => {
                let text = std::fs::read_to_string(&p).ok()?;
                Some((p.display().to_string(), text))
            }
            MapSource::Builtin(text) => Some((format!("<built-in>/{id}.yaml"), text.to_owned())),
        }
    }

    /// Reads, expands and validates a map file. Its base (`extends`) is looked up beside it,
    /// else by id among the maps this finds (the built-in ones too).
    pub(crate) fn read(&self, path: &Path) -> Result<Map, Diagnostics> {
        self.read_with(&self.loader(path), path)
    }

    /// The loader [`MapsDir::read_with`] takes for `path`: the manuals near it, bases by id
    /// among the maps this finds. Make it [`Loader::cached`] to read many maps of one
    /// directory: each file is read once, however long its chains of `extends`.
    pub(crate) fn loader(&self, path: &Path) -> Loader<'_> {
        loader_for(path).bases(|base| self.base_text(base))
    }

    /// [`MapsDir::read`] with a loader of [`MapsDir::loader`] (a cached one shares the files
    /// already read, a map's bases, between the maps it reads).
    pub(crate) fn read_with(&self, loader: &Loader<'_>, path: &Path) -> Result<Map, Diagnostics> {
        let direct = loader.load(path);
        let base_missing = |d: &Diagnostics| {
            d.iter()
                .any(|x| x.message.starts_with("base map `") && x.message.ends_with("not found"))
        };
        match &direct {
            Err(d) if base_missing(d) => {}
            _ => return direct,
        }
        // The base is not beside the file: look it up by id.
        let Ok(text) = std::fs::read_to_string(path) else {
            return direct;
        };
        let name = drivemap_map::migrate::display_name(path);
        loader.load_str(&name, &text)
    }
}

/// The loader for a map file: with the manuals directory near it, if any, for its citations.
pub(crate) fn loader_for(path: &Path) -> Loader<'static> {
    Loader::new().default_manuals(map_dir(path))
}

/// The directory of a map file, where its manuals are looked for.
fn map_dir(path: &Path) -> &Path {
    path.parent().unwrap_or(Path::new("."))
}

/// The manuals directory for a map file: `$DRIVEMAP_MANUALS`, else `shared/manuals` beside an
/// ancestor of the map's directory.
pub(crate) fn manuals_dir_for(path: &Path) -> Option<PathBuf> {
    let dir = path
        .parent()
        .filter(|p| !p.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    drivemap_map::default_manuals_dir(dir)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_shipped_map_is_built_in_and_loads_without_files() {
        let dir = drivemap_test_support::paths::maps();
        let shipped: Vec<String> = drivemap_map::find_maps(&dir)
            .unwrap()
            .iter()
            .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
            .collect();
        let built: Vec<&str> = BUILTIN_MAPS.iter().map(|(id, _)| *id).collect();
        assert_eq!(built, shipped);
        for id in &shipped {
            let drive = MapsDir::default().load(id).unwrap();
            assert_eq!(&drive.id(), id);
        }
        // yaskawa-j7 extends yaskawa-v7: the base is found among the built-in maps.
        let j7 = MapsDir::default().load("yaskawa-j7").unwrap();
        let from_file = Loader::new().load(&dir.join("yaskawa-j7.yaml")).unwrap();
        assert_eq!(j7.registers().len(), from_file.registers().len());
    }

    #[test]
    fn a_maps_directory_overrides_by_id_and_adds() {
        let tmp = std::env::temp_dir().join(format!("drivemap-maps-{}", std::process::id()));
        std::fs::create_dir_all(&tmp).unwrap();
        let v7 = builtin("yaskawa-v7").unwrap();
        std::fs::write(tmp.join("yaskawa-v7.yaml"), v7).unwrap();
        std::fs::write(
            tmp.join("my-v7.yaml"),
            v7.replacen("id: yaskawa-v7", "id: my-v7", 1),
        )
        .unwrap();
        let dir = MapsDir {
            maps: Some(tmp.clone()),
        };
        assert_eq!(
            dir.source_of("yaskawa-v7").unwrap(),
            MapSource::File(tmp.join("yaskawa-v7.yaml"))
        );
        assert!(matches!(
            dir.source_of("ptlk-tds-v8").unwrap(),
            MapSource::Builtin(_)
        ));
        assert_eq!(dir.load("my-v7").unwrap().id(), "my-v7");
        // The built-in j7 extends the v7 of the directory.
        assert!(dir.load("yaskawa-j7").is_ok());
        // A j7 file alone in a directory extends the built-in v7.
        let lone = tmp.join("lone");
        std::fs::create_dir_all(&lone).unwrap();
        std::fs::write(lone.join("yaskawa-j7.yaml"), builtin("yaskawa-j7").unwrap()).unwrap();
        let j7 = MapsDir::default()
            .read(&lone.join("yaskawa-j7.yaml"))
            .unwrap();
        assert_eq!(j7.id(), "yaskawa-j7");
        let e = MapsDir::default()
            .source_of("nope")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("known: automationdirect-acn, ptlk-tds-v8"),
            "{e}"
        );
        std::fs::remove_dir_all(&tmp).unwrap();
    }
}
