//! Every example frame printed in the five manuals of `shared/manuals/`, encoded and decoded.
//!
//! Requests are encoded from their fields and must give the printed bytes, and the printed bytes
//! must decode to the same request (slave side). Responses must decode, with every echo check,
//! as the answer to the request they follow, and encode back to the printed bytes.
//!
//! Reading the CRC bytes: each manual prints the first CRC byte on the wire first. V7
//! (`000_…`), MEMOBUS (`003_…`) and TDS-V8 (`002_…`) label that byte "Upper"/"High Byte"; it is
//! the low byte of the CRC (Modbus sends the low byte first, as the TDS-V8 text itself says at
//! `002_661580cce154f322.txt:124`), so those labels are swapped. The GPD 515 (`001_…`) labels
//! them correctly (LOWER, UPPER). The ACN (`004_…`) prints the two bytes as one number
//! ("0x1202"), which is the wire order, not the CRC value (0212h).
//!
//! One printed CRC is wrong: the MEMOBUS loop-back fault response
//! (`003_8bcf5d50afb8e230.txt:380-386`, `01 88 01 86 50`); see
//! [`memobus_loop_back_fault_response_has_a_wrong_crc`].

use crate::common;

use drivemap_runtime::client::Client;
use drivemap_runtime::core::profile::TransportKind;
use drivemap_runtime::crc;
use drivemap_runtime::pdu::{FrameError, Request, Response, Words};
use drivemap_runtime::rtu;
use drivemap_sim::FaultyLink;
use drivemap_sim::SimulatedSlave;

use common::{ACN, strict};

fn read(address: u16, quantity: u16) -> Request<'static> {
    Request::ReadHolding { address, quantity }
}

fn write(address: u16, value: u16) -> Request<'static> {
    Request::WriteSingle { address, value }
}

fn write_many(address: u16, values: &[u16]) -> Request<'_> {
    Request::WriteMultiple {
        address,
        values: Words::Native(values),
    }
}

fn loop_back(data: u16) -> Request<'static> {
    Request::LoopBack { data }
}

fn exception(function: u8, code: u8) -> Response<'static> {
    Response::Exception { function, code }
}

/// A command message: encodes to `frame` and decodes back.
#[track_caller]
fn command(frame: &[u8], slave: u8, request: Request<'_>) {
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_request(slave, &request, &mut buf).unwrap();
    assert_eq!(&buf[..n], frame, "encoding {request:?}");
    assert_eq!(rtu::decode_request(frame), Ok((slave, request)));
    assert_eq!(rtu::request_frame_len(frame), Ok(Some(frame.len())));
}

/// A response message: decodes as the answer to `request` and encodes back to `frame`.
#[track_caller]
fn response(frame: &[u8], slave: u8, request: Request<'_>, expected: Response<'_>) {
    assert_eq!(rtu::response_bytes_needed(frame), Ok(0));
    for cut in 0..frame.len() {
        assert!(rtu::response_bytes_needed(&frame[..cut]).unwrap() > 0);
    }
    assert_eq!(rtu::decode_response(slave, &request, frame), Ok(expected));
    let mut buf = [0u8; rtu::MAX_FRAME];
    let n = rtu::encode_response(slave, request.function(), &expected, &mut buf).unwrap();
    assert_eq!(&buf[..n], frame, "encoding {expected:?}");
}

// ---------------------------------------------------------------------------------------------
// 000_032dced3a1e91a75.txt: Yaskawa "Modbus Communication Manual V7 and V74X Drives", Chapter 2.

#[test]
fn v7_read_multiple_registers() {
    // Table 2.2, 000_032dced3a1e91a75.txt:310-319 ("CRC-16 Upper 45h", "Lower F0h": swapped).
    let req = read(0x0020, 4);
    command(&[0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0], 2, req);
    // Table 2.3, 000_032dced3a1e91a75.txt:335-349; values given at :357.
    response(
        &[
            0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
        ],
        2,
        req,
        Response::Registers(Words::Native(&[0x1770, 0x1770, 0x0109, 0x0000])),
    );
    // Table 2.4, 000_032dced3a1e91a75.txt:361-367.
    response(
        &[0x02, 0x83, 0x02, 0x30, 0xF1],
        2,
        req,
        exception(0x03, 0x02),
    );
}

#[test]
fn v7_write_single_register() {
    // Table 2.5, 000_032dced3a1e91a75.txt:381-390 (CRC lower byte OCR'd as "H0B": 0Bh, see
    // Table 2.6).
    let req = write(0x0001, 0x0003);
    command(&[0x01, 0x06, 0x00, 0x01, 0x00, 0x03, 0x98, 0x0B], 1, req);
    // Table 2.6, 000_032dced3a1e91a75.txt:408-417.
    response(
        &[0x01, 0x06, 0x00, 0x01, 0x00, 0x03, 0x98, 0x0B],
        1,
        req,
        Response::WriteSingle {
            address: 1,
            value: 3,
        },
    );
    // Table 2.7, 000_032dced3a1e91a75.txt:425-431: the drive's own code 21h.
    response(
        &[0x01, 0x86, 0x21, 0x82, 0x78],
        1,
        req,
        exception(0x06, 0x21),
    );
}

#[test]
fn v7_loop_back() {
    // Table 2.8, 000_032dced3a1e91a75.txt:447-456; the slave address is lost in the OCR, 01h
    // per :458.
    let req = loop_back(0xA537);
    command(&[0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D], 1, req);
    // Table 2.9, 000_032dced3a1e91a75.txt:474-483.
    response(
        &[0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D],
        1,
        req,
        Response::LoopBack { data: 0xA537 },
    );
    // Table 2.10, 000_032dced3a1e91a75.txt:487-493.
    response(
        &[0x01, 0x88, 0x01, 0x87, 0xC0],
        1,
        req,
        exception(0x08, 0x01),
    );
}

#[test]
fn v7_write_multiple_registers() {
    // Table 2.11, 000_032dced3a1e91a75.txt:505-519. The OCR lost the upper byte of the second
    // register (:516); 02h (0258h = 600 = 60.0 Hz) is what the printed CRC 63h 39h and the
    // MEMOBUS manual's same example (003_8bcf5d50afb8e230.txt:396) give.
    let values = [0x0001, 0x0258];
    let req = write_many(0x0001, &values);
    command(
        &[
            0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x02, 0x58, 0x63, 0x39,
        ],
        1,
        req,
    );
    // Table 2.12, 000_032dced3a1e91a75.txt:541-550.
    response(
        &[0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08],
        1,
        req,
        Response::WriteMultiple {
            address: 1,
            quantity: 2,
        },
    );
    // Table 2.13, 000_032dced3a1e91a75.txt:560-566.
    response(
        &[0x01, 0x90, 0x02, 0xCD, 0xC1],
        1,
        req,
        exception(0x10, 0x02),
    );
}

// ---------------------------------------------------------------------------------------------
// 001_ef66da56d29a05af.txt: Magnetek "GPD 515/G5 Modbus RTU", Chapter 6.

#[test]
fn gpd515_read_multiple_registers() {
    // Command message, 001_ef66da56d29a05af.txt:493-513 (slave 2 per :517).
    let req = read(0x0020, 4);
    command(&[0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0], 2, req);
    // Normal response, 001_ef66da56d29a05af.txt:539-594 (60.00 Hz, 60.00 Hz, 109h, 0).
    response(
        &[
            0x02, 0x03, 0x08, 0x17, 0x70, 0x17, 0x70, 0x01, 0x09, 0x00, 0x00, 0x38, 0xAC,
        ],
        2,
        req,
        Response::Registers(Words::Native(&[6000, 6000, 0x0109, 0])),
    );
    // Fault response, 001_ef66da56d29a05af.txt:611-621.
    response(
        &[0x02, 0x83, 0x02, 0x30, 0xF1],
        2,
        req,
        exception(0x03, 0x02),
    );
}

#[test]
fn gpd515_loop_back() {
    // Command, 001_ef66da56d29a05af.txt:642-661 (slave 1 per :665); normal response :682-701.
    let req = loop_back(0xA537);
    let frame = [0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D];
    command(&frame, 1, req);
    response(&frame, 1, req, Response::LoopBack { data: 0xA537 });
    // Fault response, 001_ef66da56d29a05af.txt:703-713.
    response(
        &[0x01, 0x88, 0x01, 0x87, 0xC0],
        1,
        req,
        exception(0x08, 0x01),
    );
}

#[test]
fn gpd515_write_multiple_registers() {
    // Command, 001_ef66da56d29a05af.txt:733-777: run forward at 60.00 Hz.
    let values = [0x0001, 0x1770];
    let req = write_many(0x0001, &values);
    command(
        &[
            0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x17, 0x70, 0x6D, 0xB7,
        ],
        1,
        req,
    );
    // Normal response, 001_ef66da56d29a05af.txt:813-833.
    response(
        &[0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08],
        1,
        req,
        Response::WriteMultiple {
            address: 1,
            quantity: 2,
        },
    );
    // Fault response, 001_ef66da56d29a05af.txt:848-858.
    response(
        &[0x01, 0x90, 0x02, 0xCD, 0xC1],
        1,
        req,
        exception(0x10, 0x02),
    );
}

#[test]
fn gpd515_crc_example() {
    // 001_ef66da56d29a05af.txt:946-953: slave 2, function 7: CRC lower 41h, upper 12h. Function
    // 07h is not one these drives implement, so only the CRC is checked and the frame is refused
    // as an unknown function.
    let frame = [0x02, 0x07, 0x41, 0x12];
    assert_eq!(crc::check(&frame), Ok(&[0x02u8, 0x07][..]));
    assert_eq!(
        rtu::response_bytes_needed(&frame),
        Err(FrameError::UnknownFunction(0x07))
    );
}

// ---------------------------------------------------------------------------------------------
// 002_661580cce154f322.txt: PTLK "TDS-V8 MODBUS Communication Application Manual". Every CRC
// here is labelled "High Byte" then "Low Byte"; the first is the low byte.

#[test]
fn tds_v8_read() {
    // Command, 002_661580cce154f322.txt:181-190.
    let req = read(0x0020, 1);
    command(&[0x01, 0x03, 0x00, 0x20, 0x00, 0x01, 0x85, 0xC0], 1, req);
    // Error return, 002_661580cce154f322.txt:192-198.
    response(
        &[0x01, 0x83, 0x03, 0x01, 0x31],
        1,
        req,
        exception(0x03, 0x03),
    );
    // Normal return, 002_661580cce154f322.txt:200-208 (data bytes labelled "Head Address").
    response(
        &[0x01, 0x03, 0x02, 0x08, 0x02, 0x3E, 0x45],
        1,
        req,
        Response::Registers(Words::Native(&[0x0802])),
    );
}

#[test]
fn tds_v8_write_single() {
    // Host query, 002_661580cce154f322.txt:214-223.
    let req = write(0x0001, 0x0020);
    let frame = [0x01, 0x06, 0x00, 0x01, 0x00, 0x20, 0xD9, 0xD2];
    command(&frame, 1, req);
    // Error return, 002_661580cce154f322.txt:225-231.
    response(
        &[0x01, 0x86, 0x03, 0x02, 0x61],
        1,
        req,
        exception(0x06, 0x03),
    );
    // Normal return, 002_661580cce154f322.txt:233-242.
    response(
        &frame,
        1,
        req,
        Response::WriteSingle {
            address: 1,
            value: 0x20,
        },
    );
}

#[test]
fn tds_v8_loop_test() {
    // Command, 002_661580cce154f322.txt:248-255.
    let req = loop_back(0x1234);
    let frame = [0x01, 0x08, 0x00, 0x00, 0x12, 0x34, 0xED, 0x7C];
    command(&frame, 1, req);
    // Error return, 002_661580cce154f322.txt:257-263.
    response(
        &[0x01, 0x88, 0x03, 0x06, 0x01],
        1,
        req,
        exception(0x08, 0x03),
    );
    // Normal return, 002_661580cce154f322.txt:265-274.
    response(&frame, 1, req, Response::LoopBack { data: 0x1234 });
}

#[test]
fn tds_v8_write_multiple() {
    // Host query, 002_661580cce154f322.txt:280-292.
    let values = [0x0030];
    let req = write_many(0x0001, &values);
    command(
        &[
            0x01, 0x10, 0x00, 0x01, 0x00, 0x01, 0x02, 0x00, 0x30, 0xA7, 0x95,
        ],
        1,
        req,
    );
    // Error return, 002_661580cce154f322.txt:294-300.
    response(
        &[0x01, 0x90, 0x03, 0x0C, 0x01],
        1,
        req,
        exception(0x10, 0x03),
    );
    // Normal return, 002_661580cce154f322.txt:302-311.
    response(
        &[0x01, 0x10, 0x00, 0x01, 0x00, 0x01, 0x50, 0x09],
        1,
        req,
        Response::WriteMultiple {
            address: 1,
            quantity: 1,
        },
    );
}

fn tds_step(values: &[u16; 8], crc: [u8; 2]) -> Vec<u8> {
    let mut f = vec![0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0x10];
    for v in values {
        f.extend_from_slice(&v.to_be_bytes());
    }
    f.extend_from_slice(&crc);
    f
}

#[test]
fn tds_v8_plc_example() {
    let written = Response::WriteMultiple {
        address: 0,
        quantity: 8,
    };
    let reply = [0x01, 0x10, 0x00, 0x00, 0x00, 0x08, 0xC1, 0xCF];
    // Step 1, 002_661580cce154f322.txt:659-685: forward run at 80 % (5DC0h); reply :687-696.
    let v = [0x0001, 0x5DC0, 0, 0, 0, 0, 0, 0x0001];
    command(&tds_step(&v, [0x44, 0x91]), 1, write_many(0, &v));
    response(&reply, 1, write_many(0, &v), written);
    // Step 2, 002_661580cce154f322.txt:707-733: 50 % (3A98h); reply :735-744.
    let v = [0x0001, 0x3A98, 0, 0, 0, 0, 0, 0x0001];
    command(&tds_step(&v, [0xFD, 0x2E]), 1, write_many(0, &v));
    response(&reply, 1, write_many(0, &v), written);
    // Step 3, 002_661580cce154f322.txt:755-779: reverse run. The OCR lost the Access Count
    // lines (between :760 and :761); 0008h is what the byte count 10h and the printed CRC
    // 7Fh 2Fh give. Reply :781-790.
    let v = [0x0003, 0x3A98, 0, 0, 0, 0, 0, 0x0001];
    command(&tds_step(&v, [0x7F, 0x2F]), 1, write_many(0, &v));
    response(&reply, 1, write_many(0, &v), written);
    // Step 4, 002_661580cce154f322.txt:801-813: stop. Its reply (:815-824) is printed without
    // values; the encoder gives 01 10 00 00 00 01 01 C9, which must decode.
    let v = [0x0000];
    let req = write_many(0, &v);
    command(
        &[
            0x01, 0x10, 0x00, 0x00, 0x00, 0x01, 0x02, 0x00, 0x00, 0xA6, 0x50,
        ],
        1,
        req,
    );
    response(
        &[0x01, 0x10, 0x00, 0x00, 0x00, 0x01, 0x01, 0xC9],
        1,
        req,
        Response::WriteMultiple {
            address: 0,
            quantity: 1,
        },
    );
}

// ---------------------------------------------------------------------------------------------
// 003_8bcf5d50afb8e230.txt: Yaskawa "VS-606V7 / VS mini J7 MEMOBUS Instruction Manual".

#[test]
fn memobus_read_holding_registers() {
    // Command, 003_8bcf5d50afb8e230.txt:314-322.
    let req = read(0x0020, 4);
    command(&[0x02, 0x03, 0x00, 0x20, 0x00, 0x04, 0x45, 0xF0], 2, req);
    // Normal response, 003_8bcf5d50afb8e230.txt:324-338.
    response(
        &[
            0x02, 0x03, 0x08, 0x00, 0x65, 0x00, 0x00, 0x00, 0x00, 0x01, 0xF4, 0xAF, 0x82,
        ],
        2,
        req,
        Response::Registers(Words::Native(&[0x0065, 0, 0, 0x01F4])),
    );
    // Fault response ("Command Message" in the OCR), 003_8bcf5d50afb8e230.txt:340-347.
    response(
        &[0x02, 0x83, 0x03, 0xF1, 0x31],
        2,
        req,
        exception(0x03, 0x03),
    );
}

#[test]
fn memobus_loop_back() {
    // Command, 003_8bcf5d50afb8e230.txt:359-367; normal response :369-378.
    let req = loop_back(0xA537);
    let frame = [0x01, 0x08, 0x00, 0x00, 0xA5, 0x37, 0xDA, 0x8D];
    command(&frame, 1, req);
    response(&frame, 1, req, Response::LoopBack { data: 0xA537 });
}

#[test]
fn memobus_loop_back_fault_response_has_a_wrong_crc() {
    // 003_8bcf5d50afb8e230.txt:380-386 prints 01 88 01 with CRC "Upper 86H, Lower 50H". The
    // CRC of 01 88 01 is 87h C0h, as the V7 manual (000_032dced3a1e91a75.txt:487-493) and the
    // GPD 515 manual (001_ef66da56d29a05af.txt:703-713) print for the same frame. The printed
    // frame is rejected; the corrected one decodes.
    let req = loop_back(0xA537);
    let printed = [0x01, 0x88, 0x01, 0x86, 0x50];
    assert_eq!(
        rtu::decode_response(1, &req, &printed),
        Err(FrameError::Crc {
            computed: 0xC087,
            received: 0x5086
        })
    );
    response(
        &[0x01, 0x88, 0x01, 0x87, 0xC0],
        1,
        req,
        exception(0x08, 0x01),
    );
}

#[test]
fn memobus_write_holding_registers() {
    // Command, 003_8bcf5d50afb8e230.txt:392-396: forward run at 60.0 Hz (0258h).
    let values = [0x0001, 0x0258];
    let req = write_many(0x0001, &values);
    command(
        &[
            0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x04, 0x00, 0x01, 0x02, 0x58, 0x63, 0x39,
        ],
        1,
        req,
    );
    // Normal response, 003_8bcf5d50afb8e230.txt:398.
    response(
        &[0x01, 0x10, 0x00, 0x01, 0x00, 0x02, 0x10, 0x08],
        1,
        req,
        Response::WriteMultiple {
            address: 1,
            quantity: 2,
        },
    );
    // Fault response, 003_8bcf5d50afb8e230.txt:400-407.
    response(
        &[0x01, 0x90, 0x02, 0xCD, 0xC1],
        1,
        req,
        exception(0x10, 0x02),
    );
}

#[test]
fn memobus_crc_worked_example() {
    // Fig. 7.2-7.4, 003_8bcf5d50afb8e230.txt:434-482: slave 2, function 7 gives 41h then 12h.
    // Fig. 7.4 (:476-482) labels 0001 0010 (12h) "CRC-16(LSB)" and 0100 0001 (41h)
    // "CRC-16(MSB)": swapped; 41h is the low byte and goes first.
    assert_eq!(crc::crc16(&[0x02, 0x07]), 0x1241);
    assert_eq!(crc::crc_bytes(&[0x02, 0x07]), [0x41, 0x12]);
}

// ---------------------------------------------------------------------------------------------
// 004_c5cbf92472673495.txt: AutomationDirect ACN, Chapter 5.

const ACN_REQUEST: [u8; 13] = [
    0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0x04, 0x00, 0x32, 0x00, 0x64, 0x12, 0x02,
];
const ACN_RESPONSE: [u8; 8] = [0x01, 0x10, 0x11, 0x02, 0x00, 0x02, 0xE5, 0x34];

#[test]
fn acn_write_acc_and_dec_time() {
    // 004_c5cbf92472673495.txt:605-619: Acc 5.0 s (0x0032) and Dec 10.0 s (0x0064) to
    // communication addresses 0x1103-0x1104, sent as starting address 0x1102 ("0x1103-1"). The
    // CRC is printed as "0x1202": the wire bytes 12h 02h, CRC value 0212h.
    let values = [0x0032, 0x0064];
    let req = write_many(0x1102, &values);
    command(&ACN_REQUEST, 1, req);
    // Response, 004_c5cbf92472673495.txt:621-628, CRC "0xE534".
    response(
        &ACN_RESPONSE,
        1,
        req,
        Response::WriteMultiple {
            address: 0x1102,
            quantity: 2,
        },
    );
}

#[test]
fn acn_example_through_the_client_maps_the_communication_address() {
    // The same example through the client: the user names the manual's communication address
    // 0x1103, the ACN profile's RTU offset (-1) makes it 0x1102 on the wire, and the frame is
    // byte for byte the printed one (004_c5cbf92472673495.txt:616).
    let link = FaultyLink::new(TransportKind::Rtu, SimulatedSlave::new(1, &ACN));
    let mut client = Client::with_options(link, &ACN, strict());
    client.write_registers(1, 0x1103, &[50, 100]).unwrap();
    assert_eq!(client.transport().sent, vec![ACN_REQUEST.to_vec()]);
    assert_eq!(client.transport().slave.holding(0x1102), 50);
    assert_eq!(client.transport().slave.holding(0x1103), 100);
}
