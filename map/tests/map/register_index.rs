//! A register names its plan row by the place expansion gave it (`RegisterRef::index`): every
//! register of every map finds its own row, by id, by place or by row alike, and a register
//! that is not the drive's finds no row there (`None` by id) — never row 0.

use drivemap_test_support::paths;

use std::path::{Path, PathBuf};

use drivemap_map::Map as Drive;

fn load(path: &Path) -> Drive {
    drivemap_map::Loader::new()
        .load(path)
        .unwrap_or_else(|d| panic!("{d}"))
}

fn maps() -> Vec<Drive> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(paths::maps())
        .expect("maps/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .collect();
    files.sort();
    files.push(paths::fixture("crafted/maps/variants/child-drive.yaml"));
    assert!(files.len() > 5, "{files:?}");
    files.iter().map(|p| load(p)).collect()
}

#[test]
fn every_register_finds_its_own_row() {
    for drive in maps() {
        let plan = drive.plan();
        for (i, r) in drive.registers().enumerate() {
            assert_eq!(r.index(), i, "{}: {}", drive.id(), r.id());
            let row = r.plan();
            assert_eq!(row.info.id, r.id(), "{}", drive.id());
            assert!(std::ptr::eq(row, &plan.registers[plan.order[i]]));
            assert!(std::ptr::eq(row, &plan.registers[r.row()]));
            // By place, by row and by id, the same register.
            assert!(drive.register_at(i) == Some(r));
            assert!(drive.register_of_row(r.row()) == Some(r));
            let by_id = drive.register_by_id(r.id()).expect("by id");
            assert!(
                std::ptr::eq(row, by_id.plan()),
                "{}: {}",
                drive.id(),
                r.id()
            );
        }
        assert!(drive.register_by_id("no_such_register").is_none());
    }
}

/// A register of another map is not this map's, however it is looked up: by id it is
/// `None`, and the register itself belongs to its own map (the expanded map's lookup that
/// refuses another map's register is tested in `map/src/ir.rs`).
#[test]
fn another_maps_register_has_no_row_here() {
    let drives = maps();
    let (a, b) = (&drives[0], &drives[1]);
    let foreign = b
        .registers()
        .find(|r| a.register_by_id(r.id()).is_none())
        .expect("a register of the second map that the first lacks");
    assert!(std::ptr::eq(foreign.map(), b));
    assert_eq!(foreign.plan().info.id, foreign.id());
}
