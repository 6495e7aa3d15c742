//! The registers of a map read by the front end, as [`Known`] rows.

use drivemap_map::Map;
use drivemap_map::facts::DefaultValue;

use crate::compare::Known;

/// Every register of a checked map, with what a manual row can show of it.
pub fn registers(drive: &Map) -> Vec<Known> {
    drive
        .registers()
        .map(|r| {
            let (min, max) = r.limits();
            Known {
                id: r.id().to_owned(),
                param: r.param().map(str::to_owned),
                address: r.address(),
                name: r.name().to_owned(),
                unit: r.unit().map(str::to_owned),
                scale: r.scale().map_or(Ok(None), |s| s.factor()),
                min,
                max,
                default: match r.default() {
                    None => Ok(None),
                    Some(DefaultValue::Value(v)) => Ok(Some(*v)),
                    Some(DefaultValue::Depends(_)) => {
                        Err("a default that depends on another setting")
                    }
                },
                source: r.source().and_then(|s| {
                    let (file, line) = s.rsplit_once(':')?;
                    Some((file.to_string(), line.trim().parse().ok()?))
                }),
            }
        })
        .collect()
}
