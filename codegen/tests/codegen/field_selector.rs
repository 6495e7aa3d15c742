//! A scale selected by a field of another register (`selected_by: <register>.<field>`): the
//! fixture's two current monitors take their decimals from the high byte of status word 0010h.

use drivemap_test_support::paths;

use drivemap_codegen::generate::{Options, drive_module};
use drivemap_core::plan::{Conversion, SettingsView};
use drivemap_core::scale::ValueError;
use drivemap_map::MapPlan as DrivePlan;

fn fixture() -> drivemap_map::Map {
    drivemap_map::Loader::new()
        .load(&paths::fixture("crafted/maps/field-selector.yaml"))
        .unwrap_or_else(|d| panic!("{d}"))
}

/// Settings filled the way both printers fill them: the selector's word, through the plan's code
/// slots.
struct Words<'a> {
    plan: &'a DrivePlan,
    status: Option<u16>,
}

impl SettingsView for Words<'_> {
    fn code(&self, slot: u8) -> Option<u16> {
        let c = self.plan.settings.codes.get(usize::from(slot))?;
        self.status.map(|w| c.code(w))
    }
    fn quantity(&self, _: u8) -> Option<f64> {
        None
    }
    fn variant(&self, _: u8) -> u8 {
        0
    }
}

#[test]
fn lowering_gives_each_field_its_own_code_slot() {
    let drive = fixture();
    let plan = drive.plan();
    let slots: Vec<_> = plan
        .settings
        .codes
        .iter()
        .map(|c| {
            let f = c.field.expect("both selectors are fields");
            (plan.registers[c.register].info.id, f.id, f.lsb, f.width)
        })
        .collect();
    assert_eq!(
        slots,
        [
            ("status_word", "current_decimals", 8, 8),
            ("status_word", "speed_in_rpm", 1, 1)
        ]
    );
    // One word to read for both slots.
    assert_eq!(plan.dependencies(), [0x0010]);
    let current = plan.register("output_current").unwrap();
    let Conversion::Selected { selector, .. } = current.conversion else {
        panic!("{:?}", current.conversion)
    };
    assert_eq!(
        (selector.slot, selector.label),
        (0, "status_word.current_decimals")
    );
}

#[test]
fn the_field_of_the_status_word_chooses_the_decimals() {
    let drive = fixture();
    let plan = drive.plan();
    let current = plan.register("output_current").unwrap();
    let torque = plan.register("torque_current").unwrap();
    let speed = plan.register("speed_monitor").unwrap();
    let with = |status| Words {
        plan,
        status: Some(status),
    };
    // Bits 8-15 = 0, 1, 2: the same word 1234 reads 1234 A, 123.4 A, 12.34 A; the low byte
    // (running, speed unit) does not change the current's decimals.
    assert_eq!(current.decode_number(1234, &with(0x0000)), Ok(1234.0));
    assert_eq!(current.decode_number(1234, &with(0x0101)), Ok(123.4));
    assert_eq!(current.decode_number(1234, &with(0x0203)), Ok(12.34));
    assert_eq!(torque.decode_number(0xFF38, &with(0x0100)), Ok(-20.0));
    // Bit 1 chooses the speed monitor's scale alone.
    assert_eq!(speed.decode_number(1500, &with(0x0200)), Ok(15.0));
    assert_eq!(speed.decode_number(1500, &with(0x0002)), Ok(1500.0));
    // A code no case lists, and a status not read yet, are errors naming the field.
    assert_eq!(
        current.decode_number(1234, &with(0x0300)),
        Err(ValueError::UnsupportedSetting {
            register: "output_current",
            setting: "status_word.current_decimals",
            code: 3
        })
    );
    let unread = Words { plan, status: None };
    assert_eq!(
        current.decode_number(1234, &unread),
        Err(ValueError::MissingSetting {
            register: "output_current",
            setting: "status_word.current_decimals"
        })
    );
    assert_eq!(
        current.encode_number(12.34, &with(0x0200)),
        Ok(1234),
        "encoding follows the same case"
    );
}

#[test]
fn generated_settings_absorb_the_field_of_the_word() {
    let drive = fixture();
    let options = Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "field-selector.yaml".into(),
    };
    let code = drive_module(&drive, &options).unwrap();
    let squeezed: String = code.split_whitespace().collect::<Vec<_>>().join(" ");
    for expected in [
        "pub status_word_current_decimals: Option<u16>,",
        "pub status_word_speed_in_rpm: Option<u16>,",
        "const DEPENDENCIES: &'static [u16] = &[0x0010];",
        "0x0010 => { self.status_word_current_decimals = Some((raw >> 8) & 0x00FF); self.status_word_speed_in_rpm = Some((raw >> 1) & 0x0001); }",
        "0 => self.status_word_current_decimals,",
        "1 => self.status_word_speed_in_rpm,",
    ] {
        assert!(
            squeezed.contains(expected),
            "missing `{expected}` in:\n{code}"
        );
    }
}

#[test]
fn docs_and_export_name_the_field() {
    let drive = fixture();
    let options = Options {
        runtime: "::drivemap_runtime".parse().unwrap(),
        source_name: "field-selector.yaml".into(),
    };
    let code = drive_module(&drive, &options).unwrap();
    assert!(
        code.contains("scale selected by field current_decimals (bits 8-15) of status_word"),
        "{code}"
    );
    assert!(
        code.contains("scale selected by field speed_in_rpm (bit 1) of status_word"),
        "{code}"
    );
    let json = drive.export();
    let current = json["registers"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["id"] == "output_current")
        .unwrap();
    assert_eq!(current["scale_selected_by"], "status_word.current_decimals");
}

/// The same form in an address alternative's condition: a 1-bit field moves a register.
#[test]
fn a_field_moves_a_register() {
    let text = std::fs::read_to_string(paths::fixture("crafted/maps/field-selector.yaml")).unwrap();
    let cited = "        source: \"manual.txt:23\"\n";
    assert_eq!(text.matches(cited).count(), 1);
    let moved = text.replace(
        cited,
        &format!(
            "        address_alternatives:\n          - {{address: 0x0014, when: {{setting: status_word.running, is: [1]}}, source: \"manual.txt:24\"}}\n{cited}"
        ),
    );
    let drive = drivemap_map::Loader::new()
        .load_str("field-selector.yaml", &moved)
        .unwrap_or_else(|d| panic!("{d}"));
    let plan = drive.plan();
    assert_eq!(plan.settings.codes.len(), 3, "running is a third slot");
    assert_eq!(plan.dependencies(), [0x0010], "still one word to read");
    let speed = plan.register("speed_monitor").unwrap();
    let at = |status| {
        speed.address_for(
            &Words {
                plan,
                status: Some(status),
            },
            drivemap_core::profile::TransportKind::Rtu,
        )
    };
    assert_eq!((at(0x0200), at(0x0201)), (0x0013, 0x0014));

    let wide = moved.replace("is: [1]", "is: [2]");
    let err = drivemap_map::Loader::new()
        .load_str("field-selector.yaml", &wide)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(
            "selector `status_word.running` is a 1-bit field: code 2 does not fit (0..=1)"
        ),
        "{err}"
    );
}
