//! Roles name what they may: a known role, an existing register (or, for the maximum frequency,
//! an external quantity of the map), of a fitting kind and access — a command or status role a
//! field, a setpoint a writable number register in the role's unit (or a number field of one:
//! `number_fields`), a monitor a readable one —
//! and codes the field has; two setpoint or command roles on the same register bits only where
//! the map says so (`shared_with`). Citations of roles are checked with the others
//! (`citations_present`).

use drivemap_core::roles::{Role, RoleKind};

use crate::diagnostic::Diagnostic;
use crate::ir::{Drive, Register, ValueKind};
use crate::model::{CodeRef, Field, RolePlace};
use crate::names::field_span;
use crate::source::Path;

struct Check<'a> {
    drive: &'a Drive,
    out: &'a mut Vec<Diagnostic>,
}

impl Check<'_> {
    fn error(&mut self, path: &Path, register: Option<&str>, message: String) {
        self.out.push(self.drive.error(path, register, message));
    }
}

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let mut c = Check { drive, out };
    for (id, places) in &drive.roles {
        let path = Path::root().key("roles").key(id);
        let Some(role) = Role::from_id(id) else {
            let hint = crate::hints::closest(id, Role::ALL.iter().map(|r| r.id()))
                .map(|b| format!(" (did you mean `{b}`?)"))
                .unwrap_or_default();
            let all: Vec<&str> = Role::ALL.iter().map(|r| r.id()).collect();
            c.error(
                &path,
                None,
                format!(
                    "`{id}` is not a role{hint}; the roles are {}",
                    all.join(", ")
                ),
            );
            continue;
        };
        for (i, place) in places.iter().enumerate() {
            c.place(role, place, &path.index(i));
        }
    }
    c.shared();
}

/// What a setpoint or command place writes: a register, and for a command the bits of its field.
struct Written<'a> {
    role: Role,
    place: &'a RolePlace,
    path: Path,
    register: &'a str,
    /// The field's mask, `None` for a whole register.
    mask: Option<u32>,
}

impl Written<'_> {
    fn overlaps(&self, other: &Written<'_>) -> bool {
        self.register == other.register
            && match (self.mask, other.mask) {
                (Some(a), Some(b)) => a & b != 0,
                _ => true,
            }
    }

    fn declares(&self, other: Role) -> bool {
        self.place.shared_with.as_deref() == Some(other.id())
    }
}

impl Check<'_> {
    /// Every setpoint and command place, with what it writes (places that do not resolve are
    /// reported elsewhere).
    fn written(&self) -> Vec<Written<'_>> {
        let mut out = Vec::new();
        for (id, places) in &self.drive.roles {
            let Some(role) = Role::from_id(id) else {
                continue;
            };
            if !matches!(role.kind(), RoleKind::Setpoint | RoleKind::Command) {
                continue;
            }
            for (i, place) in places.iter().enumerate() {
                let Some(r) = place.register.as_deref().and_then(|n| self.drive.find(n)) else {
                    continue;
                };
                let mask = match &place.field {
                    Some(f) => {
                        let Some((lsb, width)) = r
                            .def
                            .fields
                            .iter()
                            .find(|x| x.id == *f)
                            .and_then(field_span)
                        else {
                            continue;
                        };
                        Some(((1u32 << width) - 1) << lsb)
                    }
                    None => None,
                };
                out.push(Written {
                    role,
                    place,
                    path: Path::root().key("roles").key(id).index(i),
                    register: r.id(),
                    mask,
                });
            }
        }
        out
    }

    /// Two setpoint or command roles on the same register bits: a write of one changes the
    /// other, so the map must say so (`shared_with`); and a `shared_with` names such a role.
    fn shared(&mut self) {
        let written = self.written();
        let mut errors = Vec::new();
        for (i, a) in written.iter().enumerate() {
            for b in &written[i + 1..] {
                if a.role == b.role || a.role.kind() != b.role.kind() || !a.overlaps(b) {
                    continue;
                }
                if a.declares(b.role) || b.declares(a.role) {
                    continue;
                }
                let what = if a.mask.is_some() {
                    "bits of register"
                } else {
                    "register"
                };
                errors.push((
                    b.path.clone(),
                    b.register,
                    format!(
                        "roles `{}` and `{}` write the same {what} `{}`: a write of one changes the other. If the drive has one register for both, say so with `shared_with: {}` on this place (maps/README.md, \"Roles\")",
                        a.role.id(),
                        b.role.id(),
                        b.register,
                        a.role.id()
                    ),
                ));
            }
        }
        for w in &written {
            let Some(other_id) = w.place.shared_with.as_deref() else {
                continue;
            };
            let path = w.path.key("shared_with");
            let Some(other) = Role::from_id(other_id) else {
                let hint = crate::hints::closest(other_id, Role::ALL.iter().map(|r| r.id()))
                    .map(|b| format!(" (did you mean `{b}`?)"))
                    .unwrap_or_default();
                errors.push((
                    path,
                    w.register,
                    format!("`{other_id}` is not a role{hint}"),
                ));
                continue;
            };
            let shares = written
                .iter()
                .any(|o| o.role == other && o.role != w.role && o.overlaps(w));
            if !shares {
                errors.push((
                    path,
                    w.register,
                    format!(
                        "`shared_with: {other_id}`, but no place of `{other_id}` is on {} `{}`{}: `shared_with` names a setpoint or command role of the same kind on the same register bits",
                        if w.mask.is_some() { "the bits of register" } else { "register" },
                        w.register,
                        if other == w.role { " other than this one" } else { "" }
                    ),
                ));
            }
        }
        let errors: Vec<(Path, String, String)> = errors
            .into_iter()
            .map(|(path, register, message)| (path, register.to_owned(), message))
            .collect();
        for (path, register, message) in errors {
            self.error(&path, Some(&register), message);
        }
    }

    fn place(&mut self, role: Role, p: &RolePlace, path: &Path) {
        let id = role.id();
        if p.source.is_none() {
            self.error(
                path,
                None,
                format!("role `{id}` needs a `source`: the manual line that says so"),
            );
        }
        if let Some(reason) = &p.unknown {
            self.not_printed(role, p, reason, path);
            return;
        }
        self.transports(role, p, path);
        if p.shared_with.is_some() && !matches!(role.kind(), RoleKind::Setpoint | RoleKind::Command)
        {
            self.error(
                &path.key("shared_with"),
                None,
                format!("`shared_with` says two written roles share a register; `{id}` is read, not written"),
            );
        }
        if p.shared_with.is_some() && p.external.is_some() {
            self.error(
                &path.key("shared_with"),
                None,
                format!("role `{id}` is an external quantity: it shares no register"),
            );
        }
        let register = match (&p.register, &p.external) {
            (Some(_), Some(_)) | (None, None) => {
                self.error(
                    path,
                    None,
                    format!("role `{id}` names either a `register` or an `external` quantity"),
                );
                return;
            }
            (None, Some(name)) => {
                self.external(role, p, name, path);
                return;
            }
            (Some(name), None) => match self.drive.find(name) {
                Some(r) => r,
                None => {
                    self.error(
                        &path.key("register"),
                        None,
                        format!(
                            "role `{id}`: `{name}` names no register of this map (by id or parameter number)"
                        ),
                    );
                    return;
                }
            },
        };
        let rid = Some(register.id());
        for (at, message) in super::number_fields::check(self.drive, role, p, register, path) {
            self.error(&at, rid, message);
        }
        if !p.edge.is_level() && role.kind() != RoleKind::Command {
            self.error(
                &path.key("edge"),
                rid,
                format!("`edge` says how a command acts; `{id}` is not a command role"),
            );
        }
        match role.kind() {
            RoleKind::Command | RoleKind::Status => {
                let command = role.kind() == RoleKind::Command;
                if command && !register.writable() {
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is a command, but `{}` is not writable",
                            register.id()
                        ),
                    );
                }
                if !command && !register.readable() {
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is a status, but `{}` is not readable",
                            register.id()
                        ),
                    );
                }
                if register.table.is_bits() {
                    self.bit(role, p, register, path);
                    return;
                }
                let Some(field_id) = &p.field else {
                    if !command && p.on.is_some() {
                        // Codes of a whole register (an inverter status register: 2 stop,
                        // 3 run): the register's values.
                        self.whole_register_codes(role, p, register, path);
                        return;
                    }
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is a {} and needs the `field` of `{}` that plays it{}",
                            if command { "command" } else { "status" },
                            register.id(),
                            if command {
                                ""
                            } else {
                                " (or, for codes of the whole register, its `on` codes)"
                            }
                        ),
                    );
                    return;
                };
                let Some(field) = self.field(register, field_id, path) else {
                    return;
                };
                self.codes(role, p, register, field, path);
            }
            RoleKind::Source => self.source(role, p, register, path),
            RoleKind::Setpoint | RoleKind::Monitor => {
                if p.field.is_none() && (p.on.is_some() || p.off.is_some()) {
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is a number: it takes no `on` or `off` (those are the codes of a command or status field)"
                        ),
                    );
                }
                let setpoint = role.kind() == RoleKind::Setpoint;
                if setpoint && !register.writable() && role != Role::MaxFrequency {
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is written, but `{}` is not writable",
                            register.id()
                        ),
                    );
                }
                if (!setpoint || role == Role::MaxFrequency) && !register.readable() {
                    self.error(
                        path,
                        rid,
                        format!(
                            "role `{id}` is read, but `{}` is not readable",
                            register.id()
                        ),
                    );
                }
                match &p.field {
                    // A number field: number_fields checks it.
                    Some(field_id) => {
                        self.field(register, field_id, path);
                    }
                    None => self.number(role, register, path),
                }
            }
        }
    }

    /// A command or status role on a coil or discrete input: the bit itself, on at 1 unless
    /// `on: 0` says otherwise (and `off` the other code); no `field`.
    fn bit(&mut self, role: Role, p: &RolePlace, register: &Register, path: &Path) {
        let id = role.id();
        let rid = Some(register.id());
        if p.field.is_some() {
            self.error(
                &path.key("field"),
                rid,
                format!(
                    "role `{id}`: `{}` is a {}, one bit: it has no fields; name the register alone",
                    register.id(),
                    register.table.item()
                ),
            );
        }
        let mut codes = Vec::new();
        let on_codes = p.on.iter().flat_map(|c| c.list()).map(|c| ("on", c));
        let off_code = p.off.iter().map(|c| ("off", c));
        for (key, c) in on_codes.chain(off_code) {
            match c {
                CodeRef::Number(n) if *n <= 1 => codes.push((key, *n)),
                _ => self.error(
                    &path.key(key),
                    rid,
                    format!(
                        "role `{id}`: `{}` is a {}, whose codes are 1 (on) and 0 (off); write `{key}: 0` or `{key}: 1`",
                        register.id(),
                        register.table.item()
                    ),
                ),
            }
        }
        let on: Vec<u16> = codes.iter().filter(|c| c.0 == "on").map(|c| c.1).collect();
        if on.len() > 1 || codes.iter().any(|c| c.0 == "off" && on.contains(&c.1)) {
            self.error(
                path,
                rid,
                format!("role `{id}`: `on` and `off` of a bit are one code each, and not the same"),
            );
        }
    }

    /// A source the manual does not print: a reason, a citation, and nothing else.
    fn not_printed(&mut self, role: Role, p: &RolePlace, reason: &str, path: &Path) {
        let id = role.id();
        if role.kind() != RoleKind::Source {
            self.error(
                &path.key("unknown"),
                None,
                format!(
                    "`unknown` marks a source role the manual does not print; `{id}` is a {} role: name its register or leave the role out",
                    match role.kind() {
                        RoleKind::Command => "command",
                        RoleKind::Status => "status",
                        RoleKind::Setpoint => "setpoint",
                        RoleKind::Monitor => "monitor",
                        RoleKind::Source => "source",
                    }
                ),
            );
            return;
        }
        if reason.trim().is_empty() {
            self.error(
                &path.key("unknown"),
                None,
                format!(
                    "role `{id}`: `unknown` needs the reason the manual gives no source parameter"
                ),
            );
        }
        if p.source.is_none() {
            self.error(
                path,
                None,
                format!("role `{id}` needs a `source`: the manual line that names the parameter (or says nothing of it)"),
            );
        }
        if p.register.is_some()
            || p.field.is_some()
            || p.external.is_some()
            || p.on.is_some()
            || p.off.is_some()
            || !p.edge.is_level()
        {
            self.error(
                path,
                None,
                format!(
                    "role `{id}` is marked `unknown` (not printed): it names no `register`, `field`, `external`, `on`, `off` or `edge`"
                ),
            );
        }
    }

    /// `transports`, when given, lists transports of the map, once each.
    fn transports(&mut self, role: Role, p: &RolePlace, path: &Path) {
        let Some(list) = &p.transports else {
            return;
        };
        let map = &self.drive.protocol.transports;
        if list.is_empty() {
            self.error(
                &path.key("transports"),
                None,
                format!(
                    "role `{}`: `transports` lists no transport (leave it out for every one)",
                    role.id()
                ),
            );
        }
        for (i, t) in list.iter().enumerate() {
            if !map.contains(t) {
                self.error(
                    &path.key("transports").index(i),
                    None,
                    format!(
                        "role `{}`: transport `{}` is not among the map's `protocol.transports`",
                        role.id(),
                        t.to_string().to_lowercase()
                    ),
                );
            }
            if list[..i].contains(t) {
                self.error(
                    &path.key("transports").index(i),
                    None,
                    format!(
                        "role `{}`: transport `{}` is listed twice",
                        role.id(),
                        t.to_string().to_lowercase()
                    ),
                );
            }
        }
    }

    /// A source role names a readable parameter (a code register) and the codes with which the
    /// drive takes commands from the network, or a status field that reports it.
    fn source(&mut self, role: Role, p: &RolePlace, register: &Register, path: &Path) {
        let id = role.id();
        let rid = Some(register.id());
        if !register.readable() {
            self.error(
                path,
                rid,
                format!(
                    "role `{id}` is read before a command is sent, but `{}` is not readable",
                    register.id()
                ),
            );
        }
        if p.on.is_none() {
            self.error(
                path,
                rid,
                format!(
                    "role `{id}` needs `on`: the code(s) of `{}` with which the drive takes commands from the network",
                    register.id()
                ),
            );
        }
        if let Some(field_id) = &p.field {
            let Some(field) = self.field(register, field_id, path) else {
                return;
            };
            self.codes(role, p, register, field, path);
            return;
        }
        if !matches!(register.kind(), ValueKind::Enum(_) | ValueKind::Word)
            || register.def.pair.is_some()
        {
            self.error(
                path,
                rid,
                format!(
                    "role `{id}` reads a code: `{}` must be an enumeration or a plain word (or name the `field` that reports the source)",
                    register.id()
                ),
            );
            return;
        }
        if p.off.is_some() {
            self.error(
                &path.key("off"),
                rid,
                format!(
                    "role `{id}` on a whole parameter takes no `off`: every code but the `on` ones means another source"
                ),
            );
        }
        let values = &register.def.values;
        for (i, c) in p.on.iter().flat_map(|c| c.list()).enumerate() {
            let at = match &p.on {
                Some(crate::model::Codes::Many(_)) => path.key("on").index(i),
                _ => path.key("on"),
            };
            match c {
                CodeRef::Id(code) if !values.iter().any(|v| v.id == *code) => {
                    let listed: Vec<&str> = values.iter().map(|v| v.id.as_str()).collect();
                    self.error(
                        &at,
                        rid,
                        format!(
                            "`{}` has no code `{code}`{}",
                            register.id(),
                            if listed.is_empty() {
                                " (it lists no codes: write the number)".to_owned()
                            } else {
                                format!("; its codes are {}", listed.join(", "))
                            }
                        ),
                    );
                }
                CodeRef::Number(n)
                    if !values.is_empty() && !values.iter().any(|v| v.value == *n) =>
                {
                    self.error(
                        &at,
                        rid,
                        format!(
                            "`{}` lists no code {n}: name the network code among its `values` (with its citation)",
                            register.id()
                        ),
                    );
                }
                _ => {}
            }
        }
    }

    /// A status role on the codes of a whole register: an enumeration or plain word (not a
    /// pair), its `on` codes (and `off`, if given) among the register's values where it lists
    /// them.
    fn whole_register_codes(
        &mut self,
        role: Role,
        p: &RolePlace,
        register: &Register,
        path: &Path,
    ) {
        let id = role.id();
        let rid = Some(register.id());
        if !matches!(register.kind(), ValueKind::Enum(_) | ValueKind::Word)
            || register.def.pair.is_some()
        {
            self.error(
                path,
                rid,
                format!(
                    "role `{id}` reads codes of the whole register: `{}` must be an enumeration or a plain word (or name the `field` that plays the role)",
                    register.id()
                ),
            );
            return;
        }
        let values = &register.def.values;
        let on =
            p.on.iter()
                .flat_map(|c| c.list())
                .enumerate()
                .map(|(i, c)| {
                    let at = match &p.on {
                        Some(crate::model::Codes::Many(_)) => path.key("on").index(i),
                        _ => path.key("on"),
                    };
                    (at, c)
                });
        let off = p.off.iter().map(|c| (path.key("off"), c));
        let all: Vec<(Path, &CodeRef)> = on.chain(off).collect();
        for (at, c) in all {
            let known = match c {
                CodeRef::Id(code) => values.iter().any(|v| v.id == *code),
                CodeRef::Number(n) => values.is_empty() || values.iter().any(|v| v.value == *n),
            };
            if !known {
                let listed: Vec<String> = values
                    .iter()
                    .map(|v| format!("{} ({})", v.value, v.id))
                    .collect();
                self.error(
                    &at,
                    rid,
                    format!(
                        "`{}` has no code {}{}",
                        register.id(),
                        match c {
                            CodeRef::Id(s) => format!("`{s}`"),
                            CodeRef::Number(n) => n.to_string(),
                        },
                        if listed.is_empty() {
                            " (it lists no codes: write the number)".to_owned()
                        } else {
                            format!("; its codes are {}", listed.join(", "))
                        }
                    ),
                );
            }
        }
    }

    /// A number role names a number register in the role's unit.
    fn number(&mut self, role: Role, r: &Register, path: &Path) {
        let Some(unit) = role.unit() else {
            // The fault code: a code register or a plain word.
            if let ValueKind::Text(_) = r.kind() {
                self.error(
                    path,
                    Some(r.id()),
                    format!(
                        "role `{}` is a code; `{}` is text: no role reads text",
                        role.id(),
                        r.id()
                    ),
                );
            } else if matches!(r.kind(), ValueKind::Bits(_)) {
                self.error(
                    path,
                    Some(r.id()),
                    format!(
                        "role `{}` is a code; `{}` is a bit-field register",
                        role.id(),
                        r.id()
                    ),
                );
            }
            return;
        };
        let numeric = matches!(r.kind(), ValueKind::Quantity(_) | ValueKind::UnitQuantity);
        let got = r.def.unit.as_deref().unwrap_or("");
        if !numeric || got != unit {
            self.error(
                path,
                Some(r.id()),
                format!(
                    "role `{}` is a quantity in {unit}; `{}` is {}",
                    role.id(),
                    r.id(),
                    if numeric {
                        format!("in `{got}`")
                    } else {
                        "not a quantity with a unit".into()
                    }
                ),
            );
        }
    }

    fn external(&mut self, role: Role, p: &RolePlace, name: &str, path: &Path) {
        if role != Role::MaxFrequency {
            self.error(
                &path.key("external"),
                None,
                format!(
                    "only `max_frequency` may be an external quantity; `{}` names a register",
                    role.id()
                ),
            );
            return;
        }
        if p.field.is_some() || p.on.is_some() || p.off.is_some() || !p.edge.is_level() {
            self.error(
                path,
                None,
                "an external quantity takes no `field`, `on`, `off` or `edge`".into(),
            );
        }
        match self.drive.externals().iter().find(|q| q.external == name) {
            Some(q) if q.unit == "Hz" => {}
            Some(q) => self.error(
                &path.key("external"),
                None,
                format!("external quantity `{name}` is in `{}`, not Hz", q.unit),
            ),
            None => self.error(
                &path.key("external"),
                None,
                format!("the map has no external quantity `{name}` (a `relative_to: {{external: ..}}` of some register)"),
            ),
        }
    }

    /// `on` and `off` name codes the field has; a multi-bit command says both.
    /// The field `field_id` of `register`, or an error at the place's `field` key with the
    /// closest name as a hint.
    fn field<'r>(
        &mut self,
        register: &'r Register,
        field_id: &str,
        path: &Path,
    ) -> Option<&'r Field> {
        let found = register.def.fields.iter().find(|f| f.id == field_id);
        if found.is_none() {
            let hint =
                crate::hints::closest(field_id, register.def.fields.iter().map(|f| f.id.as_str()))
                    .map(|b| format!(" (did you mean `{b}`?)"))
                    .unwrap_or_default();
            self.error(
                &path.key("field"),
                Some(register.id()),
                format!(
                    "register `{}` has no field `{field_id}`{hint}",
                    register.id()
                ),
            );
        }
        found
    }

    fn codes(&mut self, role: Role, p: &RolePlace, r: &Register, f: &Field, path: &Path) {
        let Some((_, width)) = field_span(f) else {
            return; // bit_fields_valid reports it
        };
        let rid = Some(r.id());
        let max = (1u32 << width) - 1;
        let resolve = |c: &CodeRef, key: &str, this: &mut Self| -> Option<u16> {
            match c {
                CodeRef::Number(n) if u32::from(*n) <= max => Some(*n),
                CodeRef::Number(n) => {
                    this.error(
                        &path.key(key),
                        rid,
                        format!(
                            "code {n} does not fit field `{}.{}` ({width} bit{}, 0 ..= {max})",
                            r.id(),
                            f.id,
                            if width == 1 { "" } else { "s" }
                        ),
                    );
                    None
                }
                CodeRef::Id(id) => match f.values.iter().find(|v| v.id == *id) {
                    Some(v) => Some(v.value),
                    None => {
                        let listed: Vec<&str> = f.values.iter().map(|v| v.id.as_str()).collect();
                        this.error(
                            &path.key(key),
                            rid,
                            format!(
                                "field `{}.{}` has no code `{id}`{}",
                                r.id(),
                                f.id,
                                if listed.is_empty() {
                                    " (it lists no codes: write the number)".to_owned()
                                } else {
                                    format!("; its codes are {}", listed.join(", "))
                                }
                            ),
                        );
                        None
                    }
                },
            }
        };
        let on: Vec<Option<u16>> =
            p.on.iter()
                .flat_map(|c| c.list())
                .map(|c| resolve(c, "on", self))
                .collect();
        let off = p.off.as_ref().and_then(|c| resolve(c, "off", self));
        let command = role.kind() == RoleKind::Command;
        if width > 1 {
            if p.on.is_none() {
                self.error(
                    path,
                    rid,
                    format!(
                        "field `{}.{}` is {width} bits wide: say which code means `{}` with `on`",
                        r.id(),
                        f.id,
                        role.id()
                    ),
                );
            }
            if command && p.off.is_none() {
                self.error(
                    path,
                    rid,
                    format!(
                        "field `{}.{}` is {width} bits wide: say which code releases `{}` with `off` (the stop code, for `run`)",
                        r.id(),
                        f.id,
                        role.id()
                    ),
                );
            }
        }
        if command && on.len() > 1 {
            self.error(
                &path.key("on"),
                rid,
                format!(
                    "a command writes one code: give `{}` one `on` code",
                    role.id()
                ),
            );
        }
        if let Some(off) = off
            && on.contains(&Some(off))
        {
            self.error(
                &path.key("off"),
                rid,
                format!("code {off} is both `on` and `off`"),
            );
        }
    }
}
