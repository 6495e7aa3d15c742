//! A draft map on a live link: read with a note, written only when asked for.
//!
//! A map marked `draft:` (what `drivemap import` writes) was not reviewed against its manual:
//! its addresses, scales and accesses are what a reader made of the text. Reading a drive
//! through it says so; writing through it is refused unless the user says `--draft`
//! ([`DraftWrites::Allowed`]), and then every write says it went through a draft.
//!
//! The refusal is made twice: by each command before anything is sent (with a message naming
//! the map), and by the link itself ([`Link::connect_as`](crate::link::Link::connect_as) wraps the
//! transport of a draft's client in a guard that refuses every write function code unsent), so
//! no path that reaches a drive through a [`Link`](crate::link::Link) writes through a draft by
//! accident.

use std::io;
use std::time::Instant;

use drivemap_map::Map;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::transport::Transport;

/// Whether writes may go through a draft map.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum DraftWrites {
    /// Refused, nothing sent (the default).
    #[default]
    Refused,
    /// Sent, each said to go through a draft (`--draft`).
    Allowed,
}

impl DraftWrites {
    /// [`DraftWrites::Allowed`] when `allowed` (the command line's `--draft`).
    pub fn from_flag(allowed: bool) -> DraftWrites {
        if allowed {
            DraftWrites::Allowed
        } else {
            DraftWrites::Refused
        }
    }
}

/// What a read through `drive` says when it is a draft: `kestrel-k20 is a draft map (made by
/// drivemap import), not reviewed against its manual: values read may be misplaced or misscaled`.
pub fn read_note(drive: &Map) -> Option<String> {
    let d = drive.draft()?;
    Some(format!(
        "{} is a draft map (made by {}), not reviewed against its manual: what is read through it may be misplaced or misscaled",
        drive.id(),
        d.by
    ))
}

/// Refuses a write through `drive` when it is a draft and `writes` is not
/// [`DraftWrites::Allowed`]; `Ok(Some(note))` when it is a draft and allowed (the note to print
/// with every write), `Ok(None)` for a reviewed map.
pub fn check_write(drive: &Map, writes: DraftWrites) -> Result<Option<String>, String> {
    let Some(d) = drive.draft() else {
        return Ok(None);
    };
    match writes {
        DraftWrites::Refused => Err(format!(
            "{} is a draft map (made by {}), not reviewed against its manual: its addresses, scales and accesses may be wrong, so nothing is written through it unless --draft is given; nothing written",
            drive.id(),
            d.by
        )),
        DraftWrites::Allowed => Ok(Some(format!(
            "through draft map {} (--draft): not reviewed against its manual",
            drive.id()
        ))),
    }
}

/// `transport`, refusing every write request unsent (function codes 05h, 06h, 0Fh, 10h, 16h,
/// 17h) when `drive` is a draft and `writes` does not allow it; `transport` as it is otherwise.
pub fn guard(
    drive: &Map,
    writes: DraftWrites,
    transport: Box<dyn Transport>,
) -> Box<dyn Transport> {
    if drive.draft().is_none() || writes == DraftWrites::Allowed {
        return transport;
    }
    Box::new(Guarded {
        inner: transport,
        drive: drive.id().to_owned(),
    })
}

struct Guarded {
    inner: Box<dyn Transport>,
    drive: String,
}

/// The function code of a request frame of `kind`: after the MBAP header (7 bytes) on Modbus
/// TCP, after the slave address on RTU, the second pair of characters on Modbus ASCII.
fn function_code(kind: TransportKind, frame: &[u8]) -> Option<u8> {
    if kind.is_ascii() {
        return drivemap_runtime::ascii::function_code(frame);
    }
    frame.get(if kind.is_rtu_framed() { 1 } else { 7 }).copied()
}

/// Whether a function code writes.
pub(crate) fn writes(code: u8) -> bool {
    matches!(code, 0x05 | 0x06 | 0x0F | 0x10 | 0x16 | 0x17)
}

impl Transport for Guarded {
    fn kind(&self) -> TransportKind {
        self.inner.kind()
    }

    fn send(&mut self, frame: &[u8]) -> io::Result<()> {
        if function_code(self.inner.kind(), frame).is_some_and(writes) {
            return Err(io::Error::other(format!(
                "not sent: {} is a draft map, and writes through a draft need --draft; nothing written",
                self.drive
            )));
        }
        self.inner.send(frame)
    }

    fn recv(&mut self, buf: &mut [u8], deadline: Instant) -> io::Result<usize> {
        self.inner.recv(buf, deadline)
    }

    fn discard_input(&mut self) -> io::Result<()> {
        self.inner.discard_input()
    }

    fn reconnect(&mut self) -> io::Result<()> {
        self.inner.reconnect()
    }

    fn inter_char_timeout(&self) -> Option<std::time::Duration> {
        self.inner.inter_char_timeout()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_write_is_told_on_every_framing() {
        // 06h write of 0001h = 0258h to slave 1.
        let rtu_frame = [0x01, 0x06, 0x00, 0x01, 0x02, 0x58, 0x00, 0x00];
        assert_eq!(function_code(TransportKind::Rtu, &rtu_frame), Some(0x06));
        let tcp_frame = [0, 1, 0, 0, 0, 6, 1, 0x06, 0x00, 0x01, 0x02, 0x58];
        assert_eq!(function_code(TransportKind::Tcp, &tcp_frame), Some(0x06));
        let ascii_frame = b":010600010258\r\n";
        assert_eq!(function_code(TransportKind::Ascii, ascii_frame), Some(0x06));
        assert_eq!(
            function_code(TransportKind::AsciiOverTcp, b":011000010001"),
            Some(0x10)
        );
        assert!(writes(
            function_code(TransportKind::Ascii, ascii_frame).unwrap()
        ));
        assert_eq!(function_code(TransportKind::Ascii, b":01"), None);
    }
}
