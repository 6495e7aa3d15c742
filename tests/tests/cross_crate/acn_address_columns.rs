//! Cross-check of the ACN address columns (004_c5cbf92472673495.txt:1121-1553 and the area tables
//! at 632-1091). Every register of `maps/automationdirect-acn.yaml` that carries the note
//! `printed RTU 4xxxx, TCP 4xxxx` (the decimals exactly as the manual prints them) is checked
//! against the rule the manual follows, RTU = 40000 + hex and TCP = 40001 + hex. Parameter-table
//! registers are also checked against the table's numbering (group base + parameter number).
//! A register that disagrees must record it as a conflict `Address columns of <param>` whose
//! `chosen` starts with the address the map uses; the test lists every disagreement that is not
//! recorded, and every recorded one that no longer disagrees.

use drivemap_test_support::paths;

use drivemap_map::{Tree, TreeKind};

/// The map file as written (blocks not expanded): what these tests read of it.
struct MapFile {
    groups: Vec<Group>,
}

struct Group {
    id: String,
    registers: Vec<Register>,
}

struct Register {
    id: String,
    param: Option<String>,
    address: u16,
    notes: Vec<String>,
    repeat: Option<Repeat>,
    conflicts: Vec<Conflict>,
}

struct Repeat {
    count: u16,
}

struct Conflict {
    topic: String,
    chosen: String,
    readings: Vec<Reading>,
}

struct Reading {
    says: String,
}

fn items(node: Option<&Tree>) -> &[Tree] {
    match node.map(|n| &n.kind) {
        Some(TreeKind::Seq(items)) => items,
        _ => &[],
    }
}

fn text(node: Option<&Tree>) -> Option<String> {
    node.and_then(|n| n.to_value().as_str().map(str::to_owned))
}

fn number(node: Option<&Tree>) -> Option<u64> {
    node.and_then(|n| n.to_value().as_u64())
}

fn map() -> MapFile {
    let path = paths::shipped_map("automationdirect-acn");
    let name = path.display().to_string();
    let yaml = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let tree = drivemap_map::parse_map(&name, &yaml)
        .unwrap_or_else(|errors| panic!("{name} does not load: {errors}"));
    let register = |r: &Tree| Register {
        id: text(r.get("id")).expect("a register id"),
        param: text(r.get("param")),
        address: number(r.get("address"))
            .and_then(|a| u16::try_from(a).ok())
            .expect("a register address"),
        notes: items(r.get("notes"))
            .iter()
            .filter_map(|n| text(Some(n)))
            .collect(),
        repeat: r.get("repeat").map(|rep| Repeat {
            count: number(rep.get("count"))
                .and_then(|c| u16::try_from(c).ok())
                .unwrap_or(1),
        }),
        conflicts: items(r.get("conflicts"))
            .iter()
            .map(|c| Conflict {
                topic: text(c.get("topic")).unwrap_or_default(),
                chosen: text(c.get("chosen")).unwrap_or_default(),
                readings: items(c.get("readings"))
                    .iter()
                    .map(|rd| Reading {
                        says: text(rd.get("says")).unwrap_or_default(),
                    })
                    .collect(),
            })
            .collect(),
    };
    MapFile {
        groups: items(tree.get("groups"))
            .iter()
            .map(|g| Group {
                id: text(g.get("id")).expect("a group id"),
                registers: items(g.get("registers")).iter().map(register).collect(),
            })
            .collect(),
    }
}

/// The printed decimals from a register's notes.
fn printed(r: &Register) -> Option<(u32, u32)> {
    r.notes.iter().find_map(|n| {
        let rest = n.strip_prefix("printed RTU ")?;
        let (rtu, tcp) = rest.split_once(", TCP ")?;
        Some((rtu.parse().ok()?, tcp.parse().ok()?))
    })
}

fn address_conflict(r: &Register) -> Option<&Conflict> {
    r.conflicts
        .iter()
        .find(|c| c.topic.starts_with("Address columns"))
}

/// Base address of a parameter group by its prefix (Total memory map, lines 421-430, and the
/// address table for AO, US, UF).
fn group_base(prefix: &str) -> Option<u16> {
    Some(match prefix {
        "dr" => 0x1100,
        "bA" => 0x1200,
        "Ad" => 0x1300,
        "Cn" => 0x1400,
        "In" => 0x1500,
        "OU" => 0x1600,
        "CM" => 0x1700,
        "AP" => 0x1800,
        "AO" => 0x1A00,
        "Pr" => 0x1B00,
        "M2" => 0x1C00,
        "US" => 0x1D00,
        "UF" => 0x1E00,
        _ => return None,
    })
}

/// The address the table's numbering gives a parameter (`CM.05` → 0x1705).
fn numbered(param: &str) -> Option<u16> {
    let (prefix, number) = param.split_once('.')?;
    Some(group_base(prefix)? + number.parse::<u16>().ok()?)
}

#[test]
fn address_columns_agree_or_are_recorded() {
    let map = map();
    let mut unrecorded = Vec::new();
    let mut stale = Vec::new();
    let mut checked = 0;
    for group in &map.groups {
        let parameter_table = group.id.starts_with("param_") || group.id == "keypad";
        for r in &group.registers {
            if r.repeat.is_some() {
                continue;
            }
            let hex = u32::from(r.address);
            let mut problems = Vec::new();
            match printed(r) {
                Some((rtu, tcp)) => {
                    checked += 1;
                    if rtu != 40000 + hex {
                        problems.push(format!("RTU {rtu} != 40000 + {hex:#06X} = {}", 40000 + hex));
                    }
                    if tcp != 40001 + hex {
                        problems.push(format!("TCP {tcp} != 40001 + {hex:#06X} = {}", 40001 + hex));
                    }
                }
                None if parameter_table => {
                    problems.push("no `printed RTU .., TCP ..` note".to_string());
                }
                None => {}
            }
            if group.id.starts_with("param_") {
                let param = r.param.as_deref().unwrap_or("");
                match numbered(param) {
                    Some(a) if a != r.address => {
                        problems.push(format!("{param} numbers to {a:#06X}"));
                    }
                    Some(_) => {}
                    None => problems.push(format!("parameter number {param:?} not understood")),
                }
            }
            let conflict = address_conflict(r);
            match (problems.is_empty(), conflict) {
                (false, None) => {
                    unrecorded.push(format!(
                        "{} ({:#06X}): {}",
                        r.id,
                        r.address,
                        problems.join("; ")
                    ));
                }
                (false, Some(c)) => {
                    let chosen = format!("0x{:04X}", r.address);
                    assert!(
                        c.chosen.starts_with(&chosen),
                        "{}: conflict chooses {:?} but the map uses {chosen}",
                        r.id,
                        c.chosen
                    );
                    assert!(
                        c.readings.len() >= 2,
                        "{}: conflict needs both readings",
                        r.id
                    );
                }
                (true, Some(c)) => {
                    // Recorded although the decimals and numbering agree: allowed only when the
                    // printed hex cell is what disagreed (kept in the readings).
                    if !c
                        .readings
                        .iter()
                        .any(|rd| rd.says.contains("HEX") || rd.says.contains("hex"))
                    {
                        stale.push(format!("{} ({:#06X}): {}", r.id, r.address, c.topic));
                    }
                }
                (true, None) => {}
            }
        }
    }
    assert!(
        checked >= 740,
        "only {checked} registers carry printed decimals"
    );
    assert!(
        unrecorded.is_empty(),
        "address column disagreements not recorded as conflicts:\n{}",
        unrecorded.join("\n")
    );
    assert!(
        stale.is_empty(),
        "address conflicts with nothing to disagree:\n{}",
        stale.join("\n")
    );
}

#[test]
fn the_known_disagreements_are_recorded() {
    // Rows where the manual's own columns disagree (see docs/coverage/automationdirect-acn.md).
    let expected = [
        ("dr.10", 0x110A),
        ("dr.89", 0x1159),
        ("dr.91", 0x115B),
        ("bA.43", 0x122B),
        ("bA.46", 0x122E),
        ("Cn.12", 0x140C),
        ("Cn.13", 0x140D),
        ("Cn.15", 0x140F),
        ("Cn.16", 0x1410),
        ("Cn.43", 0x142B),
        ("Cn.91", 0x145B),
        ("In.11", 0x150B),
        ("CM.91", 0x175B),
        ("CM.95", 0x1760),
        ("AP.02", 0x1802),
        ("Pr.73", 0x1B49),
        ("Pr.74", 0x1B4A),
        ("Pr.75", 0x1B4B),
    ];
    let map = map();
    let recorded: Vec<(String, u16)> = map
        .groups
        .iter()
        .flat_map(|g| g.registers.iter())
        .filter(|r| address_conflict(r).is_some())
        .map(|r| (r.param.clone().unwrap_or_default(), r.address))
        .collect();
    let expected: Vec<(String, u16)> = expected.iter().map(|(p, a)| (p.to_string(), *a)).collect();
    assert_eq!(recorded, expected);
}

#[test]
fn parameter_addresses_are_unique() {
    let map = map();
    let mut seen = std::collections::BTreeMap::new();
    for r in map.groups.iter().flat_map(|g| g.registers.iter()) {
        let count = r.repeat.as_ref().map_or(1, |rep| rep.count);
        for i in 0..count {
            let a = r.address + i;
            if let Some(other) = seen.insert(a, r.id.clone()) {
                panic!("{a:#06X} used by {other} and {}", r.id);
            }
        }
    }
    assert_eq!(seen.len(), 762);
}
