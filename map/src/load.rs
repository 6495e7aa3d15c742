//! Reading map files: YAML text → located tree → (variant merged onto its base) → model.
//!
//! A variant map (`drive.extends: yaskawa-v7`) is merged onto its base before deserializing:
//! `drive` keys override (manuals are united), `protocol` is merged key by key recursively,
//! `variants` are replaced when given, `groups` are merged by `id` and their `registers` by `id`
//! (a register entry in the variant replaces the base register's keys it names and keeps the
//! others), `roles` are merged role by role (a role the variant gives replaces the base's places for
//! it), `conflicts` and `gaps` are concatenated, and the registers listed under `removed` are
//! dropped. Every node keeps the file and line it was written at, so errors in inherited rows
//! point at the base map and errors in overrides at the variant.

use std::cell::{Cell, RefCell};
use std::collections::{HashMap, HashSet};
use std::io::Read;
use std::path::{Path as FsPath, PathBuf};
use std::sync::Arc;

use serde_yaml::Value;

use crate::diagnostic::{Diagnostic, Loc};
use crate::model::MapFile;
use crate::source::{self, Node, NodeKind, Path, Seg};

/// A map read from disk: the model and the tree it was deserialized from.
#[derive(Debug, Clone)]
pub(crate) struct LoadedMap {
    /// The file that was asked for.
    pub path: PathBuf,
    pub model: MapFile,
    /// The merged tree, for locating findings.
    pub tree: Node,
    /// What reading the file (and its base) in an earlier schema version changed
    /// ([`crate::schema`]); empty for maps in the current schema.
    pub warnings: Vec<Diagnostic>,
}

/// How a file is named in diagnostics: relative to the current directory when possible.
pub(crate) fn display_name(path: &FsPath) -> Arc<str> {
    let shown = std::env::current_dir()
        .ok()
        .and_then(|cwd| path.strip_prefix(&cwd).ok().map(FsPath::to_path_buf))
        .unwrap_or_else(|| path.to_path_buf());
    Arc::from(shown.to_string_lossy().as_ref())
}

/// A merged tree and the warnings of reading it (and its bases), or why it cannot be read.
type Merged = Result<(Node, Vec<Diagnostic>), Vec<Diagnostic>>;

/// The merged trees of the map files read so far, by canonical path: reading every map of a
/// directory with one cache parses and merges each file once, so a chain of `extends` costs
/// time in proportion to its length (each variant is merged onto its base's cached tree),
/// not to the square of it.
#[derive(Debug, Default)]
pub(crate) struct TreeCache {
    trees: RefCell<HashMap<PathBuf, Merged>>,
    /// The merged trees of base maps found through a [`BaseResolver`] (maps read from text or
    /// from a tree), by drive id: a tool that reads many edits of one variant map parses its
    /// base once.
    bases: RefCell<HashMap<String, Merged>>,
    read: Cell<usize>,
}

impl TreeCache {
    /// An empty cache.
    pub(crate) fn new() -> Self {
        Self::default()
    }

    /// How many map files were read and parsed through this cache.
    pub(crate) fn files_read(&self) -> usize {
        self.read.get()
    }
}

/// Reads one map file, resolving `extends` against maps in the same directory
/// (`<id>.yaml`). Returns every problem found while reading.
pub(crate) fn load(path: &FsPath) -> Result<LoadedMap, Vec<Diagnostic>> {
    load_cached(path, &TreeCache::new())
}

/// Like [`load`], taking the merged tree of every file (the map and its bases) from `cache`
/// when it was read before, and keeping what it reads there.
pub(crate) fn load_cached(path: &FsPath, cache: &TreeCache) -> Result<LoadedMap, Vec<Diagnostic>> {
    let (tree, warnings) = load_tree(path, cache)?;
    let model = deserialize(&tree)?;
    Ok(LoadedMap {
        path: path.to_path_buf(),
        model,
        tree,
        warnings,
    })
}

/// Parses a map from text (for tests and tools that hold YAML in memory). `extends` is not
/// resolved.
pub(crate) fn load_str(name: &str, text: &str) -> Result<LoadedMap, Vec<Diagnostic>> {
    let file: Arc<str> = Arc::from(name);
    let parsed = source::parse_map(&file, text)?;
    let tree = parsed.tree;
    if let Some(base) = tree.get("drive").and_then(|d| d.get("extends")) {
        return Err(vec![Diagnostic::new(
            base.loc.clone(),
            None,
            "`extends` needs the map to be read from a file beside its base",
        )]);
    }
    let model = deserialize(&tree)?;
    Ok(LoadedMap {
        path: PathBuf::from(name),
        model,
        tree,
        warnings: parsed.warnings,
    })
}

fn read_tree(path: &FsPath) -> Result<source::Parsed, Vec<Diagnostic>> {
    let file = display_name(path);
    let cannot = |e: std::io::Error| {
        vec![Diagnostic::new(
            Loc::new(file.clone(), 1, 1),
            None,
            format!("cannot read map: {e}"),
        )]
    };
    // Read at most one byte past the limit, so a huge file (or a device) is never read whole.
    let mut bytes = Vec::new();
    std::fs::File::open(path)
        .and_then(|f| {
            f.take(source::MAX_MAP_BYTES as u64 + 1)
                .read_to_end(&mut bytes)
        })
        .map_err(cannot)?;
    if bytes.len() > source::MAX_MAP_BYTES {
        let len = std::fs::metadata(path).map_or(bytes.len(), |m| m.len() as usize);
        return Err(vec![source::too_large(&file, len)]);
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        cannot(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("not UTF-8 text ({e})"),
        ))
    })?;
    source::parse_map(&file, &text)
}

/// The merged tree of `path`: the file merged onto its chain of bases, with the warnings of
/// reading them. Walks the chain up to the first file without `extends` (or the first one
/// already in `cache`) in a loop, then merges back down, caching every level: a long chain
/// neither recurses nor reads a file twice.
fn load_tree(path: &FsPath, cache: &TreeCache) -> Merged {
    let canonical = |p: &FsPath| p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    // Files read on the way up, each waiting for its base's merged tree.
    let mut pending: Vec<(PathBuf, source::Parsed)> = Vec::new();
    let mut seen: HashSet<PathBuf> = HashSet::new();
    let mut current = path.to_path_buf();
    let mut merged: Merged = loop {
        let key = canonical(&current);
        if let Some(done) = cache.trees.borrow().get(&key) {
            break done.clone();
        }
        seen.insert(key.clone());
        cache.read.set(cache.read.get() + 1);
        let step = read_tree(&current).and_then(|parsed| {
            let base = base_of(&current, &parsed.tree, &seen)?;
            Ok((parsed, base))
        });
        match step {
            Ok((parsed, None)) => {
                let done = Ok((parsed.tree, parsed.warnings));
                cache.trees.borrow_mut().insert(key, done.clone());
                break done;
            }
            Ok((parsed, Some(base_path))) => {
                pending.push((key, parsed));
                current = base_path;
            }
            Err(e) => {
                cache.trees.borrow_mut().insert(key, Err(e.clone()));
                break Err(e);
            }
        }
    };
    while let Some((key, parsed)) = pending.pop() {
        merged = merged.and_then(|(base, base_warnings)| {
            // The variant's warnings, then its bases' (the order they are read in).
            let mut warnings = parsed.warnings;
            warnings.extend(base_warnings);
            Ok((merge_variant(base, parsed.tree)?, warnings))
        });
        cache.trees.borrow_mut().insert(key, merged.clone());
    }
    merged
}

/// The path of the base map that `tree` (read from `path`) names with `extends`, if any;
/// refused when the base is missing or already on the chain (`seen`).
fn base_of(
    path: &FsPath,
    tree: &Node,
    seen: &HashSet<PathBuf>,
) -> Result<Option<PathBuf>, Vec<Diagnostic>> {
    let Some(extends) = tree.get("drive").and_then(|d| d.get("extends")) else {
        return Ok(None);
    };
    let NodeKind::Scalar(Value::String(base_id)) = &extends.kind else {
        return Err(vec![Diagnostic::new(
            extends.loc.clone(),
            None,
            "`drive.extends` must name the base drive's id",
        )]);
    };
    let base_path = path
        .parent()
        .unwrap_or_else(|| FsPath::new("."))
        .join(format!("{base_id}.yaml"));
    let canonical = base_path
        .canonicalize()
        .unwrap_or_else(|_| base_path.clone());
    if seen.contains(&canonical) {
        return Err(vec![Diagnostic::new(
            extends.loc.clone(),
            None,
            format!("`extends: {base_id}` makes a cycle of variant maps"),
        )]);
    }
    if !base_path.is_file() {
        return Err(vec![Diagnostic::new(
            extends.loc.clone(),
            None,
            format!("base map `{}` not found", base_path.display()),
        )]);
    }
    Ok(Some(base_path))
}

fn deserialize(tree: &Node) -> Result<MapFile, Vec<Diagnostic>> {
    let first = match deserialize_at::<MapFile>(tree, tree, &Path::root()) {
        Ok(map) => return Ok(map),
        Err(d) => d,
    };
    // serde stops at the first error; deserialize each part on its own to report them all.
    let mut errors = vec![first];
    if let NodeKind::Map(entries) = &tree.kind {
        for (key, _, node) in entries {
            let path = Path::root().key(key);
            let err = match key.as_str() {
                "drive" => deserialize_at::<crate::model::DriveMeta>(tree, node, &path).err(),
                "protocol" => deserialize_at::<crate::model::Protocol>(tree, node, &path).err(),
                "variants" => {
                    deserialize_at::<Vec<crate::model::VariantAxis>>(tree, node, &path).err()
                }
                "conflicts" => {
                    deserialize_at::<Vec<crate::model::Conflict>>(tree, node, &path).err()
                }
                "gaps" => deserialize_at::<Vec<crate::model::Gap>>(tree, node, &path).err(),
                "examples" => {
                    deserialize_at::<Vec<crate::examples::Example>>(tree, node, &path).err()
                }
                "removed" => deserialize_at::<Vec<crate::model::Removed>>(tree, node, &path).err(),
                "roles" => deserialize_at::<
                    std::collections::BTreeMap<String, Vec<crate::model::RolePlace>>,
                >(tree, node, &path)
                .err(),
                "profile" => {
                    deserialize_at::<crate::command_profile::ProfileSpec>(tree, node, &path).err()
                }
                "groups" => {
                    if let NodeKind::Seq(groups) = &node.kind {
                        for (gi, group) in groups.iter().enumerate() {
                            group_errors(tree, group, &path.index(gi), &mut errors);
                        }
                    }
                    None
                }
                _ => None,
            };
            errors.extend(err);
        }
    }
    errors.sort();
    errors.dedup();
    Err(errors)
}

fn group_errors(tree: &Node, group: &Node, path: &Path, errors: &mut Vec<Diagnostic>) {
    let NodeKind::Map(entries) = &group.kind else {
        errors.extend(deserialize_at::<crate::model::Group>(tree, group, path).err());
        return;
    };
    // The group without its registers (each deserialized on its own): the registers are not
    // copied into the shell.
    let mut shell = Vec::with_capacity(entries.len());
    for (key, loc, value) in entries {
        if key == "registers"
            && let NodeKind::Seq(regs) = &value.kind
        {
            for (ri, reg) in regs.iter().enumerate() {
                let rp = path.key("registers").index(ri);
                errors.extend(deserialize_at::<crate::model::Register>(tree, reg, &rp).err());
            }
            let empty = Node {
                loc: value.loc.clone(),
                kind: NodeKind::Seq(Vec::new()),
            };
            shell.push((key.clone(), loc.clone(), empty));
        } else {
            shell.push((key.clone(), loc.clone(), value.clone()));
        }
    }
    let shell = Node {
        loc: group.loc.clone(),
        kind: NodeKind::Map(shell),
    };
    errors.extend(deserialize_at::<crate::model::Group>(tree, &shell, path).err());
}

/// Deserializes `node` (found at `base` in `tree`) and locates a failure in the tree.
fn deserialize_at<T: serde::de::DeserializeOwned>(
    tree: &Node,
    node: &Node,
    base: &Path,
) -> Result<T, Diagnostic> {
    serde_path_to_error::deserialize::<_, T>(node.to_value()).map_err(|e| {
        let mut path = base.clone();
        for seg in e.path().iter() {
            match seg {
                serde_path_to_error::Segment::Seq { index } => path = path.index(*index),
                serde_path_to_error::Segment::Map { key } => path = path.key(key),
                serde_path_to_error::Segment::Enum { .. }
                | serde_path_to_error::Segment::Unknown => {}
            }
        }
        let message = e.inner().to_string();
        // Point at an unknown key itself rather than at the mapping holding it.
        let loc = unknown_field(&message)
            .map(|k| tree.locate(&path.key(k)))
            .unwrap_or_else(|| tree.locate(&path));
        let written = tree.at(&path).map(Node::to_value);
        let message = crate::hints::explain(&message, written.as_ref());
        let shown = if path.is_root() {
            message
        } else {
            format!("{path}: {message}")
        };
        Diagnostic::new(loc, register_at(tree, &path).as_deref(), shown)
    })
}

fn unknown_field(message: &str) -> Option<&str> {
    let rest = message.strip_prefix("unknown field `")?;
    rest.split('`').next()
}

/// The id of the register a path points into, if any.
pub(crate) fn register_at(tree: &Node, path: &Path) -> Option<String> {
    let segs = path.segs();
    let pos = segs
        .iter()
        .position(|s| matches!(s, Seg::Key(k) if k == "registers"))?;
    let mut node = tree;
    for seg in &segs[..(pos + 2).min(segs.len())] {
        node = match (seg, &node.kind) {
            (Seg::Key(k), _) => node.get(k)?,
            (Seg::Index(i), NodeKind::Seq(items)) => items.get(*i)?,
            _ => return None,
        };
    }
    match &node.get("id")?.kind {
        NodeKind::Scalar(Value::String(s)) => Some(s.clone()),
        _ => None,
    }
}

fn scalar_str(node: &Node) -> Option<&str> {
    match &node.kind {
        NodeKind::Scalar(Value::String(s)) => Some(s),
        _ => None,
    }
}

fn entries(node: Node) -> Vec<(String, Loc, Node)> {
    match node.kind {
        NodeKind::Map(e) => e,
        _ => Vec::new(),
    }
}

/// Overrides `base`'s keys with `child`'s, recursing into mappings on both sides.
fn merge_deep(base: Node, child: Node) -> Node {
    match (base.kind, child.kind) {
        (NodeKind::Map(mut b), NodeKind::Map(c)) => {
            for (k, kloc, v) in c {
                match b.iter().position(|(bk, _, _)| *bk == k) {
                    Some(i) => {
                        let (_, _, old) = b.remove(i);
                        b.insert(i, (k, kloc, merge_deep(old, v)));
                    }
                    None => b.push((k, kloc, v)),
                }
            }
            Node {
                loc: child.loc,
                kind: NodeKind::Map(b),
            }
        }
        (_, kind) => Node {
            loc: child.loc,
            kind,
        },
    }
}

/// Overrides `base`'s keys with `child`'s, one level deep.
fn merge_shallow(base: Node, child: Node) -> Node {
    let mut b = entries(base);
    for (k, kloc, v) in entries(child.clone()) {
        match b.iter().position(|(bk, _, _)| *bk == k) {
            Some(i) => b[i] = (k, kloc, v),
            None => b.push((k, kloc, v)),
        }
    }
    Node {
        loc: child.loc,
        kind: NodeKind::Map(b),
    }
}

/// Merges two sequences of mappings keyed by `id`; `merge` combines items with equal ids.
fn merge_by_id(
    base: Node,
    child: Node,
    merge: &dyn Fn(Node, Node) -> Result<Node, Vec<Diagnostic>>,
) -> Result<Node, Vec<Diagnostic>> {
    let NodeKind::Seq(mut items) = base.kind else {
        return Ok(child);
    };
    let NodeKind::Seq(child_items) = child.kind else {
        return Err(vec![Diagnostic::new(child.loc, None, "expected a list")]);
    };
    for item in child_items {
        let id = item.get("id").and_then(scalar_str).map(str::to_owned);
        let existing = id.as_ref().and_then(|id| {
            items
                .iter()
                .position(|b| b.get("id").and_then(scalar_str) == Some(id.as_str()))
        });
        match existing {
            Some(i) => {
                let old = items.remove(i);
                items.insert(i, merge(old, item)?);
            }
            None => items.push(item),
        }
    }
    Ok(Node {
        loc: base.loc,
        kind: NodeKind::Seq(items),
    })
}

fn concat(base: Node, child: Node) -> Node {
    match (base.kind, child.kind) {
        (NodeKind::Seq(mut b), NodeKind::Seq(c)) => {
            b.extend(c);
            Node {
                loc: child.loc,
                kind: NodeKind::Seq(b),
            }
        }
        (_, kind) => Node {
            loc: child.loc,
            kind,
        },
    }
}

fn merge_group(base: Node, child: Node) -> Result<Node, Vec<Diagnostic>> {
    let mut b = entries(base);
    let child_loc = child.loc.clone();
    for (k, kloc, v) in entries(child) {
        let pos = b.iter().position(|(bk, _, _)| *bk == k);
        match (k.as_str(), pos) {
            ("registers", Some(i)) => {
                let (_, _, old) = b.remove(i);
                let merged = merge_by_id(old, v, &|a, c| Ok(merge_shallow(a, c)))?;
                b.insert(i, (k, kloc, merged));
            }
            (_, Some(i)) => b[i] = (k, kloc, v),
            (_, None) => b.push((k, kloc, v)),
        }
    }
    Ok(Node {
        loc: child_loc,
        kind: NodeKind::Map(b),
    })
}

/// Merges a variant map onto its base (see the module documentation).
fn merge_variant(base: Node, child: Node) -> Result<Node, Vec<Diagnostic>> {
    let child_loc = child.loc.clone();
    let mut out = entries(base);
    let mut removed: Vec<(String, Loc)> = Vec::new();
    for (key, kloc, value) in entries(child) {
        let pos = out.iter().position(|(k, _, _)| *k == key);
        let merged = match (key.as_str(), pos) {
            ("removed", _) => {
                if let NodeKind::Seq(items) = &value.kind {
                    for item in items {
                        if let Some(id) = item.get("id").and_then(scalar_str) {
                            removed.push((id.to_owned(), item.loc.clone()));
                        }
                    }
                }
                value
            }
            (_, None) => value,
            ("drive", Some(i)) => {
                let old = out[i].2.clone();
                let manuals = match (old.get("manuals"), value.get("manuals")) {
                    (Some(a), Some(b)) => Some(unite_manuals(a.clone(), b.clone())),
                    _ => None,
                };
                let mut m = merge_shallow(old, value);
                if let (Some(manuals), NodeKind::Map(e)) = (manuals, &mut m.kind)
                    && let Some(slot) = e.iter_mut().find(|(k, _, _)| k == "manuals")
                {
                    slot.2 = manuals;
                }
                m
            }
            ("protocol", Some(i)) => merge_deep(out[i].2.clone(), value),
            ("roles", Some(i)) => merge_shallow(out[i].2.clone(), value),
            ("groups", Some(i)) => merge_by_id(out[i].2.clone(), value, &merge_group)?,
            ("conflicts" | "gaps", Some(i)) => concat(out[i].2.clone(), value),
            (_, Some(_)) => value,
        };
        match pos {
            Some(i) => out[i] = (key, kloc, merged),
            None => out.push((key, kloc, merged)),
        }
    }
    let mut errors = Vec::new();
    for (id, loc) in removed {
        if !drop_register(&mut out, &id) {
            errors.push(Diagnostic::new(
                loc,
                Some(&id),
                format!("`removed` names `{id}`, which the base map does not have"),
            ));
        }
    }
    if !errors.is_empty() {
        return Err(errors);
    }
    Ok(Node {
        loc: child_loc,
        kind: NodeKind::Map(out),
    })
}

fn unite_manuals(base: Node, child: Node) -> Node {
    let NodeKind::Seq(mut items) = base.kind else {
        return child;
    };
    if let NodeKind::Seq(extra) = child.kind {
        for m in extra {
            // A manual is known by its file (cited by line) or its id (cited by page).
            let name = |n: &Node| {
                n.get("file")
                    .or_else(|| n.get("id"))
                    .and_then(scalar_str)
                    .map(str::to_owned)
            };
            let file = name(&m);
            let dup = file.is_some() && items.iter().any(|b| name(b) == file);
            if !dup {
                items.push(m);
            }
        }
    }
    Node {
        loc: child.loc,
        kind: NodeKind::Seq(items),
    }
}

fn drop_register(root: &mut [(String, Loc, Node)], id: &str) -> bool {
    let Some((_, _, groups)) = root.iter_mut().find(|(k, _, _)| k == "groups") else {
        return false;
    };
    let NodeKind::Seq(groups) = &mut groups.kind else {
        return false;
    };
    for group in groups {
        let NodeKind::Map(entries) = &mut group.kind else {
            continue;
        };
        let Some((_, _, regs)) = entries.iter_mut().find(|(k, _, _)| k == "registers") else {
            continue;
        };
        if let NodeKind::Seq(items) = &mut regs.kind {
            let before = items.len();
            items.retain(|r| r.get("id").and_then(scalar_str) != Some(id));
            if items.len() != before {
                return true;
            }
        }
    }
    false
}

/// Finds the text of a base map by drive id, for maps held in memory: `(name shown in
/// diagnostics, YAML text)`.
pub(crate) type BaseResolver<'a> = dyn Fn(&str) -> Option<(String, String)> + 'a;

/// Like [`load_str`], resolving `extends` through `base` (by drive id) instead of refusing it:
/// for maps built into a program, or a map file whose base is built in.
pub(crate) fn load_str_with(
    name: &str,
    text: &str,
    base: &BaseResolver<'_>,
) -> Result<LoadedMap, Vec<Diagnostic>> {
    let mut warnings = Vec::new();
    let tree = load_tree_str(name, text, base, &mut Vec::new(), &mut warnings)?;
    let model = deserialize(&tree)?;
    Ok(LoadedMap {
        path: PathBuf::from(name),
        model,
        tree,
        warnings,
    })
}

fn load_tree_str(
    name: &str,
    text: &str,
    base: &BaseResolver<'_>,
    chain: &mut Vec<String>,
    warnings: &mut Vec<Diagnostic>,
) -> Result<Node, Vec<Diagnostic>> {
    let file: Arc<str> = Arc::from(name);
    let parsed = source::parse_map(&file, text)?;
    warnings.extend(parsed.warnings);
    extend_tree(parsed.tree, base, chain, warnings)
}

/// Like [`load_str_with`] for a map already parsed ([`source::parse_map`]): for tools that edit
/// a map's tree before reading it (the diff's mutation test edits every value of a map).
///
/// With `cache`, the merged tree of the base map is taken from it when this cache resolved
/// the same drive id before (`base` is taken to give the same text for an id every time).
pub(crate) fn load_tree_with(
    name: &str,
    tree: Node,
    base: &BaseResolver<'_>,
    cache: Option<&TreeCache>,
) -> Result<LoadedMap, Vec<Diagnostic>> {
    let mut warnings = Vec::new();
    let tree = match cache {
        Some(cache) => extend_tree_cached(tree, base, cache, &mut warnings)?,
        None => extend_tree(tree, base, &mut Vec::new(), &mut warnings)?,
    };
    let model = deserialize(&tree)?;
    Ok(LoadedMap {
        path: PathBuf::from(name),
        model,
        tree,
        warnings,
    })
}

/// The id of the base map `tree` extends (`None` when it extends none), or why `extends` is
/// not an id.
fn extends_id(tree: &Node) -> Result<Option<(&String, &Loc)>, Vec<Diagnostic>> {
    let Some(extends) = tree.get("drive").and_then(|d| d.get("extends")) else {
        return Ok(None);
    };
    let NodeKind::Scalar(Value::String(base_id)) = &extends.kind else {
        return Err(vec![Diagnostic::new(
            extends.loc.clone(),
            None,
            "`drive.extends` must name the base drive's id",
        )]);
    };
    Ok(Some((base_id, &extends.loc)))
}

/// [`extend_tree`] for a map read on its own (no chain above it), taking the base's merged
/// tree and warnings from `cache` when the base's id was resolved through it before: exactly
/// what [`extend_tree`] would give, since the base's tree depends only on its id and `base`.
fn extend_tree_cached(
    tree: Node,
    base: &BaseResolver<'_>,
    cache: &TreeCache,
    warnings: &mut Vec<Diagnostic>,
) -> Result<Node, Vec<Diagnostic>> {
    let Some((base_id, loc)) = extends_id(&tree)? else {
        return Ok(tree);
    };
    let cached = cache.bases.borrow().get(base_id).cloned();
    let merged = match cached {
        Some(merged) => merged,
        None => {
            let Some((base_name, base_text)) = base(base_id) else {
                // Not cached: the error points at this map's `extends`.
                return Err(vec![not_found(loc, base_id)]);
            };
            cache.read.set(cache.read.get() + 1);
            let mut base_warnings = Vec::new();
            let merged = load_tree_str(
                &base_name,
                &base_text,
                base,
                &mut vec![base_id.clone()],
                &mut base_warnings,
            )
            .map(|t| (t, base_warnings));
            cache
                .bases
                .borrow_mut()
                .insert(base_id.clone(), merged.clone());
            merged
        }
    };
    let (base_tree, base_warnings) = merged?;
    warnings.extend(base_warnings);
    merge_variant(base_tree, tree)
}

fn not_found(loc: &Loc, base_id: &str) -> Diagnostic {
    Diagnostic::new(loc.clone(), None, format!("base map `{base_id}` not found"))
}

/// A parsed map merged onto its base when it `extends` one (found through `base`).
fn extend_tree(
    tree: Node,
    base: &BaseResolver<'_>,
    chain: &mut Vec<String>,
    warnings: &mut Vec<Diagnostic>,
) -> Result<Node, Vec<Diagnostic>> {
    let Some((base_id, loc)) = extends_id(&tree)? else {
        return Ok(tree);
    };
    if chain.iter().any(|c| c == base_id) || chain.len() > 16 {
        return Err(vec![Diagnostic::new(
            loc.clone(),
            None,
            format!("`extends: {base_id}` makes a cycle of variant maps"),
        )]);
    }
    let Some((base_name, base_text)) = base(base_id) else {
        return Err(vec![not_found(loc, base_id)]);
    };
    chain.push(base_id.clone());
    let base_tree = load_tree_str(&base_name, &base_text, base, chain, warnings)?;
    chain.pop();
    merge_variant(base_tree, tree)
}
