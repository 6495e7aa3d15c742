//! Names that point elsewhere resolve: scale selectors (a register, or `<register>.<field>`) and
//! references, variant options, address-alternative conditions, broadcast registers, command
//! addresses, protocol parameters.

use std::collections::BTreeSet;

use crate::diagnostic::Diagnostic;
use crate::hints::closest;
use crate::ir::{Drive, Register, SelectorRef, ValueKind};
use crate::model::{Reference, Scale, SelectedScale};
use crate::source::Path;

fn resolve<'a>(
    drive: &'a Drive,
    out: &mut Vec<Diagnostic>,
    name: &str,
    path: Path,
    register: Option<&str>,
    what: &str,
) -> Option<&'a Register> {
    let found = drive.find(name);
    if found.is_none() {
        out.push(drive.error(
            &path,
            register,
            format!("{what} `{name}` names no register of this map (by id or parameter number)"),
        ));
    }
    found
}

/// Resolves a selector name (`selected_by`, a condition's `setting`): a readable register, or a
/// field of a readable bit-field register named `<register>.<field>`.
fn selector<'a>(
    drive: &'a Drive,
    out: &mut Vec<Diagnostic>,
    name: &str,
    path: &Path,
    register: Option<&str>,
    what: &str,
) -> Option<SelectorRef<'a>> {
    if let Some(s) = drive.selector(name) {
        if !s.register.readable() {
            out.push(drive.error(path, register, format!("selector `{name}` is not readable")));
        }
        return Some(s);
    }
    let split = name
        .rsplit_once('.')
        .and_then(|(r, f)| Some((drive.find(r)?, f)));
    let message = match split {
        Some((r, _)) if r.def.fields.is_empty() => format!(
            "{what} `{name}`: register `{}` has no fields; `<register>.<field>` names a field of a bit-field register",
            r.id()
        ),
        Some((r, field)) => {
            let hint = closest(field, r.def.fields.iter().map(|f| f.id.as_str()))
                .map(|c| format!(" (did you mean `{}.{c}`?)", r.id()))
                .unwrap_or_default();
            let ids: Vec<String> = r.def.fields.iter().map(|f| format!("`{}`", f.id)).collect();
            format!(
                "{what} `{name}`: register `{}` has no field `{field}`{hint}; its fields: {}",
                r.id(),
                ids.join(", ")
            )
        }
        None => {
            let candidates = drive
                .registers
                .iter()
                .flat_map(|r| std::iter::once(r.id()).chain(r.def.param.as_deref()));
            // `stauts.decimals`: the register part misspelt, the field kept.
            let hint = match name.rsplit_once('.') {
                Some((head, field)) => closest(head, candidates).map(|c| format!("{c}.{field}")),
                None => closest(name, candidates).map(str::to_owned),
            }
            .map(|c| format!(" (did you mean `{c}`?)"))
            .unwrap_or_default();
            format!(
                "{what} `{name}` names no register of this map (by id or parameter number){hint}"
            )
        }
    };
    out.push(drive.error(path, register, message));
    None
}

/// The selector's codes in `codes` fit it: a field's width, and the values it lists.
fn codes_fit(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    name: &str,
    selector: Option<SelectorRef<'_>>,
    code: u16,
    path: &Path,
    register: Option<&str>,
) {
    let Some(s) = selector else { return };
    if code > s.max_code() {
        out.push(drive.error(
            path,
            register,
            format!(
                "selector `{name}` is a {}-bit field: code {code} does not fit (0..={})",
                s.max_code().count_ones(),
                s.max_code()
            ),
        ));
    } else if let Some(values) = s.listed()
        && !values.iter().any(|v| v.value == code)
    {
        out.push(drive.error(
            path,
            register,
            format!("selector `{name}` lists no code {code}"),
        ));
    }
}

/// A field selector becomes the generated `Settings` field `<register>_<field>`: it must not be the
/// name of another of its fields (a selector or reference register, an external quantity, a
/// variant axis).
fn settings_field_free(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    register: &Register,
    field: &crate::model::Field,
    path: &Path,
    rid: Option<&str>,
) {
    let name = format!("{}_{}", register.id(), field.id);
    let taken = drive
        .selectors()
        .into_iter()
        .chain(drive.references())
        .any(|r| r.id() == name)
        || drive.externals().iter().any(|q| q.external == name)
        || drive.variants.iter().any(|a| a.id == name);
    if taken {
        out.push(drive.error(
            path,
            rid,
            format!(
                "selector `{}.{}` would be the `Settings` field `{name}`, which another setting already names; rename the field",
                register.id(),
                field.id
            ),
        ));
    }
}

fn relative(
    drive: &Drive,
    out: &mut Vec<Diagnostic>,
    r: &Register,
    reference: &Reference,
    path: Path,
) {
    let Reference::Register(name) = reference else {
        return;
    };
    let Some(target) = resolve(drive, out, name, path.clone(), Some(r.id()), "relative_to") else {
        return;
    };
    let fixed = matches!(
        target.kind(),
        ValueKind::Quantity(Scale::Factor(_) | Scale::Ratio(_))
            | ValueKind::UnitQuantity
            | ValueKind::Word
    );
    if !fixed || !target.readable() {
        out.push(drive.error(
            &path,
            Some(r.id()),
            format!("relative_to `{name}` must be a readable register with a fixed scale"),
        ));
    }
}

/// One rule over the whole map: appends its findings.
type Rule = fn(&Drive, &mut Vec<Diagnostic>);

/// One rule over one register: appends its findings.
type RegisterRule = fn(&Drive, &Register, &mut Vec<Diagnostic>);

/// The rules, in the order their findings are reported.
const RULES: &[Rule] = &[
    variant_axes,
    registers,
    broadcast_registers,
    command_writes,
    protocol_parameters,
];

/// The rules run on each register in turn (all of one register's findings before the next's).
const REGISTER_RULES: &[RegisterRule] = &[scale, by_variant, address_alternatives];

pub(super) fn check(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for rule in RULES {
        rule(drive, out);
    }
}

/// Every variant axis has options.
fn variant_axes(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for (ai, axis) in drive.variants.iter().enumerate() {
        if axis.options.is_empty() {
            out.push(drive.error(
                &Path::root().key("variants").index(ai),
                None,
                format!("variant axis `{}` has no options", axis.id),
            ));
        }
    }
}

/// [`REGISTER_RULES`] on every register.
fn registers(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for r in &drive.registers {
        for rule in REGISTER_RULES {
            rule(drive, r, out);
        }
    }
}

/// A relative scale's `relative_to`, or a selected scale's selector and cases.
fn scale(drive: &Drive, r: &Register, out: &mut Vec<Diagnostic>) {
    match &r.def.scale {
        Some(Scale::Relative(rel)) => relative(
            drive,
            out,
            r,
            &rel.relative_to,
            r.key_path("scale").key("relative_to"),
        ),
        Some(Scale::Selected(sel)) => selected_scale(drive, r, sel, out),
        _ => {}
    }
}

/// A selected scale: its selector resolves (not to the register itself, nor to a taken
/// `Settings` field), and its cases are there, each with codes the selector has, once.
fn selected_scale(drive: &Drive, r: &Register, sel: &SelectedScale, out: &mut Vec<Diagnostic>) {
    let rid = Some(r.id());
    let sp = r.selection_path();
    let by = sp.key("selected_by");
    let selector = selector(drive, out, &sel.selected_by, &by, rid, "selected_by");
    if let Some(SelectorRef {
        register: s,
        field: Some(f),
    }) = selector
    {
        settings_field_free(drive, out, s, f, &by, rid);
    }
    if selector.is_some_and(|s| s.register.id() == r.id()) {
        out.push(drive.error(
            &by,
            rid,
            format!(
                "selected_by `{}` is this register itself: its word cannot both be the value and choose the value's scale; name the parameter that selects it",
                sel.selected_by
            ),
        ));
    }
    if sel.cases.is_empty() {
        out.push(drive.error(&sp, rid, "a selected scale needs at least one case"));
    }
    let mut seen = BTreeSet::new();
    for ci in 0..sel.cases.len() {
        selected_case(drive, r, sel, selector, ci, &mut seen, out);
    }
}

/// The `ci`th case of a selected scale: its codes (new to the scale, fitting the selector) and
/// its own `relative_to`.
fn selected_case(
    drive: &Drive,
    r: &Register,
    sel: &SelectedScale,
    selector: Option<SelectorRef<'_>>,
    ci: usize,
    seen: &mut BTreeSet<u16>,
    out: &mut Vec<Diagnostic>,
) {
    let case = &sel.cases[ci];
    let cp = r.cases_path().index(ci);
    let rid = Some(r.id());
    let wp = cp.key("when");
    if case.when.is_empty() {
        out.push(drive.error(&wp, rid, "a case needs the selector codes it applies to"));
    }
    for code in &case.when {
        if !seen.insert(*code) {
            out.push(drive.error(
                &wp,
                rid,
                format!("selector code {code} appears in two cases"),
            ));
        }
        codes_fit(drive, out, &sel.selected_by, selector, *code, &wp, rid);
    }
    if let Scale::Relative(rel) = &case.scale {
        relative(
            drive,
            out,
            r,
            &rel.relative_to,
            cp.key("scale").key("relative_to"),
        );
    }
}

/// The `by_variant` keys are variant options, all of one axis.
fn by_variant(drive: &Drive, r: &Register, out: &mut Vec<Diagnostic>) {
    let rid = Some(r.id());
    let mut axes = BTreeSet::new();
    for k in r.def.by_variant.keys() {
        match drive.variant_option(k) {
            None => out.push(drive.error(
                &r.key_path("by_variant").key(k),
                rid,
                format!("`{k}` is not a variant option of this map"),
            )),
            Some((axis, _)) => {
                axes.insert(axis.id.clone());
            }
        }
    }
    if axes.len() > 1 {
        out.push(drive.error(
            &r.key_path("by_variant"),
            rid,
            "overrides of one register must belong to one variant axis",
        ));
    }
}

/// Each address alternative's condition names one thing, and what it names resolves.
fn address_alternatives(drive: &Drive, r: &Register, out: &mut Vec<Diagnostic>) {
    let rid = Some(r.id());
    for (ai, alt) in r.def.address_alternatives.iter().enumerate() {
        let ap = r.key_path("address_alternatives").index(ai).key("when");
        let w = &alt.when;
        let n = usize::from(w.setting.is_some())
            + usize::from(w.variant.is_some())
            + usize::from(w.transport.is_some());
        if n != 1 {
            out.push(drive.error(
                &ap,
                rid,
                "a condition names exactly one of `setting`, `variant`, `transport`",
            ));
        }
        if let Some(s) = &w.setting {
            setting_condition(drive, r, s, &w.is, &ap, out);
        }
        if let Some(v) = &w.variant
            && drive.variant_option(v).is_none()
        {
            out.push(drive.error(
                &ap.key("variant"),
                rid,
                format!("`{v}` is not a variant option of this map"),
            ));
        }
    }
}

/// A setting condition (at `ap`): its selector resolves, is not the register itself, and has
/// the codes of `is`, which are there.
fn setting_condition(
    drive: &Drive,
    r: &Register,
    s: &str,
    is: &[u16],
    ap: &Path,
    out: &mut Vec<Diagnostic>,
) {
    let rid = Some(r.id());
    let found = selector(drive, out, s, &ap.key("setting"), rid, "condition setting");
    if found.is_some_and(|f| f.register.id() == r.id()) {
        out.push(drive.error(
            &ap.key("setting"),
            rid,
            format!(
                "condition setting `{s}` is this register itself: its address cannot depend on its own value"
            ),
        ));
    }
    for code in is {
        codes_fit(drive, out, s, found, *code, &ap.key("is"), rid);
    }
    if is.is_empty() {
        out.push(drive.error(ap, rid, "a setting condition needs `is: [codes]`"));
    }
}

/// The broadcast registers resolve and are writable.
fn broadcast_registers(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let Some(b) = &drive.protocol.broadcast else {
        return;
    };
    let bp = Path::root()
        .key("protocol")
        .key("broadcast")
        .key("registers");
    for (i, name) in b.registers.iter().enumerate() {
        let path = bp.index(i);
        if let Some(r) = resolve(drive, out, name, path.clone(), None, "broadcast register")
            && !r.writable()
        {
            out.push(drive.error(&path, Some(r.id()), "a broadcast register must be writable"));
        }
    }
}

/// Each command write lands on a writable (not broadcast-only) register of the map.
fn command_writes(drive: &Drive, out: &mut Vec<Diagnostic>) {
    let proto = Path::root().key("protocol");
    for (ci, c) in drive.protocol.commands.iter().enumerate() {
        for (wi, w) in c.writes.iter().enumerate() {
            let ok = drive
                .registers
                .iter()
                .any(|r| !r.broadcast && r.def.address == w.address && r.writable());
            if !ok {
                out.push(drive.error(
                    &proto.key("commands").index(ci).key("writes").index(wi).key("address"),
                    None,
                    format!("command `{}` writes {}, which no writable register of the map describes", c.id, crate::facts::manual_address(drive, w.address)),
                ));
            }
        }
    }
}

/// A protocol parameter naming a register: where it sits under `protocol`, what it is called in
/// messages, and its value.
type Parameter = (
    &'static [&'static str],
    &'static str,
    fn(&Drive) -> Option<&str>,
);

/// The protocol parameters that name a register, in the order their findings are reported.
const PARAMETERS: &[Parameter] = &[
    (
        &["slave_address", "param"],
        "slave address parameter",
        |d| d.protocol.slave_address.param.as_deref(),
    ),
    (
        &["timing", "response_delay_param"],
        "response delay parameter",
        |d| {
            d.protocol
                .timing
                .as_ref()
                .and_then(|t| t.response_delay_param.as_deref())
        },
    ),
];

/// Each of [`PARAMETERS`] that is given resolves.
fn protocol_parameters(drive: &Drive, out: &mut Vec<Diagnostic>) {
    for (keys, what, value) in PARAMETERS {
        if let Some(p) = value(drive) {
            let path = keys
                .iter()
                .fold(Path::root().key("protocol"), |path, k| path.key(k));
            resolve(drive, out, p, path, None, what);
        }
    }
}
