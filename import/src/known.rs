//! The registers of a map read by the front end, as [`Known`] rows.

use drivemap_map::ir::Drive;
use drivemap_map::model::{DefaultValue, Scale};

use crate::compare::Known;

/// Every register of a checked map, with what a manual row can show of it.
pub fn registers(drive: &Drive) -> Vec<Known> {
    drive
        .registers
        .iter()
        .map(|r| {
            let d = &r.def;
            Known {
                id: d.id.clone(),
                param: d.param.clone(),
                address: d.address,
                name: d.name.clone(),
                unit: d.unit.clone(),
                scale: match &d.scale {
                    None => Ok(None),
                    Some(Scale::Factor(f)) => Ok(Some(*f)),
                    Some(Scale::Relative(_)) => Err("a relative scale"),
                    Some(Scale::Ratio(_)) => Err("a ratio scale"),
                    Some(Scale::Selected(_)) => Err("a scale selected by another parameter"),
                },
                min: d.min,
                max: d.max,
                default: match &d.default {
                    None => Ok(None),
                    Some(DefaultValue::Value(v)) => Ok(Some(*v)),
                    Some(DefaultValue::Depends(_)) => {
                        Err("a default that depends on another setting")
                    }
                },
                source: d.source.as_deref().and_then(|s| {
                    let (file, line) = s.rsplit_once(':')?;
                    Some((file.to_string(), line.trim().parse().ok()?))
                }),
            }
        })
        .collect()
}
