//! A map's command profile (`profile:`): a drive run through a control-word state machine.
//!
//! The common profiles are written once, as data, in `map/profiles/*.yaml` (CiA 402,
//! PROFIdrive, the ABB Drives profile), each naming the public specification it follows; a map
//! names one with `standard:` and gives its control and status registers, the manual line
//! that says the drive uses it, and a citation of its own manual for every state and
//! transition (overriding what its drive does differently: a time limit, the bits it keeps). A
//! map may also write a whole profile of its own. [`resolve`] merges the two, [`check`]
//! validates the result, [`lower`] decides the plan's
//! [`CommandProfile`].

use std::collections::BTreeMap;

use drivemap_core::command_profile::{CommandProfile, Path, PathKind, ProfileState, Transition};
use serde::{Deserialize, Deserializer, Serialize};

use crate::diagnostic::Diagnostic;
use crate::ir::Drive;
use crate::source;

/// A 16-bit word as the manuals print it: a number, `0x047E`, `047Eh` or `047EH`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(transparent)]
pub struct Word(pub u16);

impl<'de> Deserialize<'de> for Word {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Word, D::Error> {
        #[derive(Deserialize)]
        #[serde(untagged)]
        enum Raw {
            N(u64),
            S(String),
        }
        let bad = |s: &str| {
            serde::de::Error::custom(format!(
                "`{}` is not a 16-bit word (write 0x047E, 047Eh or a decimal number up to 65535)",
                s.chars().take(40).collect::<String>().escape_default()
            ))
        };
        match Raw::deserialize(d)? {
            Raw::N(n) => u16::try_from(n).map(Word).map_err(|_| bad(&n.to_string())),
            Raw::S(s) => {
                let t = s.trim();
                let hex = t
                    .strip_prefix("0x")
                    .or_else(|| t.strip_prefix("0X"))
                    .or_else(|| t.strip_suffix('h'))
                    .or_else(|| t.strip_suffix('H'));
                match hex {
                    Some(h) => u16::from_str_radix(h, 16).map(Word).map_err(|_| bad(t)),
                    None => t.parse::<u16>().map(Word).map_err(|_| bad(t)),
                }
            }
        }
    }
}

/// `profile:` of a map, or a standard definition in `map/profiles/`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ProfileSpec {
    /// The standard definition the map extends (`cia402`, `profidrive`, `abb_drives`,
    /// `danfoss_fc`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub standard: Option<String>,
    /// A definition's title.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// A definition's public specification (document and section).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spec: Option<String>,
    /// The control word's register id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub control: Option<String>,
    /// The status word's register id.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub status: Option<String>,
    /// The manual line that says the drive uses the profile.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    /// The state the drive is in at power-on, with the manual line that names it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub power_on: Option<PowerOnSpec>,
    /// The states, by id.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub states: BTreeMap<String, StateSpec>,
    /// The transitions, by id.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub transitions: BTreeMap<String, TransitionSpec>,
    /// The paths, by kind (`run`, `stop`, `coast`, `quick_stop`, `reset_fault`).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub paths: BTreeMap<String, PathSpec>,
    /// The map's notes on the profile.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// `power_on: {state, source}`.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PowerOnSpec {
    /// The state's id.
    pub state: String,
    /// The manual line that names it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// A state: the status-word bits that decide it and what they show.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct StateSpec {
    /// The status-word bits that decide the state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mask: Option<Word>,
    /// What those bits show in the state.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub value: Option<Word>,
    /// The manual line that prints the state's bits.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// A transition: the control word, the bits kept, the edge bits, from and to, the time limit.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct TransitionSpec {
    /// The control word that takes the transition.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub word: Option<Word>,
    /// Bits the master keeps from its own composition (a direction bit): default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub keep: Option<Word>,
    /// Bits the drive acts on when they rise (fault acknowledge): default none.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge: Option<Word>,
    /// The states it is taken from (by id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub from: Option<Vec<String>>,
    /// The state it leads to (by id).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub to: Option<String>,
    /// How long the drive may take to show `to` (ms).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limit_ms: Option<u32>,
    /// The manual line that prints the word.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
}

/// A path: transitions in order of preference and the states that end it.
#[derive(Debug, Clone, Default, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    /// The transitions, in order of preference (by id).
    pub via: Vec<String>,
    /// The states that end the path (by id).
    pub to: Vec<String>,
}

/// The standard definitions: (id, YAML).
pub(crate) const STANDARDS: &[(&str, &str)] = &[
    ("cia402", include_str!("../profiles/cia402.yaml")),
    ("profidrive", include_str!("../profiles/profidrive.yaml")),
    ("abb_drives", include_str!("../profiles/abb_drives.yaml")),
    ("danfoss_fc", include_str!("../profiles/danfoss_fc.yaml")),
];

/// The standard definition `id`, parsed.
pub(crate) fn standard(id: &str) -> Option<ProfileSpec> {
    let (_, text) = STANDARDS.iter().find(|(k, _)| *k == id)?;
    serde_yaml::from_str(text).ok()
}

impl ProfileSpec {
    /// The profile with the standard it names merged under it: the map's entries override the
    /// definition's, key by key; an unknown standard leaves the map's own entries (`check`
    /// reports it).
    pub fn resolved(&self) -> ProfileSpec {
        resolve(self)
    }
}

/// The map's profile with the standard it names merged under it: the map's entries override
/// the definition's, key by key. An unknown standard leaves the map's own entries (`check`
/// reports it).
pub(crate) fn resolve(spec: &ProfileSpec) -> ProfileSpec {
    let Some(mut out) = spec.standard.as_deref().and_then(standard) else {
        return spec.clone();
    };
    out.standard = spec.standard.clone();
    macro_rules! over {
        ($($f:ident),*) => { $( if spec.$f.is_some() { out.$f = spec.$f.clone(); } )* };
    }
    over!(control, status, source, power_on);
    out.notes.extend(spec.notes.iter().cloned());
    for (id, s) in &spec.states {
        let e = out.states.entry(id.clone()).or_default();
        if s.mask.is_some() {
            e.mask = s.mask;
        }
        if s.value.is_some() {
            e.value = s.value;
        }
        if s.source.is_some() {
            e.source = s.source.clone();
        }
    }
    for (id, t) in &spec.transitions {
        let e = out.transitions.entry(id.clone()).or_default();
        macro_rules! tover {
            ($($f:ident),*) => { $( if t.$f.is_some() { e.$f = t.$f.clone(); } )* };
        }
        tover!(word, keep, edge, from, to, limit_ms, source);
    }
    for (id, p) in &spec.paths {
        out.paths.insert(id.clone(), p.clone());
    }
    out
}

fn index(map: &BTreeMap<String, impl Sized>, id: &str) -> Option<u8> {
    map.keys().position(|k| k == id).map(|i| i as u8)
}

/// Validates the map's profile: a known standard, existing control and status registers (one
/// word each, the control word writable and the status word readable), every state and
/// transition complete and cited, no status word that shows two states, transitions and paths
/// naming states and transitions that exist, a run path, and no stop, coast, quick stop or
/// reset path through a run transition.
pub(crate) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let Some(spec) = &drive.profile else {
        return;
    };
    let root = source::Path::root().key("profile");
    let mut err = |path: &source::Path, msg: String| out.push(drive.error(path, None, msg));
    if let Some(s) = &spec.standard
        && standard(s).is_none()
    {
        let all: Vec<&str> = STANDARDS.iter().map(|(k, _)| *k).collect();
        err(
            &root.key("standard"),
            format!(
                "`{s}` is not a standard profile; the standards are {}",
                all.join(", ")
            ),
        );
        return;
    }
    for role in ["run", "run_forward", "run_reverse", "fault_reset"] {
        if drive.roles.contains_key(role) {
            err(
                &source::Path::root().key("roles").key(role),
                format!(
                    "the drive has a command profile: its paths run, stop and reset it, so a `{role}` role would be a second way past the state machine; remove the role"
                ),
            );
        }
    }
    let p = resolve(spec);
    for (key, id, writable) in [("control", &p.control, true), ("status", &p.status, false)] {
        let Some(id) = id else {
            err(
                &root,
                format!("a profile names its `{key}` word's register"),
            );
            continue;
        };
        let Some(r) = drive.find(id) else {
            err(
                &root.key(key),
                format!("`{id}` is not a register of this map"),
            );
            continue;
        };
        let plan = drive.register_plan(r);
        let ok_access = if writable {
            plan.info.access.writable()
        } else {
            plan.info.access.readable()
        };
        if !ok_access || plan.info.width.count() != 1 {
            err(
                &root.key(key),
                format!(
                    "the {key} word `{id}` must be one {} register",
                    if writable { "writable" } else { "readable" }
                ),
            );
        }
    }
    if p.source.is_none() {
        err(
            &root,
            "a profile cites the manual line that says the drive uses it (`source`)".into(),
        );
    }
    match &p.power_on {
        None => err(
            &root,
            "a profile names its power-on state (`power_on: {state, source}`)".into(),
        ),
        Some(s) if !p.states.contains_key(&s.state) => err(
            &root.key("power_on"),
            format!("`{}` is not a state of the profile", s.state),
        ),
        Some(s) if s.source.is_none() => err(
            &root.key("power_on"),
            "cite the manual line that names the power-on state (`source`)".into(),
        ),
        _ => {}
    }
    if p.states.len() > 64 || p.transitions.len() > 64 {
        err(
            &root,
            "a profile has at most 64 states and 64 transitions".into(),
        );
        return;
    }
    let states: Vec<(&String, u16, u16)> = p
        .states
        .iter()
        .map(|(id, s)| {
            let path = root.key("states").key(id);
            if s.mask.is_none() || s.value.is_none() {
                err(&path, format!("state `{id}` needs its `mask` and `value`"));
            }
            if s.source.is_none() {
                err(
                    &path,
                    format!("cite the manual line that prints state `{id}` (`source`)"),
                );
            }
            let (m, v) = (s.mask.map_or(0, |w| w.0), s.value.map_or(0, |w| w.0));
            if v & !m != 0 {
                err(
                    &path,
                    format!("state `{id}`: value {v:#06X} has bits outside its mask {m:#06X}"),
                );
            }
            (id, m, v)
        })
        .collect();
    for (i, a) in states.iter().enumerate() {
        for b in &states[..i] {
            if (a.2 ^ b.2) & a.1 & b.1 == 0 {
                err(
                    &root.key("states").key(a.0),
                    format!(
                        "states `{}` and `{}` can show at once (a status word {:#06X} shows both): the masks must tell them apart",
                        b.0,
                        a.0,
                        a.2 | b.2
                    ),
                );
            }
        }
    }
    for (id, t) in &p.transitions {
        let path = root.key("transitions").key(id);
        if t.word.is_none() {
            err(&path, format!("transition `{id}` needs its control `word`"));
        }
        if t.source.is_none() {
            err(
                &path,
                format!("cite the manual line that prints transition `{id}` (`source`)"),
            );
        }
        for s in t.from.iter().flatten().chain(t.to.iter()) {
            if !p.states.contains_key(s) {
                err(&path, format!("`{s}` is not a state of the profile"));
            }
        }
        if t.from.as_ref().is_none_or(Vec::is_empty) || t.to.is_none() {
            err(
                &path,
                format!("transition `{id}` needs `from` (states) and `to` (a state)"),
            );
        }
        if t.limit_ms.is_none_or(|l| l == 0 || l > 600_000) {
            err(
                &path,
                format!("transition `{id}` needs a `limit_ms` between 1 and 600000"),
            );
        }
    }
    for (id, path_spec) in &p.paths {
        let path = root.key("paths").key(id);
        if PathKind::from_id(id).is_none() {
            let all: Vec<&str> = PathKind::ALL.iter().map(|k| k.id()).collect();
            err(
                &path,
                format!("`{id}` is not a path; the paths are {}", all.join(", ")),
            );
        }
        for t in &path_spec.via {
            if !p.transitions.contains_key(t) {
                err(&path, format!("`{t}` is not a transition of the profile"));
            }
        }
        for s in &path_spec.to {
            if !p.states.contains_key(s) {
                err(&path, format!("`{s}` is not a state of the profile"));
            }
        }
        if path_spec.via.is_empty() || path_spec.to.is_empty() {
            err(&path, format!("path `{id}` needs `via` and `to`"));
        }
    }
    let Some(run) = p.paths.get("run") else {
        err(&root, "a profile gives a `run` path".into());
        return;
    };
    for (id, path_spec) in &p.paths {
        if id == "run" {
            continue;
        }
        for t in &path_spec.via {
            if let Some(to) = p.transitions.get(t).and_then(|t| t.to.as_ref())
                && run.to.contains(to)
            {
                err(
                    &root.key("paths").key(id),
                    format!(
                        "path `{id}` takes `{t}`, a run transition (it leads to `{to}`, where the run path ends): a {id} never runs the drive"
                    ),
                );
            }
        }
        for s in &path_spec.to {
            if run.to.contains(s) {
                err(
                    &root.key("paths").key(id),
                    format!("path `{id}` ends in `{s}`, where the run path ends"),
                );
            }
        }
    }
}

/// The plan's command profile of a validated drive; `None` without `profile:` or when it does
/// not resolve (validation has reported it).
pub(crate) fn lower(drive: &Drive, row_of: &dyn Fn(&str) -> Option<u16>) -> Option<CommandProfile> {
    let spec = drive.profile.as_ref()?;
    let p = resolve(spec);
    let leak_str = |s: &str| -> &'static str { Box::leak(s.to_owned().into_boxed_str()) };
    let states: Vec<ProfileState> = p
        .states
        .iter()
        .map(|(id, s)| ProfileState {
            id: leak_str(id),
            mask: s.mask.map_or(0, |w| w.0),
            value: s.value.map_or(0, |w| w.0),
            source: leak_str(s.source.as_deref().unwrap_or_default()),
        })
        .collect();
    let mut transitions = Vec::new();
    for (id, t) in &p.transitions {
        let from: Option<Vec<u8>> = t
            .from
            .iter()
            .flatten()
            .map(|s| index(&p.states, s))
            .collect();
        transitions.push(Transition {
            id: leak_str(id),
            word: t.word?.0,
            keep: t.keep.map_or(0, |w| w.0),
            edge: t.edge.map_or(0, |w| w.0),
            from: Box::leak(from?.into_boxed_slice()),
            to: index(&p.states, t.to.as_deref()?)?,
            limit_ms: t.limit_ms?,
            source: leak_str(t.source.as_deref().unwrap_or_default()),
        });
    }
    let mut paths = Vec::new();
    for kind in PathKind::ALL {
        let Some(ps) = p.paths.get(kind.id()) else {
            continue;
        };
        let via: Option<Vec<u8>> = ps.via.iter().map(|t| index(&p.transitions, t)).collect();
        let to: Option<Vec<u8>> = ps.to.iter().map(|s| index(&p.states, s)).collect();
        paths.push(Path {
            kind,
            via: Box::leak(via?.into_boxed_slice()),
            to: Box::leak(to?.into_boxed_slice()),
        });
    }
    Some(CommandProfile {
        name: leak_str(p.standard.as_deref().unwrap_or("own")),
        control: row_of(p.control.as_deref()?)?,
        status: row_of(p.status.as_deref()?)?,
        states: Box::leak(states.into_boxed_slice()),
        transitions: Box::leak(transitions.into_boxed_slice()),
        paths: Box::leak(paths.into_boxed_slice()),
        power_on: index(&p.states, &p.power_on.as_ref()?.state)?,
        source: leak_str(p.source.as_deref().unwrap_or_default()),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_standard_parses_and_is_closed() {
        for (id, _) in STANDARDS {
            let p = standard(id).unwrap_or_else(|| panic!("{id} does not parse"));
            assert!(p.spec.is_some(), "{id} names its specification");
            assert!(p.paths.contains_key("run"), "{id} has a run path");
            for t in p.transitions.values() {
                for s in t.from.iter().flatten().chain(t.to.iter()) {
                    assert!(p.states.contains_key(s), "{id}: {s}");
                }
            }
            for path in p.paths.values() {
                assert!(path.via.iter().all(|t| p.transitions.contains_key(t)));
                assert!(path.to.iter().all(|s| p.states.contains_key(s)));
            }
        }
    }

    #[test]
    fn words_read_as_the_manuals_print_them() {
        let w: Vec<Word> = serde_yaml::from_str("[0x047E, 047Fh, \"000FH\", 6]").unwrap();
        assert_eq!(w, [Word(0x047E), Word(0x047F), Word(0x000F), Word(6)]);
        assert!(serde_yaml::from_str::<Word>("70000").is_err());
        assert!(serde_yaml::from_str::<Word>("0xZZ").is_err());
    }
}
