//! The manuals' example frames as tests of the simulator: for every map of `maps/` (the
//! directory is read, so a new map is covered with no edit here), the Orbis Q5 fixture and the
//! Quill Q2 fixture (Modbus ASCII: its frames go over the wire as ASCII characters), each
//! request example that a response example answers is fed to a simulated drive of that map (at
//! the request's slave address, with the drive state the example assumes, and, for a read, the
//! response's words set first as the drive's state, in a register store without the drive model,
//! which would compute its monitors from its own stopped state), and the simulator must answer
//! with the response's bytes, byte for byte. Writes and loop-backs go to the full simulated drive.
//!
//! A response whose printed bytes contradict the codec (marked `conflict:`) is compared on its
//! address and PDU, and its CRC against the codec's; a request so marked is not fed (the map
//! records that the drive as mapped does not take it).

use drivemap_test_support::paths;

use std::path::PathBuf;
use std::sync::Arc;

use drivemap_live::examples::{Frame, frame, kind_of, register_at, with_settings};
use drivemap_map::Map as Drive;
use drivemap_map::facts::{Direction, Example};
use drivemap_runtime::pdu::{self, Request, Response};
use drivemap_runtime::{crc, tcp};
use drivemap_sim::{RolesChoice, SimOptions, Simulator, clock::ManualClock};

fn root() -> PathBuf {
    paths::workspace().to_path_buf()
}

fn maps() -> Vec<PathBuf> {
    let mut out = drivemap_map::find_maps(&paths::maps()).unwrap();
    assert!(out.len() >= 5, "maps/ holds {} maps", out.len());
    out.push(paths::fixture("orbis-q5/orbis-q5.yaml"));
    out.push(paths::fixture("quill-q2/quill-q2.yaml"));
    out
}

/// A simulated drive of `drive` at `slave`, in the state `request` assumes, with a read
/// response's words set first.
fn simulator(drive: &Drive, request: &Example, response: &Frame, req: &Request<'_>) -> Simulator {
    let mut options = SimOptions::new()
        .slave(response.slave)
        .clock(Arc::new(ManualClock::new()));
    if req.is_read() {
        // The response's words are the drive's state: a register store holds them as set,
        // where the drive model would compute its monitors from its own (stopped) state.
        options = options.roles(RolesChoice::NoModel);
    }
    for (name, &value) in &request.settings {
        options = if drive.register(name).is_some() {
            options.set(name, value)
        } else {
            options.external(name, value)
        };
    }
    let mut sim = Simulator::new(drive.clone(), options).unwrap();
    if let (Ok(Response::Registers(words)), Some(address)) =
        (pdu::decode_response(req, response.pdu()), req.address())
    {
        let kind = kind_of(request);
        let settings = with_settings(drive, request, &sim.settings());
        let offsets = &drive.plan().profile.address_offsets;
        for (k, word) in words.iter().enumerate() {
            let comm = offsets
                .communication_address(address + k as u16, kind)
                .unwrap();
            let (r, w) = register_at(drive, &settings, kind, comm, None, false)
                .unwrap_or_else(|| panic!("{}: no register at {comm:04X}h", request.id));
            assert_eq!(w, 0, "{}: a 32-bit pair in a read example", request.id);
            sim.set_raw(r.id(), u32::from(word)).unwrap();
        }
    }
    sim
}

#[test]
fn every_map_s_simulator_answers_its_manual_s_examples_byte_for_byte() {
    let ctx = drivemap_map::Loader::new().manuals(root().join("../shared/manuals"));
    let mut ascii_pairs = 0;
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for path in maps() {
        let drive = ctx.load(&path).unwrap_or_else(|e| panic!("{e}"));
        let mut pairs = 0;
        for response in drive
            .examples()
            .iter()
            .filter(|e| e.direction == Direction::Response)
        {
            let Some(request) = response
                .answers
                .as_ref()
                .and_then(|id| drive.examples().iter().find(|e| e.id == *id))
            else {
                continue;
            };
            if request.conflict.is_some() {
                continue;
            }
            let rf = frame(request).unwrap();
            let req = pdu::decode_request(rf.pdu()).unwrap();
            // A marked response: its CRC is the codec's, the rest as printed.
            let mut printed = parse(&response.bytes);
            let ascii = kind_of(request).is_ascii();
            if response.conflict.is_some() && kind_of(response).is_rtu_framed() {
                let n = printed.len();
                let crc = crc::crc_bytes(&printed[..n - 2]);
                printed[n - 2..].copy_from_slice(&crc);
            }
            let resp = Frame {
                slave: printed[if rf.pdu_start == 1 { 0 } else { 6 }],
                pdu_start: rf.pdu_start,
                pdu_end: printed.len()
                    - match (rf.pdu_start, ascii) {
                        (1, true) => 1,
                        (1, false) => 2,
                        _ => 0,
                    },
                bytes: printed.clone(),
            };
            let mut sim = simulator(&drive, request, &resp, &req);
            let mut out = [0u8; tcp::MAX_FRAME];
            let answer = if ascii {
                // On the wire as the manual prints it: ':', the bytes as characters, CR LF; the
                // drive answers the RTU frame it stands for, its reply goes back as ASCII.
                let wire = ascii_wire(&rf.bytes);
                let mut rtu_frame = [0u8; 256];
                let n = drivemap_runtime::ascii::to_rtu(&wire, &mut rtu_frame)
                    .unwrap_or_else(|e| panic!("{}: {e}", request.id));
                let handled = sim.handle(kind_of(request), &rtu_frame[..n], &mut out);
                ascii_pairs += 1;
                handled.reply.map(|m| {
                    let mut reply = [0u8; drivemap_runtime::ascii::MAX_FRAME];
                    let k = drivemap_runtime::ascii::from_rtu(&out[..m], &mut reply).unwrap();
                    assert_eq!(
                        &reply[..k],
                        &ascii_wire(&printed)[..],
                        "{}: the ASCII reply as the manual prints it",
                        response.id
                    );
                    printed.clone()
                })
            } else {
                let handled = sim.handle(kind_of(request), &rf.bytes, &mut out);
                handled.reply.map(|n| out[..n].to_vec())
            };
            if answer.as_deref() != Some(&printed[..]) {
                failures.push(format!(
                    "{}: `{}` answered {} to `{}`; the manual prints {}",
                    drive.id(),
                    response.id,
                    answer.map_or("nothing".into(), |a| drivemap_map::facts::hex_text(&a)),
                    request.id,
                    drivemap_map::facts::hex_text(&printed)
                ));
            }
            pairs += 1;
        }
        report.push(format!("{}: {pairs}", drive.id()));
        if path.starts_with(paths::maps()) {
            assert!(
                pairs > 0,
                "{}: no request/response example pair",
                drive.id()
            );
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
    assert!(
        ascii_pairs > 0,
        "the Quill Q2's ASCII examples were replayed"
    );
    eprintln!("request/response pairs replayed: {}", report.join(", "));
}

/// An ASCII frame as it goes on the wire: ':', each byte as two upper-case hex characters,
/// CR LF.
fn ascii_wire(bytes: &[u8]) -> Vec<u8> {
    let mut wire = vec![b':'];
    for b in bytes {
        wire.extend_from_slice(format!("{b:02X}").as_bytes());
    }
    wire.extend_from_slice(b"\r\n");
    wire
}

fn parse(text: &str) -> Vec<u8> {
    drivemap_map::facts::parse_bytes(text)
        .unwrap()
        .iter()
        .map(|b| b.value)
        .collect()
}
