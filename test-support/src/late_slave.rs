//! A slave on any [`Transport`] (one end of a pseudo-terminal pair, a socket) that answers
//! like [`hostile_peer::Script::Late`](crate::hostile_peer::Script::Late): correctly, but every
//! `every`-th request just after the client's timeout. With [`numbered`], holding register `a`
//! holds `a`, so an answer misattributed to another register's request shows as a wrong value.

use std::time::{Duration, Instant};

use drivemap_runtime::core::profile::Profile;
use drivemap_runtime::transport::Transport;
use drivemap_runtime::{ascii, rtu, tcp};
use drivemap_sim::SimulatedSlave;

/// Slave 1 of `profile` whose holding and input register `a` hold `a` (0..64).
pub fn numbered(profile: &'static Profile) -> SimulatedSlave {
    let mut slave = SimulatedSlave::new(1, profile);
    for a in 0..64u16 {
        slave.set_holding(a, a);
        slave.set_input(a, a);
    }
    slave
}

/// Serves `link` as `slave` until `until`; every `every`-th request (the 1st, the
/// `every + 1`-th, ...) is answered `late` after it arrived. Returns the requests answered.
pub fn serve_late(
    link: &mut impl Transport,
    slave: &mut SimulatedSlave,
    every: u32,
    late: Duration,
    until: Instant,
) -> u32 {
    let kind = link.kind();
    let mut buf: Vec<u8> = Vec::new();
    let mut chunk = [0u8; 512];
    let mut served = 0u32;
    while Instant::now() < until {
        let total = if kind.is_ascii() {
            // Modbus ASCII: a frame runs to its LF (what precedes its ':' is dropped below).
            buf.iter().position(|&c| c == b'\n').map(|lf| lf + 1)
        } else if kind.is_rtu_framed() {
            match rtu::request_frame_len(&buf) {
                Ok(t) => t,
                Err(_) => {
                    // Not a request: drop a byte and look again.
                    buf.remove(0);
                    continue;
                }
            }
        } else {
            tcp::Header::parse(&buf)
                .ok()
                .flatten()
                .map(|h| h.frame_len())
        };
        let Some(total) = total.filter(|&t| t <= buf.len()) else {
            let wait = (Instant::now() + Duration::from_millis(20)).min(until);
            match link.recv(&mut chunk, wait) {
                Ok(n) => buf.extend_from_slice(&chunk[..n]),
                Err(_) => return served,
            }
            continue;
        };
        let frame: Vec<u8> = buf.drain(..total).collect();
        let mut out = [0u8; ascii::MAX_FRAME];
        let n = if kind.is_ascii() {
            // The drive answers the RTU frame an ASCII frame stands for; its reply goes back
            // as ASCII. A damaged frame goes unanswered.
            let start = frame.iter().position(|&c| c == ascii::START).unwrap_or(0);
            let mut request = [0u8; rtu::MAX_FRAME];
            let mut reply = [0u8; tcp::MAX_FRAME];
            ascii::to_rtu(&frame[start..], &mut request)
                .ok()
                .and_then(|m| slave.respond(kind, &request[..m], &mut reply))
                .and_then(|m| ascii::from_rtu(&reply[..m], &mut out).ok())
                .unwrap_or(0)
        } else {
            slave.respond(kind, &frame, &mut out).unwrap_or(0)
        };
        if served.is_multiple_of(every.max(1)) {
            std::thread::sleep(late);
        }
        served += 1;
        if n > 0 && link.send(&out[..n]).is_err() {
            return served;
        }
    }
    served
}
