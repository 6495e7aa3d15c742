//! Response decoding must never panic, whatever arrives, and must only ever accept a frame that
//! decodes as the answer to the request.
#![no_main]

use drivemap_runtime::pdu::{self, BitValues, Request, Response, Words};
use drivemap_runtime::reply::{Framing, ReplyBuffer};
use drivemap_runtime::{rtu, tcp};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // First bytes choose the request and framing; the rest is what the line delivers.
    let [sel, slave, a_hi, a_lo, q, chunk, rest @ ..] = data else {
        return;
    };
    let address = u16::from_be_bytes([*a_hi, *a_lo]);
    let values = [0x0001u16, 0x0258, 0x1234, 0xFFFF];
    let states = [true, false, true, true, false, false, true, false, true, true];
    let quantity = u16::from(q % 126);
    let request = match sel % 9 {
        0 => Request::ReadHolding { address, quantity },
        1 => Request::ReadInput { address, quantity },
        2 => Request::WriteSingle { address, value: u16::from(*q) },
        3 => Request::LoopBack { data: address },
        4 => Request::WriteMultiple {
            address,
            values: Words::Native(&values[..usize::from(q % 5)]),
        },
        // Coils and discrete inputs: up to 255 states per read (32 bytes of reply).
        5 => Request::ReadCoils { address, quantity: u16::from(*q) },
        6 => Request::ReadDiscreteInputs { address, quantity: u16::from(*q) },
        7 => Request::WriteCoil { address, value: q & 1 == 1 },
        _ => Request::WriteCoils {
            address,
            values: BitValues::Native(&states[..usize::from(q % 11)]),
        },
    };
    let framing = if sel & 0x80 == 0 {
        Framing::Rtu { slave: *slave }
    } else {
        Framing::Tcp { transaction: address, unit: *slave }
    };

    // Whole-frame decoders on the raw input.
    let _ = rtu::decode_response(*slave, &request, rest);
    let _ = tcp::decode_response(address, *slave, &request, rest);
    let _ = pdu::decode_response(&request, rest);
    let _ = rtu::response_bytes_needed(rest);
    let _ = tcp::bytes_needed(rest);
    let _ = rtu::decode_request(rest);
    let _ = tcp::decode_request(rest);

    // Streaming: deliver in chunks, scan after each.
    let mut rx = ReplyBuffer::new();
    let step = usize::from(*chunk % 17) + 1;
    for piece in rest.chunks(step) {
        let mut piece = piece;
        while !piece.is_empty() {
            let n = rx.push(piece);
            piece = &piece[n..];
            if let Some(range) = rx.scan(framing, &request) {
                let frame = rx.frame(range);
                let decoded = match framing {
                    Framing::Rtu { slave } => rtu::decode_response(slave, &request, frame),
                    Framing::Tcp { transaction, unit } => {
                        tcp::decode_response(transaction, unit, &request, frame)
                    }
                };
                // What scan locates must decode, and a read must carry the quantity asked.
                match decoded {
                    Ok(Response::Registers(words)) => assert_eq!(words.len(), request.quantity()),
                    Ok(Response::Bits(bits)) => assert_eq!(bits.len(), request.quantity()),
                    Ok(_) => {}
                    Err(e) => panic!("scan located a frame that does not decode: {e}"),
                }
                return;
            }
        }
    }
});
