//! A variant map inherits its base and overrides it (`drive.extends`).

use std::path::Path;

use drivemap_codegen::validate::Context;

#[test]
fn variant_inherits_overrides_and_removes() {
    let child = drivemap_codegen::read_map(
        Path::new("tests/fixtures/variants/child-drive.yaml"),
        &Context::default(),
    )
    .unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(child.meta.id, "child-drive");
    assert_eq!(child.meta.extends.as_deref(), Some("base-drive"));
    let manuals: Vec<&str> = child.meta.manuals.iter().map(|m| m.name()).collect();
    assert_eq!(manuals, ["base.txt", "child.txt"], "manuals are united");
    // protocol merged key by key
    assert_eq!(child.protocol.function_codes.codes, [0x03, 0x10]);
    assert_eq!(child.protocol.max_read.value, 16);
    assert_eq!(child.protocol.max_write.value, 8, "inherited");
    let ict = child
        .protocol
        .timing
        .as_ref()
        .unwrap()
        .inter_char_timeout
        .as_ref()
        .unwrap();
    assert_eq!((ict.ms, ict.bits), (None, Some(24)));
    // registers merged by id
    let ids: Vec<&str> = child.registers.iter().map(|r| r.id()).collect();
    assert_eq!(
        ids,
        ["speed", "delay", "added"],
        "extra removed, added appended"
    );
    let speed = child.find("speed").unwrap();
    assert_eq!(speed.def.param.as_deref(), Some("n01"));
    assert_eq!((speed.def.min, speed.def.max), (Some(0.0), Some(200.0)));
    assert_eq!(speed.def.address, 0x0101, "inherited address");
    assert_eq!(speed.def.source.as_deref(), Some("child.txt:5"));
    assert_eq!(
        child.find("n01").map(|r| r.id()),
        Some("speed"),
        "lookup by the new parameter number"
    );
    // locations: inherited rows point at the base file, overrides at the child
    let delay = child.find("delay").unwrap();
    assert!(child.locate(&delay.path).file.ends_with("base-drive.yaml"));
    let added = child.find("added").unwrap();
    assert!(child.locate(&added.path).file.ends_with("child-drive.yaml"));
}

#[test]
fn removing_an_unknown_register_is_an_error() {
    let dir = std::env::temp_dir().join(format!("drivemap-variant-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        "tests/fixtures/variants/base-drive.yaml",
        dir.join("base-drive.yaml"),
    )
    .unwrap();
    let child = std::fs::read_to_string("tests/fixtures/variants/child-drive.yaml")
        .unwrap()
        .replace("{id: extra,", "{id: no_such_register,");
    std::fs::write(dir.join("child-drive.yaml"), child).unwrap();
    let err =
        drivemap_codegen::read_map(&dir.join("child-drive.yaml"), &Context::default()).unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("`removed` names `no_such_register`"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
