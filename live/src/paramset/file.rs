//! The parameter-set file: YAML, one setting per line in the map's order, a comment with each
//! setting's name and unit (JSON Schema: `docs/schema/parameter-set.schema.json`).

use std::collections::BTreeMap;

use drivemap_map::Map;
use serde::{Deserialize, Serialize};

use super::by_id;

/// The format this crate writes and reads (the `format` key of a set).
pub const FORMAT: &str = "drivemap-parameter-set/1";

/// The largest set file read (bytes): far above the largest map's settings (the ACN's 700 make
/// about 60 kB).
pub const MAX_FILE: usize = 8 << 20;

/// A drive's settings, as saved.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParameterSet {
    /// [`FORMAT`].
    pub format: String,
    /// The map's id.
    pub drive: String,
    /// The model variant the values were read under: axis id → option id (every axis of the
    /// map).
    #[serde(default)]
    pub variant: BTreeMap<String, String>,
    /// [`super::fingerprint`] of the map the set was saved with.
    pub fingerprint: String,
    /// The slave address read.
    pub slave: u8,
    /// When it was saved (RFC 3339, UTC).
    pub saved: String,
    /// The settings read, in the map's order.
    #[serde(default)]
    pub settings: Vec<SavedSetting>,
    /// The settings the drive would not read, with why.
    #[serde(default)]
    pub unread: Vec<UnreadSetting>,
}

/// One setting's value.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedSetting {
    /// The register id in the map.
    pub id: String,
    /// The manual's parameter number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
    /// The value in the manual's units: a number (`10.0`, in the register's unit), an
    /// enumeration's code number, a bit-field register's word, or an exact ratio (`"3599/60"`).
    #[serde(with = "value_text")]
    pub value: String,
    /// An enumeration code's id, when the manual lists the code.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub code: Option<String>,
}

/// A setting the drive did not give a value for.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UnreadSetting {
    /// The register id in the map.
    pub id: String,
    /// The manual's parameter number.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub param: Option<String>,
    /// Why it has no value.
    pub reason: String,
}

/// A value is a YAML number or string; kept as its text.
mod value_text {
    use serde::{Deserialize, Deserializer, Serializer};

    pub(super) fn serialize<S: Serializer>(text: &str, s: S) -> Result<S::Ok, S::Error> {
        match text.parse::<f64>() {
            Ok(v) if v.is_finite() => s.serialize_f64(v),
            _ => s.serialize_str(text),
        }
    }

    pub(super) fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<String, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Scalar {
            Int(i64),
            Float(f64),
            Text(String),
        }
        Ok(match Scalar::deserialize(d)? {
            Scalar::Int(i) => i.to_string(),
            Scalar::Float(f) => f.to_string(),
            Scalar::Text(t) => t,
        })
    }
}

/// Why a set file cannot be read.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// Not YAML of a set; the message names the line and column.
    #[error("{file}: {message}")]
    Syntax {
        /// The file, as given.
        file: String,
        /// What is wrong and where.
        message: String,
    },
    /// Another format or version.
    #[error("{file}: format {found} is not {FORMAT}, which this version of drivemap reads")]
    Format {
        /// The file, as given.
        file: String,
        /// The `format` found, quoted.
        found: String,
    },
    /// Larger than [`MAX_FILE`].
    #[error("{file}: {size} bytes is more than a parameter set ({MAX_FILE} bytes at most)")]
    TooLarge {
        /// The file, as given.
        file: String,
        /// Its size.
        size: usize,
    },
}

/// A string as a YAML double-quoted scalar (JSON's escaping is YAML's).
fn yaml_string(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            '\t' => out.push_str("\\t"),
            c if c.is_control() => out.push_str(&format!("\\u{:04x}", u32::from(c))),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// One line of a comment: control characters (line breaks) as spaces.
fn comment(text: &str) -> String {
    text.chars()
        .map(|c| if c.is_control() { ' ' } else { c })
        .collect()
}

/// A value as YAML: a number as it is, anything else quoted.
fn yaml_value(text: &str) -> String {
    let number = !text.is_empty()
        && text
            .chars()
            .all(|c| c.is_ascii_digit() || matches!(c, '-' | '.'))
        && text.parse::<f64>().is_ok_and(f64::is_finite);
    if number {
        text.to_owned()
    } else {
        yaml_string(text)
    }
}

impl ParameterSet {
    /// The set as YAML: the keys in a fixed order, one setting a line in the set's order (the
    /// map's, as [`super::save`] makes it), each followed by a comment with the setting's name
    /// and unit from `drive`.
    pub fn to_yaml(&self, drive: &Map) -> String {
        let mut out = String::new();
        out.push_str(&format!(
            "# drivemap parameter set of {} at slave {}; values in the manual's units\n",
            comment(&self.drive),
            self.slave
        ));
        out.push_str(&format!("format: {}\n", yaml_string(&self.format)));
        out.push_str(&format!("drive: {}\n", yaml_string(&self.drive)));
        let variant: Vec<String> = self
            .variant
            .iter()
            .map(|(a, o)| format!("{}: {}", yaml_string(a), yaml_string(o)))
            .collect();
        out.push_str(&format!("variant: {{{}}}\n", variant.join(", ")));
        out.push_str(&format!(
            "fingerprint: {}\n",
            yaml_string(&self.fingerprint)
        ));
        out.push_str(&format!("slave: {}\n", self.slave));
        out.push_str(&format!("saved: {}\n", yaml_string(&self.saved)));
        if self.settings.is_empty() {
            out.push_str("settings: []\n");
        } else {
            out.push_str("settings:\n");
        }
        for s in &self.settings {
            let mut line = format!("  - {{id: {}", yaml_string(&s.id));
            if let Some(p) = &s.param {
                line.push_str(&format!(", param: {}", yaml_string(p)));
            }
            line.push_str(&format!(", value: {}", yaml_value(&s.value)));
            if let Some(c) = &s.code {
                line.push_str(&format!(", code: {}", yaml_string(c)));
            }
            line.push('}');
            if let Some(r) = by_id(drive, &s.id) {
                let unit = r.plan().unit;
                let mut note = comment(r.name());
                if !unit.is_empty() {
                    note.push_str(&format!(", {}", comment(unit)));
                }
                line.push_str(&format!("   # {note}"));
            }
            out.push_str(&line);
            out.push('\n');
        }
        if self.unread.is_empty() {
            out.push_str("unread: []\n");
        } else {
            out.push_str("unread:\n");
        }
        for u in &self.unread {
            let mut line = format!("  - {{id: {}", yaml_string(&u.id));
            if let Some(p) = &u.param {
                line.push_str(&format!(", param: {}", yaml_string(p)));
            }
            line.push_str(&format!(", reason: {}}}\n", yaml_string(&u.reason)));
            out.push_str(&line);
        }
        out
    }

    /// Reads a set from YAML text; `file` names it in errors (which give line and column).
    pub fn from_yaml(file: &str, text: &str) -> Result<ParameterSet, FileError> {
        if text.len() > MAX_FILE {
            return Err(FileError::TooLarge {
                file: file.to_owned(),
                size: text.len(),
            });
        }
        let set: ParameterSet = serde_yaml::from_str(text).map_err(|e| FileError::Syntax {
            file: file.to_owned(),
            message: e.to_string(),
        })?;
        if set.format != FORMAT {
            return Err(FileError::Format {
                file: file.to_owned(),
                found: super::quoted(&set.format, 60),
            });
        }
        // Every text of the file is printed in messages and reports: short and one line.
        let mut texts: Vec<(String, &str, usize)> = vec![
            ("drive".into(), &set.drive, 100),
            ("fingerprint".into(), &set.fingerprint, 100),
            ("saved".into(), &set.saved, 100),
        ];
        for (a, o) in &set.variant {
            texts.push(("variant".into(), a, 100));
            texts.push((format!("variant {}", super::quoted(a, 40)), o, 100));
        }
        for (i, s) in set.settings.iter().enumerate() {
            let at = format!("settings[{i}]");
            texts.push((format!("{at}.id"), &s.id, 200));
            texts.push((format!("{at}.value"), &s.value, 200));
            if let Some(p) = &s.param {
                texts.push((format!("{at}.param"), p, 200));
            }
            if let Some(c) = &s.code {
                texts.push((format!("{at}.code"), c, 200));
            }
        }
        for (i, u) in set.unread.iter().enumerate() {
            texts.push((format!("unread[{i}].id"), &u.id, 200));
            texts.push((format!("unread[{i}].reason"), &u.reason, 2000));
        }
        for (at, text, max) in texts {
            if text.chars().count() > max || text.chars().any(char::is_control) {
                return Err(FileError::Syntax {
                    file: file.to_owned(),
                    message: format!(
                        "{at}: {} is not a value of a set (at most {max} characters, one line)",
                        super::quoted(text, 40)
                    ),
                });
            }
        }
        Ok(set)
    }

    /// The set as JSON (the same keys as the YAML).
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The value of setting `id`, if the set holds it.
    pub fn get(&self, id: &str) -> Option<&SavedSetting> {
        self.settings.iter().find(|s| s.id == id)
    }
}
