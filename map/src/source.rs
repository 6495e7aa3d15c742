//! YAML text to a tree that remembers where every node was written.
//!
//! `yaml_serde` resolves scalars and deserializes the schema types, but it forgets positions.
//! This module reads the same text with `saphyr-parser`'s event stream, builds a [`Node`] tree
//! whose nodes carry their [`Loc`], and hands `yaml_serde` a plain `Value` to deserialize. A
//! path into the tree ([`Path`]) turns any later finding back into `file:line:column`, also
//! after a variant map has been merged onto its base (each node keeps the file it came from).

use std::collections::{HashMap, HashSet};
use std::fmt;
use std::sync::Arc;

use saphyr_parser::{Event, Parser, ScalarStyle};
use serde_yaml::{Mapping, Value};

use crate::diagnostic::{Diagnostic, Loc};

/// A YAML node and where it was written.
#[derive(Debug, Clone)]
pub struct Node {
    /// Where the node was written.
    pub loc: Loc,
    /// What the node is.
    pub kind: NodeKind,
}

#[derive(Debug, Clone)]
/// What a YAML node holds.
pub enum NodeKind {
    /// A scalar.
    Scalar(Value),
    /// A sequence.
    Seq(Vec<Node>),
    /// Entries in document order: (key, location of the key, value).
    Map(Vec<(String, Loc, Node)>),
}

/// One step of a path into a tree.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub(crate) enum Seg {
    Key(String),
    Index(usize),
}

/// A path from the root of a map to a node (`groups[2].registers[5].scale`).
///
/// A path shares the path it extends: [`Path::key`] and [`Path::index`] add one step, and a
/// clone is a count. Validation keeps a path for every item it may report on, and reports on
/// few of them.
#[derive(Clone, Default)]
pub struct Path(Option<Arc<Step>>);

/// The last step of a path and the path before it.
struct Step {
    parent: Path,
    seg: Seg,
}

impl Path {
    /// The root of a map.
    pub fn root() -> Self {
        Path(None)
    }

    /// This path, then mapping key `key`.
    pub fn key(&self, key: &str) -> Path {
        self.then(Seg::Key(key.to_owned()))
    }

    /// This path, then sequence item `index`.
    pub fn index(&self, index: usize) -> Path {
        self.then(Seg::Index(index))
    }

    fn then(&self, seg: Seg) -> Path {
        Path(Some(Arc::new(Step {
            parent: self.clone(),
            seg,
        })))
    }

    /// Whether this is the root (no step).
    pub(crate) fn is_root(&self) -> bool {
        self.0.is_none()
    }

    /// The last step, if any.
    pub(crate) fn last(&self) -> Option<&Seg> {
        self.0.as_ref().map(|step| &step.seg)
    }

    /// The path without its last step (the root's is the root).
    pub(crate) fn parent(&self) -> Path {
        self.0
            .as_ref()
            .map_or_else(Path::root, |step| step.parent.clone())
    }

    /// The steps from the root.
    pub(crate) fn segs(&self) -> Vec<&Seg> {
        let mut segs = Vec::new();
        let mut at = self;
        while let Some(step) = &at.0 {
            segs.push(&step.seg);
            at = &step.parent;
        }
        segs.reverse();
        segs
    }
}

impl PartialEq for Path {
    fn eq(&self, other: &Self) -> bool {
        let (mut a, mut b) = (self, other);
        loop {
            match (&a.0, &b.0) {
                (None, None) => return true,
                (Some(x), Some(y)) if Arc::ptr_eq(x, y) => return true,
                (Some(x), Some(y)) if x.seg == y.seg => (a, b) = (&x.parent, &y.parent),
                _ => return false,
            }
        }
    }
}

impl Eq for Path {}

impl std::hash::Hash for Path {
    fn hash<H: std::hash::Hasher>(&self, state: &mut H) {
        self.segs().hash(state);
    }
}

impl fmt::Debug for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_tuple("Path").field(&self.segs()).finish()
    }
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, seg) in self.segs().into_iter().enumerate() {
            match seg {
                Seg::Key(k) if i == 0 => write!(f, "{k}")?,
                Seg::Key(k) => write!(f, ".{k}")?,
                Seg::Index(n) => write!(f, "[{n}]")?,
            }
        }
        Ok(())
    }
}

impl Node {
    /// The value of a mapping key, if this is a mapping that has it.
    pub fn get(&self, key: &str) -> Option<&Node> {
        match &self.kind {
            NodeKind::Map(entries) => entries.iter().find(|(k, _, _)| k == key).map(|(_, _, v)| v),
            _ => None,
        }
    }

    /// The node at `path`, if there is one.
    pub fn at(&self, path: &Path) -> Option<&Node> {
        let mut node = self;
        for seg in path.segs() {
            node = match (seg, &node.kind) {
                (Seg::Key(k), _) => node.get(k)?,
                (Seg::Index(i), NodeKind::Seq(items)) => items.get(*i)?,
                _ => return None,
            };
        }
        Some(node)
    }

    /// The best location for `path`: the key of the last mapping entry on the path, the start
    /// of the last sequence item, or the deepest node that exists.
    pub fn locate(&self, path: &Path) -> Loc {
        let mut node = self;
        let mut loc = self.loc.clone();
        for seg in path.segs() {
            match (seg, &node.kind) {
                (Seg::Key(k), NodeKind::Map(entries)) => {
                    match entries.iter().find(|(key, _, _)| key == k) {
                        Some((_, key_loc, value)) => {
                            loc = key_loc.clone();
                            node = value;
                        }
                        None => return loc,
                    }
                }
                (Seg::Index(i), NodeKind::Seq(items)) => match items.get(*i) {
                    Some(item) => {
                        loc = item.loc.clone();
                        node = item;
                    }
                    None => return loc,
                },
                _ => return loc,
            }
        }
        loc
    }

    /// The plain YAML value, for `yaml_serde` to deserialize.
    pub fn to_value(&self) -> Value {
        match &self.kind {
            NodeKind::Scalar(v) => v.clone(),
            NodeKind::Seq(items) => Value::Sequence(items.iter().map(Node::to_value).collect()),
            NodeKind::Map(entries) => {
                let mut m = Mapping::with_capacity(entries.len());
                for (k, _, v) in entries {
                    m.insert(Value::String(k.clone()), v.to_value());
                }
                Value::Mapping(m)
            }
        }
    }
}

/// The largest map file read, in bytes: 4 MiB. The largest shipped map
/// (`maps/automationdirect-acn.yaml`, 1,300 registers) is 377 KB, so this leaves room for a drive
/// ten times larger while bounding what a contributed file can make the loader hold (the tree is
/// a few times the text).
pub(crate) const MAX_MAP_BYTES: usize = 4 * 1024 * 1024;

/// The deepest nesting of collections. Shipped maps nest 8 levels; every recursive step after
/// parsing (merging a variant, `to_value`, deserializing, dropping the tree) is bounded by this.
pub(crate) const MAX_DEPTH: usize = 64;

/// The most aliases (`*name`) a map may use.
pub(crate) const MAX_ALIASES: usize = 1_000;

/// The most nodes all aliases of a map may expand to together (aliases are copied into the
/// tree, so this bounds the work and memory a "billion laughs" file can cause).
pub(crate) const MAX_ALIAS_NODES: usize = 100_000;

/// Parses YAML text into a located tree. `file` names the file in locations.
///
/// Safe for untrusted text: the size, the nesting depth and alias expansion are bounded (see the
/// constants above), nothing recurses while parsing, every step is linear in the input, and
/// exactly one YAML document is accepted.
pub(crate) fn parse(file: &Arc<str>, text: &str) -> Result<Node, Diagnostic> {
    let (tree, slot_aliases) = parse_tree(file, text)?;
    match slot_aliases.into_iter().next() {
        Some(alias) => Err(alias),
        None => Ok(tree),
    }
}

/// [`parse`], returning the YAML aliases written where an address or code goes beside the
/// tree instead of refusing them (schema 1 read them; schema 2 refuses them).
fn parse_tree(file: &Arc<str>, text: &str) -> Result<(Node, Vec<Diagnostic>), Diagnostic> {
    if text.len() > MAX_MAP_BYTES {
        return Err(too_large(file, text.len()));
    }
    let mut builder = Builder {
        file: file.clone(),
        text,
        line_starts: None,
        stack: Vec::new(),
        anchors: HashMap::new(),
        root: None,
        documents: 0,
        aliases: 0,
        alias_nodes: 0,
        slot_aliases: Vec::new(),
    };
    for event in Parser::new_from_str(text) {
        let (event, span) = event.map_err(|e| {
            let m = e.marker();
            Diagnostic::new(
                Loc::new(file.clone(), m.line(), m.col() + 1),
                None,
                format!("YAML syntax: {}", e.info()),
            )
        })?;
        let loc = Loc::new(file.clone(), span.start.line(), span.start.col() + 1);
        builder.event(event, loc)?;
    }
    let tree = builder.root.unwrap_or(Node {
        loc: Loc::new(file.clone(), 1, 1),
        kind: NodeKind::Scalar(Value::Null),
    });
    Ok((tree, builder.slot_aliases))
}

/// One map file read as the loader uses it.
#[derive(Debug, Clone)]
pub(crate) struct Parsed {
    pub tree: Node,
    /// The schema version the file is written in ([`crate::schema`]).
    pub version: u32,
    /// What reading an earlier schema version changed (the file's warning, then one per value).
    pub warnings: Vec<Diagnostic>,
    /// The numbers read as schema 1 reads them, which [`crate::schema::migrate`] rewrites.
    pub reread: Vec<crate::hex::Reread>,
    /// YAML aliases where an address or code goes, which schema 1 read and schema 2 refuses.
    pub slot_aliases: Vec<Diagnostic>,
}

/// [`parse`], then the file's schema version and the decision on every address and code
/// written without a hex marker (see [`crate::hex`]): the tree of one map file as the loader
/// uses it.
pub(crate) fn parse_map(file: &Arc<str>, text: &str) -> Result<Parsed, Vec<Diagnostic>> {
    let (mut tree, slot_aliases) = parse_tree(file, text).map_err(|d| vec![d])?;
    let version = crate::schema::version_of(&tree).map_err(|d| vec![d])?;
    if version >= 2 && !slot_aliases.is_empty() {
        return Err(slot_aliases);
    }
    let resolved = crate::hex::resolve(&mut tree, version);
    if !resolved.errors.is_empty() {
        return Err(resolved.errors);
    }
    let mut warnings: Vec<Diagnostic> = crate::schema::file_warning(file, &tree, version)
        .into_iter()
        .collect();
    warnings.extend(resolved.reread.iter().map(crate::hex::Reread::warning));
    warnings.extend(slot_aliases.iter().map(|a| {
        Diagnostic::new(
            a.loc.clone(),
            None,
            format!(
                "{}; schema 1 reads the anchored value, schema 2 refuses the alias",
                a.message
                    .replacen(": write the number itself, as the manual prints it", "", 1)
            ),
        )
    }));
    Ok(Parsed {
        tree,
        version,
        warnings,
        reread: resolved.reread,
        slot_aliases,
    })
}

/// The error for a file over [`MAX_MAP_BYTES`].
pub(crate) fn too_large(file: &Arc<str>, len: usize) -> Diagnostic {
    Diagnostic::new(
        Loc::new(file.clone(), 1, 1),
        None,
        format!(
            "map file is {len} bytes; a map may be at most {MAX_MAP_BYTES} bytes (4 MiB, ten \
             times the largest shipped map)"
        ),
    )
}

enum Frame {
    Seq {
        loc: Loc,
        anchor: usize,
        items: Vec<Node>,
        nodes: usize,
    },
    Map {
        loc: Loc,
        anchor: usize,
        entries: Vec<(String, Loc, Node)>,
        keys: HashSet<String>,
        pending_key: Option<(String, Loc)>,
        nodes: usize,
    },
}

/// An anchored node: the node, how many nodes it holds, where its anchor was written.
struct Anchored {
    node: Node,
    nodes: usize,
}

struct Builder<'t> {
    file: Arc<str>,
    text: &'t str,
    /// Byte offset of each line start, computed when an alias needs its name.
    line_starts: Option<Vec<usize>>,
    stack: Vec<Frame>,
    anchors: HashMap<usize, Anchored>,
    root: Option<Node>,
    documents: usize,
    aliases: usize,
    alias_nodes: usize,
    /// Aliases written where an address or code goes.
    slot_aliases: Vec<Diagnostic>,
}

impl Builder<'_> {
    fn event(&mut self, event: Event<'_>, loc: Loc) -> Result<(), Diagnostic> {
        match event {
            Event::DocumentStart(_) => {
                self.documents += 1;
                if self.documents > 1 {
                    return Err(Diagnostic::new(
                        loc,
                        None,
                        "a second YAML document: a map file holds exactly one",
                    ));
                }
                Ok(())
            }
            Event::Scalar(text, style, anchor, _tag) => {
                let hex = self
                    .hex_slot()
                    .and_then(|slot| crate::hex::literal(&text, slot));
                let value = if let Some(value) = hex {
                    value
                } else if self.digits_as_printed() {
                    // A Modicon reference keeps its digits: YAML would read the coil `00017`
                    // as 17 and lose the table digit.
                    Value::String(text.to_string())
                } else if style == ScalarStyle::Plain {
                    // Let yaml_serde resolve plain scalars (ints incl. 0x.., floats, bools, null).
                    serde_yaml::from_str::<Value>(&text)
                        .unwrap_or_else(|_| Value::String(text.to_string()))
                } else {
                    Value::String(text.to_string())
                };
                let node = Node {
                    loc,
                    kind: NodeKind::Scalar(value),
                };
                if anchor != 0 {
                    self.anchors.insert(
                        anchor,
                        Anchored {
                            node: node.clone(),
                            nodes: 1,
                        },
                    );
                }
                self.push(node, 1)
            }
            Event::Alias(id) => {
                // An address or code is decided from how it is written (`crate::hex`); an alias
                // copies a node resolved elsewhere, so it may not stand for one.
                let items_slot = matches!(
                    self.stack.last(),
                    Some(Frame::Map { pending_key: Some((k, _)), .. })
                        if crate::hex::Slot::of_items(k).is_some()
                );
                if self.hex_slot().is_some() || items_slot {
                    // Refused in schema 2 (`parse_map` decides once the version is known);
                    // schema 1 read the anchored value.
                    let name = self.alias_name(&loc);
                    self.slot_aliases.push(Diagnostic::new(
                        loc.clone(),
                        None,
                        format!(
                            "YAML alias `*{name}` where an address or code goes: write the \
                             number itself, as the manual prints it"
                        ),
                    ));
                }
                let Some(anchored) = self.anchors.get(&id) else {
                    return Err(Diagnostic::new(
                        loc,
                        None,
                        "YAML alias to an unknown anchor",
                    ));
                };
                let nodes = anchored.nodes;
                let anchor_loc = anchored.node.loc.clone();
                self.aliases += 1;
                self.alias_nodes = self.alias_nodes.saturating_add(nodes);
                if self.aliases > MAX_ALIASES || self.alias_nodes > MAX_ALIAS_NODES {
                    let name = self.alias_name(&loc);
                    let what = if self.aliases > MAX_ALIASES {
                        format!("a map may use at most {MAX_ALIASES} aliases")
                    } else {
                        format!(
                            "aliases may expand to at most {MAX_ALIAS_NODES} nodes in all; this \
                             one copies {nodes}"
                        )
                    };
                    return Err(Diagnostic::new(
                        loc,
                        None,
                        format!("YAML alias `*{name}` (anchor at {anchor_loc}): {what}"),
                    ));
                }
                let node = anchored.node.clone();
                self.push(node, nodes)
            }
            Event::SequenceStart(anchor, _) => {
                self.check_depth(&loc)?;
                self.stack.push(Frame::Seq {
                    loc,
                    anchor,
                    items: Vec::new(),
                    nodes: 1,
                });
                Ok(())
            }
            Event::MappingStart(anchor, _) => {
                self.check_depth(&loc)?;
                self.stack.push(Frame::Map {
                    loc,
                    anchor,
                    entries: Vec::new(),
                    keys: HashSet::new(),
                    pending_key: None,
                    nodes: 1,
                });
                Ok(())
            }
            Event::SequenceEnd | Event::MappingEnd => {
                let (node, anchor, nodes) = match self.stack.pop() {
                    Some(Frame::Seq {
                        loc,
                        anchor,
                        items,
                        nodes,
                    }) => (
                        Node {
                            loc,
                            kind: NodeKind::Seq(items),
                        },
                        anchor,
                        nodes,
                    ),
                    Some(Frame::Map {
                        loc,
                        anchor,
                        entries,
                        nodes,
                        ..
                    }) => (
                        Node {
                            loc,
                            kind: NodeKind::Map(entries),
                        },
                        anchor,
                        nodes,
                    ),
                    None => {
                        return Err(Diagnostic::new(
                            loc,
                            None,
                            "YAML: unbalanced collection end",
                        ));
                    }
                };
                if anchor != 0 {
                    self.anchors.insert(
                        anchor,
                        Anchored {
                            node: node.clone(),
                            nodes,
                        },
                    );
                }
                self.push(node, nodes)
            }
            _ => Ok(()),
        }
    }

    /// Whether the scalar about to be pushed is a register's `reference:` (a Modicon reference,
    /// kept as its printed digits; see [`crate::modicon`]).
    fn digits_as_printed(&self) -> bool {
        matches!(
            self.stack.last(),
            Some(Frame::Map {
                pending_key: Some((key, _)),
                ..
            }) if key == "reference"
        )
    }

    /// Whether the scalar about to be pushed is a value whose number the manuals print in hex
    /// (see [`crate::hex`]).
    fn hex_slot(&self) -> Option<crate::hex::Slot> {
        fn key_of(frame: Option<&Frame>) -> Option<&str> {
            match frame {
                Some(Frame::Map {
                    pending_key: Some((key, _)),
                    ..
                }) => Some(key),
                _ => None,
            }
        }
        match self.stack.last() {
            Some(Frame::Map { .. }) => key_of(self.stack.last()).and_then(crate::hex::Slot::of_key),
            Some(Frame::Seq { .. }) => {
                let below = self
                    .stack
                    .len()
                    .checked_sub(2)
                    .and_then(|i| self.stack.get(i));
                key_of(below).and_then(crate::hex::Slot::of_items)
            }
            None => None,
        }
    }

    /// Refuses a collection that would nest deeper than [`MAX_DEPTH`], before it is opened.
    fn check_depth(&self, loc: &Loc) -> Result<(), Diagnostic> {
        if self.stack.len() >= MAX_DEPTH {
            return Err(Diagnostic::new(
                loc.clone(),
                None,
                format!("YAML nests deeper than {MAX_DEPTH} levels"),
            ));
        }
        Ok(())
    }

    /// The name of the alias written at `loc` (`*name`), read back from the text.
    fn alias_name(&mut self, loc: &Loc) -> String {
        let text = self.text;
        let starts = self.line_starts.get_or_insert_with(|| {
            std::iter::once(0)
                .chain(text.match_indices('\n').map(|(i, _)| i + 1))
                .collect()
        });
        let Some(&start) = starts.get(loc.line.saturating_sub(1)) else {
            return String::from("?");
        };
        let line = text[start..].lines().next().unwrap_or("");
        let rest: String = line.chars().skip(loc.col.saturating_sub(1)).collect();
        let rest = rest.strip_prefix('*').unwrap_or(&rest);
        rest.chars()
            .take_while(|c| !c.is_whitespace() && !",[]{}".contains(*c))
            .take(100)
            .collect()
    }

    fn push(&mut self, node: Node, size: usize) -> Result<(), Diagnostic> {
        match self.stack.last_mut() {
            None => {
                self.root = Some(node);
                Ok(())
            }
            Some(Frame::Seq { items, nodes, .. }) => {
                *nodes = nodes.saturating_add(size);
                items.push(node);
                Ok(())
            }
            Some(Frame::Map {
                entries,
                keys,
                pending_key,
                nodes,
                ..
            }) => {
                *nodes = nodes.saturating_add(size);
                match pending_key.take() {
                    None => {
                        let key = match &node.kind {
                            NodeKind::Scalar(Value::String(s)) => s.clone(),
                            NodeKind::Scalar(Value::Number(n)) => n.to_string(),
                            NodeKind::Scalar(Value::Bool(b)) => b.to_string(),
                            _ => {
                                return Err(Diagnostic::new(
                                    node.loc.clone(),
                                    None,
                                    format!("mapping keys must be plain scalars in {}", self.file),
                                ));
                            }
                        };
                        if !keys.insert(key.clone()) {
                            return Err(Diagnostic::new(
                                node.loc,
                                None,
                                format!("duplicate key `{key}`"),
                            ));
                        }
                        *pending_key = Some((key, node.loc));
                    }
                    Some((key, key_loc)) => entries.push((key, key_loc, node)),
                }
                Ok(())
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locates_keys_and_items() {
        let file: Arc<str> = Arc::from("m.yaml");
        let text = "a:\n  - x: 0x10\n    y: [1, 2]\n  - x: 'q'\n";
        let root = parse(&file, text).unwrap();
        let p = Path::root().key("a").index(1).key("x");
        assert_eq!(root.locate(&p).line, 4);
        assert_eq!(root.locate(&p).col, 5);
        let y = Path::root().key("a").index(0).key("y");
        assert_eq!((root.locate(&y).line, root.locate(&y).col), (3, 5));
        let v = root.to_value();
        assert_eq!(v["a"][0]["x"].as_u64(), Some(16));
        assert_eq!(v["a"][1]["x"].as_str(), Some("q"));
    }

    #[test]
    fn syntax_error_has_a_position() {
        let file: Arc<str> = Arc::from("m.yaml");
        let err = parse(&file, "a: [1, 2\nb: 3\n").unwrap_err();
        assert!(err.loc.line >= 1);
        assert!(err.message.contains("YAML syntax"), "{}", err.message);
    }

    #[test]
    fn duplicate_keys_are_refused() {
        let file: Arc<str> = Arc::from("m.yaml");
        let err = parse(&file, "a: 1\na: 2\n").unwrap_err();
        assert_eq!(err.loc.line, 2);
    }
}
