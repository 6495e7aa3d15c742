//! Function codes per register (the map's `function_codes`): a request with a function one of
//! its registers does not accept is answered with that register's `refused_with` exception
//! (01h illegal function unless the map says 02h illegal data address), as the manual's drive
//! answers it, before anything is read or written.

use drivemap_runtime::core::profile::TransportKind;

use super::Simulator;

impl Simulator {
    /// The exception for a request of `function` over `quantity` registers from PDU address
    /// `pdu`, when a register it covers does not accept that function; `Ok` otherwise
    /// (addresses that hold no register are left to the read and write rules).
    pub(super) fn function_refused(
        &self,
        kind: TransportKind,
        function: u8,
        pdu: u16,
        quantity: usize,
    ) -> Result<(), u8> {
        let layout = &self.layouts[usize::from(kind == TransportKind::Tcp)];
        let table = drivemap_runtime::core::register::Table::of_function(function)
            .unwrap_or(drivemap_runtime::core::register::Table::Holding);
        let map = layout.of(table);
        for k in 0..quantity {
            let Ok(address) = self.communication_address(kind, u32::from(pdu) + k as u32) else {
                continue;
            };
            if let Some(slot) = map.get(&address) {
                let plan = self.reg(slot.index).plan();
                if !plan.functions.allows(function) {
                    return Err(plan.functions.refused_with);
                }
            }
        }
        Ok(())
    }
}
