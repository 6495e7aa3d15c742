//! A register names its plan row by the place expansion gave it (`Register::index`): every
//! register of every map finds its own row, by id or by place alike, and a register that is
//! not the drive's finds no row at all (a panic naming it, or `None` by id) — never row 0.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;

use drivemap_map::Map as Drive;

fn load(path: &str) -> Drive {
    drivemap_map::Loader::new()
        .load(Path::new(path))
        .unwrap_or_else(|d| panic!("{d}"))
}

fn maps() -> Vec<Drive> {
    let mut paths: Vec<String> = std::fs::read_dir("../maps")
        .expect("maps/")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "yaml"))
        .map(|p| p.display().to_string())
        .collect();
    paths.sort();
    paths.push("tests/fixtures/variants/child-drive.yaml".into());
    assert!(paths.len() > 5, "{paths:?}");
    paths.iter().map(|p| load(p)).collect()
}

#[test]
fn every_register_finds_its_own_row() {
    for drive in maps() {
        let plan = drive.plan();
        for (i, r) in drive.registers().enumerate() {
            assert_eq!(r.index(), i, "{}: {}", drive.id(), r.id());
            assert_eq!(r.ir().index.get(), i);
            let row = r.plan();
            assert!(std::ptr::eq(row, drive.ir().register_plan(r.ir())));
            assert_eq!(row.info.id, r.id(), "{}", drive.id());
            assert!(std::ptr::eq(row, &plan.registers[plan.order[i]]));
            let by_id = drive.ir().plan_of(r.id()).expect("by id");
            assert!(std::ptr::eq(row, by_id), "{}: {}", drive.id(), r.id());
            // A copy of the register is still this drive's register.
            assert!(std::ptr::eq(drive.ir().register_plan(&r.ir().clone()), row));
        }
        assert!(drive.ir().plan_of("no_such_register").is_none());
        assert!(drive.register_by_id("no_such_register").is_none());
    }
}

/// The old lookup fell back to row 0 for a register it could not place; now a register of
/// another map is refused by name, and looking it up by id answers `None`.
#[test]
fn another_maps_register_has_no_row_here() {
    let drives = maps();
    let (a, b) = (&drives[0], &drives[1]);
    let foreign = b
        .registers()
        .find(|r| a.register_by_id(r.id()).is_none())
        .expect("a register of the second map that the first lacks");
    let caught = catch_unwind(AssertUnwindSafe(|| {
        a.ir().register_plan(foreign.ir()).info.id
    }));
    let message = match caught {
        Ok(id) => panic!("{} answered row {id} for {}", a.id(), foreign.id()),
        Err(e) => e.downcast_ref::<String>().cloned().unwrap_or_default(),
    };
    assert!(
        message.contains(foreign.id()) && message.contains(a.id()),
        "{message}"
    );
}
