//! YAML text to a tree that remembers where every node was written.
//!
//! `yaml_serde` resolves scalars and deserializes the schema types, but it forgets positions.
//! This module reads the same text with `saphyr-parser`'s event stream, builds a [`Node`] tree
//! whose nodes carry their [`Loc`], and hands `yaml_serde` a plain `Value` to deserialize. A
//! path into the tree ([`Path`]) turns any later finding back into `file:line:column`, also
//! after a variant map has been merged onto its base (each node keeps the file it came from).

use std::collections::HashMap;
use std::fmt;
use std::sync::Arc;

use saphyr_parser::{Event, Parser, ScalarStyle};
use serde_yaml::{Mapping, Value};

use crate::diagnostic::{Diagnostic, Loc};

/// A YAML node and where it was written.
#[derive(Debug, Clone)]
pub struct Node {
    pub loc: Loc,
    pub kind: NodeKind,
}

#[derive(Debug, Clone)]
pub enum NodeKind {
    Scalar(Value),
    Seq(Vec<Node>),
    /// Entries in document order: (key, location of the key, value).
    Map(Vec<(String, Loc, Node)>),
}

/// One step of a path into a tree.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Seg {
    Key(String),
    Index(usize),
}

/// A path from the root of a map to a node (`groups[2].registers[5].scale`).
#[derive(Debug, Clone, Default, PartialEq, Eq, Hash)]
pub struct Path(pub Vec<Seg>);

impl Path {
    pub fn root() -> Self {
        Path(Vec::new())
    }

    pub fn key(&self, key: &str) -> Path {
        let mut p = self.clone();
        p.0.push(Seg::Key(key.to_owned()));
        p
    }

    pub fn index(&self, index: usize) -> Path {
        let mut p = self.clone();
        p.0.push(Seg::Index(index));
        p
    }
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, seg) in self.0.iter().enumerate() {
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

    /// The best location for `path`: the key of the last mapping entry on the path, the start
    /// of the last sequence item, or the deepest node that exists.
    pub fn locate(&self, path: &Path) -> Loc {
        let mut node = self;
        let mut loc = self.loc.clone();
        for seg in &path.0 {
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
                let mut m = Mapping::new();
                for (k, _, v) in entries {
                    m.insert(Value::String(k.clone()), v.to_value());
                }
                Value::Mapping(m)
            }
        }
    }
}

/// Parses YAML text into a located tree. `file` names the file in locations.
pub fn parse(file: &Arc<str>, text: &str) -> Result<Node, Diagnostic> {
    let mut builder = Builder {
        file: file.clone(),
        stack: Vec::new(),
        anchors: HashMap::new(),
        root: None,
    };
    for event in Parser::new_from_str(text) {
        let (event, span) = event.map_err(|e| {
            // yaml_serde is the parser the schema is defined against; prefer its wording.
            if let Err(e) = serde_yaml::from_str::<Value>(text) {
                let (line, col) = e
                    .location()
                    .map(|l| (l.line(), l.column()))
                    .unwrap_or((1, 1));
                return Diagnostic::new(
                    Loc::new(file.clone(), line, col),
                    None,
                    format!("YAML syntax: {e}"),
                );
            }
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
    Ok(builder.root.unwrap_or(Node {
        loc: Loc::new(file.clone(), 1, 1),
        kind: NodeKind::Scalar(Value::Null),
    }))
}

enum Frame {
    Seq {
        loc: Loc,
        anchor: usize,
        items: Vec<Node>,
    },
    Map {
        loc: Loc,
        anchor: usize,
        entries: Vec<(String, Loc, Node)>,
        pending_key: Option<(String, Loc)>,
    },
}

struct Builder {
    file: Arc<str>,
    stack: Vec<Frame>,
    anchors: HashMap<usize, Node>,
    root: Option<Node>,
}

impl Builder {
    fn event(&mut self, event: Event<'_>, loc: Loc) -> Result<(), Diagnostic> {
        match event {
            Event::Scalar(text, style, anchor, _tag) => {
                let value = if style == ScalarStyle::Plain {
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
                    self.anchors.insert(anchor, node.clone());
                }
                self.push(node)
            }
            Event::Alias(id) => {
                let node = self.anchors.get(&id).cloned().ok_or_else(|| {
                    Diagnostic::new(loc.clone(), None, "YAML alias to an unknown anchor")
                })?;
                self.push(node)
            }
            Event::SequenceStart(anchor, _) => {
                self.stack.push(Frame::Seq {
                    loc,
                    anchor,
                    items: Vec::new(),
                });
                Ok(())
            }
            Event::MappingStart(anchor, _) => {
                self.stack.push(Frame::Map {
                    loc,
                    anchor,
                    entries: Vec::new(),
                    pending_key: None,
                });
                Ok(())
            }
            Event::SequenceEnd | Event::MappingEnd => {
                let (node, anchor) = match self.stack.pop() {
                    Some(Frame::Seq { loc, anchor, items }) => (
                        Node {
                            loc,
                            kind: NodeKind::Seq(items),
                        },
                        anchor,
                    ),
                    Some(Frame::Map {
                        loc,
                        anchor,
                        entries,
                        ..
                    }) => (
                        Node {
                            loc,
                            kind: NodeKind::Map(entries),
                        },
                        anchor,
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
                    self.anchors.insert(anchor, node.clone());
                }
                self.push(node)
            }
            _ => Ok(()),
        }
    }

    fn push(&mut self, node: Node) -> Result<(), Diagnostic> {
        match self.stack.last_mut() {
            None => {
                self.root = Some(node);
                Ok(())
            }
            Some(Frame::Seq { items, .. }) => {
                items.push(node);
                Ok(())
            }
            Some(Frame::Map {
                entries,
                pending_key,
                ..
            }) => {
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
                        if entries.iter().any(|(k, _, _)| *k == key) {
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
