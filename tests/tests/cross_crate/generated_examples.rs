//! The generated modules carry their map's example frames (`<module>::examples`): one `const`
//! per example, byte for byte as the map writes them, and `ALL` in the map's order; an RTU
//! request example's CRC checks with the runtime's codec unless the map records it as wrong.

use drivemap_test_support::paths;

use drivemap_drives::{automationdirect_acn, ptlk_tds_v8, yaskawa_gpd515, yaskawa_j7, yaskawa_v7};
use drivemap_map::facts::TransportName;
use drivemap_map::facts::parse_bytes;
use drivemap_runtime::crc;

/// A generated module's `examples::ALL`.
type Frames = &'static [(&'static str, &'static [u8])];

fn map_examples(id: &str) -> Vec<(String, Vec<u8>, bool, bool)> {
    let path = paths::shipped_map(id);
    let drive = drivemap_map::Loader::new().load(&path).unwrap();
    drive
        .examples()
        .iter()
        .map(|e| {
            let bytes = parse_bytes(&e.bytes)
                .unwrap()
                .iter()
                .map(|b| b.value)
                .collect();
            (
                e.id.clone(),
                bytes,
                e.transport == TransportName::Rtu,
                e.conflict.is_some(),
            )
        })
        .collect()
}

#[test]
fn every_shipped_module_carries_its_map_s_example_frames() {
    let modules: [(&str, Frames); 5] = [
        ("yaskawa-v7", yaskawa_v7::examples::ALL),
        ("yaskawa-j7", yaskawa_j7::examples::ALL),
        ("yaskawa-gpd515", yaskawa_gpd515::examples::ALL),
        ("ptlk-tds-v8", ptlk_tds_v8::examples::ALL),
        ("automationdirect-acn", automationdirect_acn::examples::ALL),
    ];
    for (id, generated) in modules {
        let from_map = map_examples(id);
        assert_eq!(generated.len(), from_map.len(), "{id}");
        for ((name, bytes), (map_id, map_bytes, rtu, marked)) in generated.iter().zip(&from_map) {
            assert_eq!(name, map_id, "{id}");
            assert_eq!(bytes, map_bytes, "{id}: {name}");
            if *rtu && !marked {
                assert!(crc::check(bytes).is_ok(), "{id}: {name}: CRC");
            }
        }
    }
    // One by name: the V7 manual's read command (000 Table 2.2).
    assert_eq!(
        yaskawa_v7::examples::READ_STATUS_REQUEST,
        &[0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0]
    );
    // The J7 lists the 003 frames only (a variant's list replaces its base's).
    assert!(
        yaskawa_j7::examples::ALL
            .iter()
            .all(|(id, _)| id.starts_with("memobus_"))
    );
}
