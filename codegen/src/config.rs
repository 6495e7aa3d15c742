//! The `build.rs` entry point, in the style of `prost-build`.
//!
//! ```no_run
//! // build.rs of a crate with its own maps under `maps/`
//! fn main() -> Result<(), Box<dyn std::error::Error>> {
//!     drivemap_codegen::Config::new().maps_dir("maps").compile()?;
//!     Ok(())
//! }
//! ```
//!
//! A map with an error fails the build with the report `drivemap check` prints for it, one
//! `file:line:col: error ...` line per finding and the count: the error's `Display` and its
//! `Debug` (what `?` in `main` prints) are that report.
//!
//! and in `src/lib.rs`:
//!
//! ```text
//! include!(concat!(env!("OUT_DIR"), "/drivemap.rs"));
//! ```
//!
//! Each map becomes `OUT_DIR/<module>.rs` and a `pub mod <module>` in `OUT_DIR/drivemap.rs`.
//! Files are written only when their content changed, and `cargo:rerun-if-changed` is printed
//! for every map and map directory, so adding a YAML file to the directory adds a module with
//! no other edit. The generated code refers to the runtime as `::drivemap_runtime` unless told
//! otherwise ([`Config::runtime_crate`]); the crate must depend on it. It names the vocabulary
//! through the runtime's one path to it (`use ::drivemap_runtime::core as rt;`, then
//! `rt::plan::RegisterPlan`).

use std::fmt;
use std::path::{Path, PathBuf};

use crate::generate::{self, Options};
use drivemap_map::Diagnostics;
use drivemap_map::{Loader, Map as Drive};

/// Builder for generating drive modules from maps.
#[derive(Debug, Clone)]
pub struct Config {
    maps: Vec<PathBuf>,
    dirs: Vec<PathBuf>,
    out_dir: Option<PathBuf>,
    manuals_dir: Option<PathBuf>,
    runtime: String,
    index_file: String,
    cargo_directives: bool,
}

impl Default for Config {
    fn default() -> Self {
        Config::new()
    }
}

/// Why generation failed. `Display` and `Debug` are the same readable report (a `build.rs`
/// whose `main` returns it with `?` prints it as is): for invalid maps, the lines `drivemap
/// check` prints, `file:line:col: error ...`, and the count.
#[non_exhaustive]
pub enum Error {
    /// One or more maps are invalid; every finding is listed.
    Invalid(Diagnostics),
    /// A map or a directory could not be read, or an output file written.
    Io {
        /// The file or directory.
        path: PathBuf,
        /// What went wrong.
        error: std::io::Error,
    },
    /// `OUT_DIR` is not set and no output directory was given.
    NoOutDir,
    /// The generated code could not be formed (a runtime path that is not a Rust path).
    Generate(String),
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Invalid(d) => write!(f, "{d}"),
            Error::Io { path, error } => write!(f, "{}: {error}", path.display()),
            Error::NoOutDir => write!(f, "OUT_DIR is not set; call Config::out_dir"),
            Error::Generate(e) => write!(f, "{e}"),
        }
    }
}

impl fmt::Debug for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(self, f)
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Io { error, .. } => Some(error),
            _ => None,
        }
    }
}

/// What a run produced.
#[derive(Debug, Clone)]
pub struct Generated {
    /// Per drive: (drive id, module name, output file).
    pub modules: Vec<(String, String, PathBuf)>,
    /// The index file to `include!`.
    pub index: PathBuf,
    /// Files actually rewritten (unchanged files are left alone).
    pub written: Vec<PathBuf>,
    /// Lines of generated Rust, all modules.
    pub lines: usize,
}

impl Config {
    /// A configuration with no maps, the runtime at `::drivemap_runtime`, the manuals found
    /// beside the maps, and the output in `OUT_DIR`.
    pub fn new() -> Self {
        Config {
            maps: Vec::new(),
            dirs: Vec::new(),
            out_dir: None,
            manuals_dir: None,
            runtime: "::drivemap_runtime".into(),
            index_file: "drivemap.rs".into(),
            cargo_directives: true,
        }
    }

    /// Adds one map file.
    pub fn map(&mut self, path: impl Into<PathBuf>) -> &mut Self {
        self.maps.push(path.into());
        self
    }

    /// Adds every `*.yaml` map of a directory (read at [`Config::compile`] time).
    pub fn maps_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Self {
        self.dirs.push(dir.into());
        self
    }

    /// Where to write the modules (default: `$OUT_DIR`).
    pub fn out_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Where the manuals are, to check that citations point inside them. Default: the
    /// `DRIVEMAP_MANUALS` variable, else `shared/manuals` beside an ancestor of the maps.
    pub fn manuals_dir(&mut self, dir: impl Into<PathBuf>) -> &mut Self {
        self.manuals_dir = Some(dir.into());
        self
    }

    /// Path of the runtime crate in generated code (`::drivemap_runtime`, or
    /// `crate::runtime` when re-exported).
    pub fn runtime_crate(&mut self, path: &str) -> &mut Self {
        self.runtime = path.into();
        self
    }

    /// Name of the index file in the output directory (default `drivemap.rs`).
    pub fn index_file(&mut self, name: &str) -> &mut Self {
        self.index_file = name.into();
        self
    }

    /// Whether to print `cargo:rerun-if-changed` lines (default true; off outside build.rs).
    pub fn cargo_directives(&mut self, on: bool) -> &mut Self {
        self.cargo_directives = on;
        self
    }

    fn map_files(&self) -> Result<Vec<PathBuf>, Error> {
        let mut files = self.maps.clone();
        for dir in &self.dirs {
            let found = crate::find_maps(dir).map_err(|error| Error::Io {
                path: dir.clone(),
                error,
            })?;
            files.extend(found);
        }
        files.sort();
        files.dedup();
        Ok(files)
    }

    fn loader(&self, files: &[PathBuf]) -> Loader<'static> {
        let dir = self.manuals_dir.clone().or_else(|| {
            files
                .first()
                .and_then(|f| crate::default_manuals_dir(f.parent().unwrap_or(Path::new("."))))
        });
        match dir {
            Some(d) => Loader::new().manuals(d),
            None => Loader::new(),
        }
    }

    /// Reads and validates every map without writing anything.
    pub fn check(&self) -> Result<Vec<Drive>, Error> {
        let files = self.map_files()?;
        let loader = self.loader(&files);
        let mut drives = Vec::new();
        let mut errors = Vec::new();
        for f in &files {
            match loader.load(f) {
                Ok(d) => drives.push(d),
                Err(d) => errors.extend(d.0),
            }
        }
        if errors.is_empty() {
            Ok(drives)
        } else {
            Err(Error::Invalid(errors.into()))
        }
    }

    /// Validates every map and returns the code [`compile`](Config::compile) would write — each
    /// module's source and the index that includes them — without writing files or printing
    /// `cargo:` directives (a `prost-build`-style entry for callers that place the files
    /// themselves, and for tests).
    pub fn generate(&self) -> Result<Code, Error> {
        let drives = self.check()?;
        refuse_drafts(&drives)?;
        self.generate_drives(&drives)
    }

    fn generate_drives(&self, drives: &[Drive]) -> Result<Code, Error> {
        let runtime: proc_macro2::TokenStream = self
            .runtime
            .parse()
            .map_err(|e| Error::Generate(format!("runtime path `{}`: {e}", self.runtime)))?;
        let mut modules = Vec::new();
        let mut index = String::from("// @generated by drivemap-codegen. Do not edit.\n\n");
        for drive in drives {
            let options = Options {
                runtime: runtime.clone(),
                source_name: drive
                    .file()
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            };
            let source = generate::drive_module(drive, &options)
                .map_err(|e| Error::Generate(e.to_string()))?;
            // The index and the modules lie side by side in the output directory; `include!`
            // resolves a relative path against the file it is written in, so the index works
            // wherever that directory is (prost-build's include file does the same).
            for line in generate::module_doc(drive) {
                index += &format!("#[doc = {line:?}]\n");
            }
            // A module is a drive's whole map; an application uses a few of its registers.
            // Included into a binary or a private module, the rest is dead code by design, not
            // a mistake to warn about (`examples/one-register` builds with `unused` denied).
            index += "#[allow(dead_code)]\n";
            index += &format!(
                "pub mod {module} {{\n    include!(\"{module}.rs\");\n}}\n\n",
                module = drive.module(),
            );
            modules.push(Module {
                id: drive.id().to_owned(),
                module: drive.module().to_owned(),
                file_name: format!("{}.rs", drive.module()),
                source,
            });
        }
        // Like the modules: a program that includes the index need not list the drives.
        index += "/// Every generated drive: (drive id, module name).\n#[allow(dead_code)]\npub const DRIVES: &[(&str, &str)] = &[\n";
        for m in &modules {
            index += &format!("    ({:?}, {:?}),\n", m.id, m.module);
        }
        index += "];\n\n";
        // Code generic over the drives compiled in (a tool, a test over every map) cannot name
        // modules by string; this macro hands each module to the caller's macro.
        index += "/// Calls `$m!(module, \"drive-id\")` once for every generated drive module, for code that\n\
                  /// is generic over the drives compiled in.\n\
                  #[macro_export]\nmacro_rules! for_each_drive {\n    ($m:ident) => {\n";
        for m in &modules {
            index += &format!("        $m!({}, {:?});\n", m.module, m.id);
        }
        index += "    };\n}\n";
        Ok(Code { modules, index })
    }

    /// Validates every map and writes the modules and the index.
    pub fn compile(&self) -> Result<Generated, Error> {
        let out_dir = match &self.out_dir {
            Some(d) => d.clone(),
            None => std::env::var_os("OUT_DIR")
                .map(PathBuf::from)
                .ok_or(Error::NoOutDir)?,
        };
        let files = self.map_files()?;
        if self.cargo_directives {
            for dir in &self.dirs {
                println!("cargo:rerun-if-changed={}", dir.display());
            }
            for f in &files {
                println!("cargo:rerun-if-changed={}", f.display());
            }
            println!("cargo:rerun-if-env-changed=DRIVEMAP_MANUALS");
        }
        let drives = self.check()?;
        refuse_drafts(&drives)?;
        if self.cargo_directives {
            // A map of an earlier schema version builds, by its meaning; say so once per map.
            for d in &drives {
                if let Some(first) = d.warnings().first() {
                    println!("cargo:warning={}", first.as_warning());
                }
            }
        }
        let code = self.generate_drives(&drives)?;
        std::fs::create_dir_all(&out_dir).map_err(|error| Error::Io {
            path: out_dir.clone(),
            error,
        })?;
        let mut generated = Generated {
            modules: Vec::new(),
            index: out_dir.join(&self.index_file),
            written: Vec::new(),
            lines: 0,
        };
        for m in code.modules {
            generated.lines += m.source.lines().count();
            let path = out_dir.join(&m.file_name);
            if write_if_changed(&path, &m.source)? {
                generated.written.push(path.clone());
            }
            generated.modules.push((m.id, m.module, path));
        }
        if write_if_changed(&generated.index, &code.index)? {
            generated.written.push(generated.index.clone());
        }
        Ok(generated)
    }
}

/// The code of every map, as [`Config::generate`] returns it: nothing written.
#[derive(Debug, Clone)]
pub struct Code {
    /// One per drive, in the order of the map files.
    pub modules: Vec<Module>,
    /// The index (`drivemap.rs` by default): a `pub mod` per module that `include!`s its file
    /// (`<module>.rs`, beside the index), `DRIVES` and `for_each_drive!`.
    pub index: String,
}

/// One drive's generated module.
#[derive(Debug, Clone)]
pub struct Module {
    /// The drive id (`ptlk-tds-v8`).
    pub id: String,
    /// The module name (`ptlk_tds_v8`).
    pub module: String,
    /// The file the index includes (`ptlk_tds_v8.rs`).
    pub file_name: String,
    /// The formatted Rust source.
    pub source: String,
}

/// A draft is never generated: it has not been read against its manual by a person.
fn refuse_drafts(drives: &[Drive]) -> Result<(), Error> {
    let drafts: Vec<crate::Diagnostic> = drives
        .iter()
        .filter(|d| d.draft().is_some())
        .map(|d| {
            d.error_at(
                "draft",
                None,
                "the map is a draft (`draft:`): review every row against the manual and remove \
                 the mark before generating code from it",
            )
        })
        .collect();
    if drafts.is_empty() {
        Ok(())
    } else {
        Err(Error::Invalid(drafts.into()))
    }
}

/// Writes `content` unless the file already holds exactly it. Returns whether it wrote.
fn write_if_changed(path: &Path, content: &str) -> Result<bool, Error> {
    if std::fs::read_to_string(path).is_ok_and(|old| old == content) {
        return Ok(false);
    }
    std::fs::write(path, content).map_err(|error| Error::Io {
        path: path.to_path_buf(),
        error,
    })?;
    Ok(true)
}
