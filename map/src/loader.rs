//! The one way to read a map: a [`Loader`] with the options the reading needs, giving a
//! validated [`Map`] or every problem of the file at once ([`Diagnostics`]).

use std::path::{Path, PathBuf};

use crate::diagnostic::Diagnostics;
use crate::load::{self, LoadedMap, TreeCache};
use crate::map::Map;
use crate::source::Node;
use crate::validate::Context;

/// Gives the name and YAML text of a base map by drive id (maps built into a program).
type Bases<'a> = dyn Fn(&str) -> Option<(String, String)> + 'a;

/// Reads, expands, validates and lowers map files.
///
/// ```no_run
/// let map = drivemap_map::Loader::new()
///     .manuals("../shared/manuals")
///     .load("maps/yaskawa-v7.yaml".as_ref())
///     .map_err(|d| d.to_string())?;
/// println!("{} registers", map.registers().count());
/// # Ok::<(), String>(())
/// ```
///
/// One loader may read many maps; with [`Loader::cached`] it reads each file once however
/// many maps extend it.
#[derive(Default)]
pub struct Loader<'a> {
    ctx: Context,
    cache: Option<TreeCache>,
    bases: Option<Box<Bases<'a>>>,
    any_file_name: bool,
}

impl std::fmt::Debug for Loader<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Loader")
            .field("manuals", &self.ctx.manual_lines.len())
            .field("cached", &self.cache.is_some())
            .field("bases", &self.bases.is_some())
            .field("any_file_name", &self.any_file_name)
            .finish()
    }
}

impl<'a> Loader<'a> {
    /// A loader that checks citations for form and manual name only, caches nothing and
    /// resolves `extends` against the map's own directory.
    pub fn new() -> Loader<'a> {
        Loader::default()
    }

    /// Checks that citations fall inside the `*.txt` manuals of `dir` (a missing directory
    /// checks nothing more than [`Loader::new`]).
    pub fn manuals(mut self, dir: impl AsRef<Path>) -> Loader<'a> {
        self.ctx = Context::with_manuals(dir.as_ref());
        self
    }

    /// Checks citations of the text manual `file` against `lines` lines, as if the manuals
    /// directory held it (for maps and manuals held in memory).
    pub fn manual_lines(mut self, file: &str, lines: usize) -> Loader<'a> {
        self.ctx.manual_lines.insert(file.to_owned(), lines);
        self
    }

    /// [`Loader::manuals`] with the directory [`default_manuals_dir`](crate::default_manuals_dir)
    /// finds for maps in `maps_dir`, when it finds one.
    pub fn default_manuals(self, maps_dir: &Path) -> Loader<'a> {
        match crate::default_manuals_dir(maps_dir) {
            Some(dir) => self.manuals(dir),
            None => self,
        }
    }

    /// Shares the trees of map files already read (and their bases) between the maps this
    /// loader reads: reading every map of a directory reads each file once. The bases that
    /// [`Loader::load_tree`] finds through [`Loader::bases`] are kept too, by drive id.
    pub fn cached(mut self) -> Loader<'a> {
        self.cache = Some(TreeCache::new());
        self
    }

    /// How many map files were read and parsed through the cache ([`Loader::cached`]).
    pub fn files_read(&self) -> usize {
        self.cache.as_ref().map_or(0, TreeCache::files_read)
    }

    /// Resolves `extends` of maps read from text through `bases`, which gives the name and
    /// YAML text of a base map by drive id (maps built into a program).
    pub fn bases(mut self, bases: impl Fn(&str) -> Option<(String, String)> + 'a) -> Loader<'a> {
        self.bases = Some(Box::new(bases));
        self
    }

    /// Reads a map kept under any file name (`old.yaml`, `tds-before.yaml`): the rule that a
    /// map's file is named `<drive id>.yaml`, which matters for a maps directory, is not
    /// applied. `drivemap diff old.yaml new.yaml` reads maps so.
    pub fn any_file_name(mut self) -> Loader<'a> {
        self.any_file_name = true;
        self
    }

    /// Reads one map file, resolving `extends` against maps in the same directory.
    pub fn load(&self, path: &Path) -> Result<Map, Diagnostics> {
        let loaded = match &self.cache {
            Some(cache) => load::load_cached(path, cache),
            None => load::load(path),
        }
        .map_err(Diagnostics::from)?;
        if self.any_file_name {
            let mut drive = crate::ir::expand(loaded).map_err(Diagnostics::from)?;
            drive.file = path.with_file_name(format!("{}.yaml", drive.meta.id));
            let errors = crate::validate::validate(&drive, &self.ctx);
            drive.file = PathBuf::from(path);
            return Map::checked(drive, errors);
        }
        self.finish(loaded)
    }

    /// Reads a map held in memory, named `name` in diagnostics; `extends` is resolved through
    /// [`Loader::bases`] (without it, a map that extends another is an error).
    pub fn load_str(&self, name: &str, text: &str) -> Result<Map, Diagnostics> {
        let loaded = match &self.bases {
            Some(bases) => load::load_str_with(name, text, bases.as_ref()),
            None => load::load_str(name, text),
        }
        .map_err(Diagnostics::from)?;
        self.finish(loaded)
    }

    /// Reads a map already parsed into a [`Tree`](crate::Tree) ([`parse_map`](crate::parse_map)):
    /// for tools that edit a map's tree before reading it. With [`Loader::cached`], the base a
    /// map extends is read through [`Loader::bases`] and parsed once for all the trees this
    /// loader reads (the base's text is taken to stay the same).
    pub fn load_tree(&self, name: &str, tree: Node) -> Result<Map, Diagnostics> {
        let none = |_: &str| None;
        let bases: &Bases<'_> = match &self.bases {
            Some(b) => b.as_ref(),
            None => &none,
        };
        let loaded = load::load_tree_with(name, tree, bases, self.cache.as_ref())
            .map_err(Diagnostics::from)?;
        self.finish(loaded)
    }

    fn finish(&self, loaded: LoadedMap) -> Result<Map, Diagnostics> {
        let drive = crate::ir::expand(loaded).map_err(Diagnostics::from)?;
        let errors = crate::validate::validate(&drive, &self.ctx);
        Map::checked(drive, errors)
    }
}

/// Parses a map file's text as the loader does (numbers read in the file's schema version),
/// named `name` in diagnostics: the tree a tool edits before [`Loader::load_tree`].
pub fn parse_map(name: &str, text: &str) -> Result<Node, Diagnostics> {
    crate::source::parse_map(&name.into(), text)
        .map(|p| p.tree)
        .map_err(Diagnostics::from)
}

/// Parses any YAML text into a located tree, named `name` in diagnostics (a configuration
/// file read with the map's located errors). Text over [`MAX_YAML_BYTES`] is refused by the
/// caller with [`too_large`].
pub fn parse_yaml(name: &str, text: &str) -> Result<Node, crate::Diagnostic> {
    crate::source::parse(&name.into(), text)
}

/// The largest map (or YAML file) read, in bytes.
pub const MAX_YAML_BYTES: usize = crate::source::MAX_MAP_BYTES;

/// The deepest nesting of YAML collections read.
pub const MAX_YAML_DEPTH: usize = crate::source::MAX_DEPTH;

/// The most nodes YAML aliases may expand to in one file.
pub const MAX_YAML_ALIAS_NODES: usize = crate::source::MAX_ALIAS_NODES;

/// The error for a file of `len` bytes, over [`MAX_YAML_BYTES`].
pub fn too_large(name: &str, len: usize) -> crate::Diagnostic {
    crate::source::too_large(&name.into(), len)
}
