//! A variant map inherits its base and overrides it (`drive.extends`).

use drivemap_test_support::paths;

#[test]
fn variant_inherits_overrides_and_removes() {
    let child = drivemap_map::Loader::new()
        .load(&paths::fixture("crafted/maps/variants/child-drive.yaml"))
        .unwrap_or_else(|d| panic!("{d}"));
    assert_eq!(child.id(), "child-drive");
    assert_eq!(child.meta().extends.as_deref(), Some("base-drive"));
    let manuals: Vec<&str> = child.meta().manuals.iter().map(|m| m.name()).collect();
    assert_eq!(manuals, ["base.txt", "child.txt"], "manuals are united");
    // protocol merged key by key
    assert_eq!(child.protocol().function_codes.codes, [0x03, 0x10]);
    assert_eq!(child.protocol().max_read(), 16);
    assert_eq!(child.protocol().max_write(), 8, "inherited");
    let ict = child
        .protocol()
        .timing
        .as_ref()
        .unwrap()
        .inter_char_timeout
        .as_ref()
        .unwrap();
    assert_eq!((ict.ms, ict.bits), (None, Some(24)));
    // registers merged by id
    let ids: Vec<&str> = child.registers().map(|r| r.id()).collect();
    assert_eq!(
        ids,
        ["speed", "delay", "added"],
        "extra removed, added appended"
    );
    let speed = child.register("speed").unwrap();
    assert_eq!(speed.param(), Some("n01"));
    assert_eq!(speed.limits(), (Some(0.0), Some(200.0)));
    assert_eq!(speed.address(), 0x0101, "inherited address");
    assert_eq!(speed.source(), Some("child.txt:5"));
    assert_eq!(
        child.register("n01").map(|r| r.id()),
        Some("speed"),
        "lookup by the new parameter number"
    );
    // locations: inherited rows point at the base file, overrides at the child
    let delay = child.register("delay").unwrap();
    assert!(delay.location().file.ends_with("base-drive.yaml"));
    let added = child.register("added").unwrap();
    assert!(added.location().file.ends_with("child-drive.yaml"));
}

#[test]
fn removing_an_unknown_register_is_an_error() {
    let dir = std::env::temp_dir().join(format!("drivemap-variant-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        paths::fixture("crafted/maps/variants/base-drive.yaml"),
        dir.join("base-drive.yaml"),
    )
    .unwrap();
    let child = std::fs::read_to_string(paths::fixture("crafted/maps/variants/child-drive.yaml"))
        .unwrap()
        .replace("{id: extra,", "{id: no_such_register,");
    std::fs::write(dir.join("child-drive.yaml"), child).unwrap();
    let err = drivemap_map::Loader::new()
        .load(&dir.join("child-drive.yaml"))
        .unwrap_err();
    let text = err.to_string();
    assert!(
        text.contains("`removed` names `no_such_register`"),
        "{text}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A chain of `extends` (each map the variant of the one before) read with one cache: every
/// file is read and parsed once, however deep the chain (without the cache, the map at depth
/// k reads k files, and checking the directory reads n²/2), and a deep chain is walked without
/// recursion (1,000 levels on a 256 KiB stack).
#[test]
fn a_chain_of_variants_reads_each_file_once() {
    let dir = std::env::temp_dir().join(format!("drivemap-chain-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::fs::read_to_string(paths::fixture("crafted/maps/mini-drive.yaml"))
        .unwrap()
        .replace("id: mini-drive", "id: c0000");
    std::fs::write(dir.join("c0000.yaml"), base).unwrap();
    const N: usize = 1000;
    for i in 1..N {
        std::fs::write(
            dir.join(format!("c{i:04}.yaml")),
            format!(
                "drive:\n  id: c{i:04}\n  extends: c{:04}\n  vendor: Example\n  models: [MD-{i}]\n  manuals: [{{file: manual.txt, title: Example manual}}]\n",
                i - 1
            ),
        )
        .unwrap();
    }
    let files = drivemap_map::find_maps(&dir).unwrap();
    assert_eq!(files.len(), N);
    let (read, last_models) = std::thread::Builder::new()
        .stack_size(256 * 1024)
        .spawn(move || {
            let loader = drivemap_map::Loader::new().cached();
            let mut last = Vec::new();
            for f in &files {
                let d = loader.load(f).unwrap_or_else(|d| panic!("{d}"));
                assert_eq!(d.registers().len(), 17, "{}", f.display());
                last = d.meta().models.clone();
            }
            (loader.files_read(), last)
        })
        .unwrap()
        .join()
        .unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    assert_eq!(read, N, "each file of the chain is read once");
    assert_eq!(last_models, ["MD-999"]);
}

/// A cycle of `extends` is an error for every map on it, and each file is read once.
#[test]
fn a_cycle_of_variants_is_still_refused() {
    let dir = std::env::temp_dir().join(format!("drivemap-cycle-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    for (id, base) in [("a", "b"), ("b", "a")] {
        std::fs::write(
            dir.join(format!("{id}.yaml")),
            format!("drive:\n  id: {id}\n  extends: {base}\n"),
        )
        .unwrap();
    }
    let loader = drivemap_map::Loader::new().cached();
    for id in ["a", "b"] {
        let e = loader
            .load(&dir.join(format!("{id}.yaml")))
            .unwrap_err()
            .to_string();
        assert!(e.contains("makes a cycle of variant maps"), "{e}");
    }
    assert_eq!(loader.files_read(), 2);
    let _ = std::fs::remove_dir_all(&dir);
}

/// A cached loader reading many trees of one variant map (a tool editing the map) asks for
/// the base's text and parses it once, and reads every tree as an uncached loader does: the
/// same map, the same warnings, the same errors (a base not found is asked for again).
#[test]
fn a_cached_loader_parses_a_base_once_for_every_tree_it_reads() {
    let dir = paths::fixture("crafted/maps/variants");
    let text = std::fs::read_to_string(dir.join("child-drive.yaml")).unwrap();
    let asked = std::cell::Cell::new(0);
    let bases = |id: &str| {
        asked.set(asked.get() + 1);
        let path = dir.join(format!("{id}.yaml"));
        Some((
            path.display().to_string(),
            std::fs::read_to_string(path).ok()?,
        ))
    };
    let tree = drivemap_map::parse_map("child-drive.yaml", &text).unwrap();
    // An edit of the child: its `max_read` moved by one.
    let edited = drivemap_map::parse_map(
        "child-drive.yaml",
        &text.replace("max_read: 16", "max_read: 17"),
    )
    .unwrap();
    let said = |m: &drivemap_map::Map| {
        let warnings: Vec<String> = m.warnings().iter().map(ToString::to_string).collect();
        (serde_json::to_string(&m.written()).unwrap(), warnings)
    };
    let cached = drivemap_map::Loader::new().cached().bases(bases);
    let mut read = Vec::new();
    for t in [&tree, &edited, &tree] {
        let once = cached
            .load_tree("child-drive.yaml", t.clone())
            .unwrap_or_else(|d| panic!("{d}"));
        let fresh = drivemap_map::Loader::new()
            .bases(|id: &str| {
                let path = dir.join(format!("{id}.yaml"));
                Some((
                    path.display().to_string(),
                    std::fs::read_to_string(path).ok()?,
                ))
            })
            .load_tree("child-drive.yaml", t.clone())
            .unwrap_or_else(|d| panic!("{d}"));
        assert_eq!(said(&once), said(&fresh));
        assert!(once.registers().any(|r| r.id() == "delay"));
        read.push(once.protocol().max_read());
    }
    assert_eq!(read, [16, 17, 16], "each tree is read, the base shared");
    assert_eq!(asked.get(), 1, "the base's text is asked for once");
    assert_eq!(cached.files_read(), 1);

    // A base the resolver does not know is not kept: asked for (and refused) every time.
    let missing = drivemap_map::Loader::new().cached().bases(|_: &str| None);
    for _ in 0..2 {
        let e = missing
            .load_tree("child-drive.yaml", tree.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("base map `base-drive` not found"), "{e}");
    }
    // A base that extends the map back is a cycle, cached or not.
    let back = |_: &str| {
        Some((
            "base-drive.yaml".to_owned(),
            "drive:\n  id: base-drive\n  extends: child-drive\n".to_owned(),
        ))
    };
    let fresh = drivemap_map::Loader::new()
        .bases(back)
        .load_tree("child-drive.yaml", tree.clone())
        .unwrap_err()
        .to_string();
    let cached = drivemap_map::Loader::new().cached().bases(back);
    for _ in 0..2 {
        let e = cached
            .load_tree("child-drive.yaml", tree.clone())
            .unwrap_err()
            .to_string();
        assert!(e.contains("makes a cycle of variant maps"), "{e}");
        assert_eq!(e, fresh);
    }
}
