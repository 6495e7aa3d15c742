//! A number role (setpoint or monitor: `fault_code`, `output_current`, `frequency_reference`,
//! ...) on a `field` of a register — a fault code in the status word's high byte — names a
//! field that is a number: at least 2 bits and less than the whole word (a whole word is the
//! register itself), read or written by no command, status or source role (a run bit inside a
//! "fault code" would make the code change with the run), with a `scale` where the role has a
//! unit (a field carries none). `signed` and `scale` say nothing on a whole register or a role
//! that is not a number; `edge` says how a command acts, and `edge: {unknown: ..}` needs its
//! reason. Called by `roles_valid` for each place.

use drivemap_core::roles::{Role, RoleKind};

use crate::ir::{Drive, Register};
use crate::model::{EdgeSpec, RolePlace};
use crate::names::field_span;
use crate::source::Path;

/// The errors of place `p` of `role` on `register` (a resolved register), as (where, message).
pub(super) fn check(
    drive: &Drive,
    role: Role,
    p: &RolePlace,
    register: &Register,
    path: &Path,
) -> Vec<(Path, String)> {
    let mut out = Vec::new();
    let id = role.id();
    let number = matches!(role.kind(), RoleKind::Setpoint | RoleKind::Monitor);
    if let EdgeSpec::Unknown(u) = &p.edge
        && u.unknown.trim().is_empty()
    {
        out.push((
            path.key("edge").key("unknown"),
            format!("role `{id}`: `edge: {{unknown: ..}}` needs the reason the manual does not print whether the drive acts on the edge or the level"),
        ));
    }
    if !number || p.field.is_none() {
        for (key, given) in [("signed", p.signed), ("scale", p.scale.is_some())] {
            if given {
                out.push((
                    path.key(key),
                    if number {
                        format!("`{key}` describes a number role on a `field`; `{id}` names the whole register `{}`, whose own `signed` and `scale` apply", register.id())
                    } else {
                        format!("`{key}` describes a number role on a `field`; `{id}` is not a number role")
                    },
                ));
            }
        }
        return out;
    }
    let Some(field_id) = p.field.as_deref() else {
        return out;
    };
    // A missing field is reported by `roles_valid` with a hint.
    let Some(field) = register.def.fields.iter().find(|f| f.id == field_id) else {
        return out;
    };
    let Some((lsb, width)) = field_span(field) else {
        return out; // bit_fields_valid reports it
    };
    let at = path.key("field");
    let rid = register.id();
    if width < 2 {
        out.push((
            at.clone(),
            format!("role `{id}` is a number; field `{rid}.{field_id}` is one bit, a flag: name a field of at least 2 bits (a status role reads a flag)"),
        ));
    }
    if width >= 16 {
        out.push((
            at.clone(),
            format!("field `{rid}.{field_id}` is the whole 16-bit word: name the register `{rid}` without `field` (and give it `signed` and `scale` there)"),
        ));
    }
    if p.signed && width < 2 {
        out.push((
            path.key("signed"),
            format!(
                "a signed field needs a sign bit and a value bit; `{rid}.{field_id}` is {width} bit"
            ),
        ));
    }
    if p.on.is_some() || p.off.is_some() || !p.edge.is_level() {
        out.push((
            path.clone(),
            format!("role `{id}` is a number: it takes no `on`, `off` or `edge` (those are the codes of a command or status field)"),
        ));
    }
    match (role.unit(), p.scale) {
        (Some(unit), None) => out.push((
            path.clone(),
            format!("role `{id}` is a quantity in {unit}, and a field has no unit: give `scale`, one count of `{rid}.{field_id}` in {unit}, as the manual prints it"),
        )),
        (_, Some(s)) if !(s.is_finite() && s > 0.0) => out.push((
            path.key("scale"),
            format!("`scale` is one count in the role's unit: a positive number, not {s}"),
        )),
        (_, Some(s)) if drivemap_core::scale::Decimal::from_f64(s).is_none_or(|d| d.exponent > 9) => {
            out.push((
                path.key("scale"),
                format!("`scale` {s} is not a decimal of at most 9 places"),
            ))
        }
        _ => {}
    }
    // The bits of the field must be read or written by no command, status or source role.
    let mask = (((1u32 << width) - 1) << lsb) as u16;
    let mut others: Vec<String> = Vec::new();
    for (other_id, places) in &drive.roles {
        let Some(other) = Role::from_id(other_id) else {
            continue;
        };
        if matches!(other.kind(), RoleKind::Setpoint | RoleKind::Monitor) {
            continue;
        }
        for q in places {
            let same_register = q
                .register
                .as_deref()
                .and_then(|n| drive.find(n))
                .is_some_and(|r| std::ptr::eq(r, register));
            if !same_register {
                continue;
            }
            let other_mask = match q.field.as_deref() {
                None => u16::MAX,
                Some(f) => register
                    .def
                    .fields
                    .iter()
                    .find(|x| x.id == f)
                    .and_then(field_span)
                    .map_or(0, |(l, w)| (((1u32 << w) - 1) << l) as u16),
            };
            let kind = match other.kind() {
                RoleKind::Command => "command",
                RoleKind::Status => "status",
                _ => "source",
            };
            let named = format!("{kind} role `{other_id}`");
            if other_mask & mask != 0 && !others.contains(&named) {
                others.push(named);
            }
        }
    }
    if !others.is_empty() {
        out.push((
            at,
            format!("field `{rid}.{field_id}` holds bits of the {}: a number role cannot be read from (or written to) a command, status or source field; name the field that holds the number alone", others.join(", ")),
        ));
    }
    out
}
