//! Protocol data units (function code + data) of the functions these drives implement — the
//! register functions 03h, 04h, 06h, 10h, the loop-back 08h, and the bit functions 01h, 02h,
//! 05h, 0Fh of coils and discrete inputs — with no I/O and no heap: requests are encoded into
//! caller buffers and responses are decoded as views of the received bytes.
//!
//! Every response is checked against the request that it answers: function echo, byte count,
//! address and quantity echo (10h, 0Fh), address and value echo (06h, 05h), sub-function and
//! data echo (08h). A response that fails any check is a [`FrameError`], never a value.

use ::core::fmt;

/// Function codes.
pub mod function {
    /// Read coils.
    pub const READ_COILS: u8 = 0x01;
    /// Read discrete inputs.
    pub const READ_DISCRETE_INPUTS: u8 = 0x02;
    /// Write single coil: FF00h turns it on, 0000h off.
    pub const WRITE_COIL: u8 = 0x05;
    /// Write multiple coils.
    pub const WRITE_COILS: u8 = 0x0F;
    /// Read holding registers.
    pub const READ_HOLDING: u8 = 0x03;
    /// Read input registers.
    pub const READ_INPUT: u8 = 0x04;
    /// Write single register.
    pub const WRITE_SINGLE: u8 = 0x06;
    /// Diagnostics; only sub-function 0000h (return query data, "loop-back") is used.
    pub const LOOP_BACK: u8 = 0x08;
    /// Write multiple registers.
    pub const WRITE_MULTIPLE: u8 = 0x10;
    /// Set in the function code of an exception response.
    pub const EXCEPTION_BIT: u8 = 0x80;
}

/// Largest PDU the Modbus specification allows (256-byte RTU frame less address and CRC).
pub const MAX_PDU: usize = 253;
/// Most registers one 03h/04h request may read (Modbus specification).
pub const MAX_READ: u16 = 125;
/// Most registers one 10h request may write (Modbus specification).
pub const MAX_WRITE: u16 = 123;
/// Most coils or discrete inputs one 01h/02h request may read (Modbus specification).
pub const MAX_READ_BITS: u16 = 2000;
/// Most coils one 0Fh request may write (Modbus specification).
pub const MAX_WRITE_BITS: u16 = 1968;
/// The word 05h writes to turn a coil on (0000h turns it off).
pub const COIL_ON: u16 = 0xFF00;

/// A sequence of coil or discrete-input states: either values to send, or the packed bytes as
/// received (the first bit in the lowest bit of the first byte) with their count. Comparing two
/// `BitValues` compares the states.
#[derive(Clone, Copy)]
pub enum BitValues<'a> {
    /// States in memory.
    Native(&'a [bool]),
    /// Packed bytes on the wire, and how many bits of them are states (the rest is padding).
    Wire {
        /// The packed bytes: bit `i` is bit `i % 8` of byte `i / 8`.
        bytes: &'a [u8],
        /// Number of states.
        count: usize,
    },
}

impl<'a> BitValues<'a> {
    /// Number of states.
    pub fn len(&self) -> usize {
        match self {
            BitValues::Native(b) => b.len(),
            BitValues::Wire { count, .. } => *count,
        }
    }

    /// Whether there are no states.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The state at `index`.
    pub fn get(&self, index: usize) -> Option<bool> {
        match self {
            BitValues::Native(b) => b.get(index).copied(),
            BitValues::Wire { bytes, count } => {
                if index >= *count {
                    return None;
                }
                Some(bytes.get(index / 8)? >> (index % 8) & 1 == 1)
            }
        }
    }

    /// The states in order.
    pub fn iter(&self) -> impl Iterator<Item = bool> + 'a {
        let bits = *self;
        (0..bits.len()).filter_map(move |i| bits.get(i))
    }

    /// Bytes the packed states take on the wire.
    pub fn byte_count(&self) -> usize {
        self.len().div_ceil(8)
    }

    /// Copies the states into `out` as words, 1 for on and 0 for off (the raw value of a coil);
    /// returns how many were copied (the shorter length).
    pub fn copy_to(&self, out: &mut [u16]) -> usize {
        let n = self.len().min(out.len());
        for (i, slot) in out.iter_mut().take(n).enumerate() {
            *slot = u16::from(self.get(i).unwrap_or(false));
        }
        n
    }

    fn write_packed(&self, out: &mut [u8]) {
        for b in out.iter_mut() {
            *b = 0;
        }
        for (i, on) in self.iter().enumerate() {
            if on {
                out[i / 8] |= 1 << (i % 8);
            }
        }
    }
}

impl PartialEq for BitValues<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl Eq for BitValues<'_> {}

impl fmt::Debug for BitValues<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_list().entries(self.iter().map(u8::from)).finish()
    }
}

/// A sequence of 16-bit register words: either native words to send, or big-endian bytes as
/// received. Comparing two `Words` compares the register values.
#[derive(Clone, Copy)]
pub enum Words<'a> {
    /// Words in memory.
    Native(&'a [u16]),
    /// Big-endian words on the wire (always an even number of bytes).
    Wire(&'a [u8]),
}

impl<'a> Words<'a> {
    /// Number of registers.
    pub fn len(&self) -> usize {
        match self {
            Words::Native(w) => w.len(),
            Words::Wire(b) => b.len() / 2,
        }
    }

    /// Whether there are no registers.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The register at `index`.
    pub fn get(&self, index: usize) -> Option<u16> {
        match self {
            Words::Native(w) => w.get(index).copied(),
            Words::Wire(b) => {
                let i = index.checked_mul(2)?;
                Some(u16::from_be_bytes([*b.get(i)?, *b.get(i + 1)?]))
            }
        }
    }

    /// The registers in order.
    pub fn iter(&self) -> impl Iterator<Item = u16> + 'a {
        let words = *self;
        (0..words.len()).filter_map(move |i| words.get(i))
    }

    /// Copies the registers into `out`; returns how many were copied (the shorter length).
    pub fn copy_to(&self, out: &mut [u16]) -> usize {
        let n = self.len().min(out.len());
        for (i, slot) in out.iter_mut().take(n).enumerate() {
            *slot = self.get(i).unwrap_or(0);
        }
        n
    }

    fn write_be(&self, out: &mut [u8]) {
        for (i, w) in self.iter().enumerate() {
            out[2 * i..2 * i + 2].copy_from_slice(&w.to_be_bytes());
        }
    }
}

impl PartialEq for Words<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.len() == other.len() && self.iter().eq(other.iter())
    }
}

impl Eq for Words<'_> {}

impl fmt::Debug for Words<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        struct Hex(u16);
        impl fmt::Debug for Hex {
            fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                write!(f, "{:04X}h", self.0)
            }
        }
        f.debug_list().entries(self.iter().map(Hex)).finish()
    }
}

/// A request as it goes on the wire (PDU addresses, not the manual's communication addresses).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Request<'a> {
    /// 03h: read `quantity` holding registers from `address`.
    ReadHolding {
        /// The PDU address of the first register.
        address: u16,
        /// The number of registers.
        quantity: u16,
    },
    /// 04h: read `quantity` input registers from `address`.
    ReadInput {
        /// The PDU address of the first register.
        address: u16,
        /// The number of registers.
        quantity: u16,
    },
    /// 06h: write one register.
    WriteSingle {
        /// The register's PDU address.
        address: u16,
        /// The value.
        value: u16,
    },
    /// 08h sub-function 0000h: the drive returns `data` unchanged.
    LoopBack {
        /// The data.
        data: u16,
    },
    /// 10h: write consecutive registers from `address`.
    WriteMultiple {
        /// The PDU address of the first register.
        address: u16,
        /// The values, in address order.
        values: Words<'a>,
    },
    /// 01h: read `quantity` coils from `address`.
    ReadCoils {
        /// The PDU address of the first coil.
        address: u16,
        /// The number of coils.
        quantity: u16,
    },
    /// 02h: read `quantity` discrete inputs from `address`.
    ReadDiscreteInputs {
        /// The PDU address of the first input.
        address: u16,
        /// The number of inputs.
        quantity: u16,
    },
    /// 05h: write one coil (FF00h on, 0000h off on the wire).
    WriteCoil {
        /// The coil's PDU address.
        address: u16,
        /// On (`true`) or off.
        value: bool,
    },
    /// 0Fh: write consecutive coils from `address`.
    WriteCoils {
        /// The PDU address of the first coil.
        address: u16,
        /// The states, in address order.
        values: BitValues<'a>,
    },
}

/// Why a request cannot be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RequestError {
    /// Zero registers, or more than the Modbus limit for the function.
    #[error("{function:02X}h with {quantity} registers: Modbus allows 1 ..= {max}")]
    Quantity {
        /// The function code.
        function: u8,
        /// The number of registers.
        quantity: usize,
        /// The Modbus limit for the function.
        max: u16,
    },
    /// The registers would run past address FFFFh.
    #[error("{quantity} registers from {address:04X}h run past FFFFh")]
    AddressOverflow {
        /// The PDU address of the first register.
        address: u16,
        /// The number of registers.
        quantity: usize,
    },
    /// The output buffer is too small for the frame.
    #[error("frame of {needed} bytes does not fit a buffer of {available}")]
    Buffer {
        /// Bytes the frame needs.
        needed: usize,
        /// Bytes the buffer has.
        available: usize,
    },
}

impl Request<'_> {
    /// The function code.
    pub fn function(&self) -> u8 {
        match self {
            Request::ReadHolding { .. } => function::READ_HOLDING,
            Request::ReadInput { .. } => function::READ_INPUT,
            Request::WriteSingle { .. } => function::WRITE_SINGLE,
            Request::LoopBack { .. } => function::LOOP_BACK,
            Request::WriteMultiple { .. } => function::WRITE_MULTIPLE,
            Request::ReadCoils { .. } => function::READ_COILS,
            Request::ReadDiscreteInputs { .. } => function::READ_DISCRETE_INPUTS,
            Request::WriteCoil { .. } => function::WRITE_COIL,
            Request::WriteCoils { .. } => function::WRITE_COILS,
        }
    }

    /// Whether the request reads or writes coils or discrete inputs (01h, 02h, 05h, 0Fh).
    pub fn is_bits(&self) -> bool {
        matches!(
            self,
            Request::ReadCoils { .. }
                | Request::ReadDiscreteInputs { .. }
                | Request::WriteCoil { .. }
                | Request::WriteCoils { .. }
        )
    }

    /// First register address, if the function addresses registers.
    pub fn address(&self) -> Option<u16> {
        match *self {
            Request::ReadHolding { address, .. }
            | Request::ReadInput { address, .. }
            | Request::WriteSingle { address, .. }
            | Request::WriteMultiple { address, .. }
            | Request::ReadCoils { address, .. }
            | Request::ReadDiscreteInputs { address, .. }
            | Request::WriteCoil { address, .. }
            | Request::WriteCoils { address, .. } => Some(address),
            Request::LoopBack { .. } => None,
        }
    }

    /// Number of registers, coils or inputs read or written (0 for loop-back).
    pub fn quantity(&self) -> usize {
        match self {
            Request::ReadHolding { quantity, .. }
            | Request::ReadInput { quantity, .. }
            | Request::ReadCoils { quantity, .. }
            | Request::ReadDiscreteInputs { quantity, .. } => usize::from(*quantity),
            Request::WriteSingle { .. } | Request::WriteCoil { .. } => 1,
            Request::LoopBack { .. } => 0,
            Request::WriteMultiple { values, .. } => values.len(),
            Request::WriteCoils { values, .. } => values.len(),
        }
    }

    /// Whether the request reads (03h/04h, 01h/02h).
    pub fn is_read(&self) -> bool {
        matches!(
            self,
            Request::ReadHolding { .. }
                | Request::ReadInput { .. }
                | Request::ReadCoils { .. }
                | Request::ReadDiscreteInputs { .. }
        )
    }

    /// Length of the encoded PDU.
    pub fn pdu_len(&self) -> usize {
        match self {
            Request::WriteMultiple { values, .. } => 6 + 2 * values.len(),
            Request::WriteCoils { values, .. } => 6 + values.byte_count(),
            _ => 5,
        }
    }

    /// Length of the normal response PDU this request must get.
    pub fn response_pdu_len(&self) -> usize {
        match self {
            Request::ReadHolding { quantity, .. } | Request::ReadInput { quantity, .. } => {
                2 + 2 * usize::from(*quantity)
            }
            Request::ReadCoils { quantity, .. } | Request::ReadDiscreteInputs { quantity, .. } => {
                2 + usize::from(*quantity).div_ceil(8)
            }
            _ => 5,
        }
    }

    /// Checks the quantity and address range against the Modbus limits.
    pub fn validate(&self) -> Result<(), RequestError> {
        let (max, quantity) = match self {
            Request::ReadHolding { quantity, .. } | Request::ReadInput { quantity, .. } => {
                (MAX_READ, usize::from(*quantity))
            }
            Request::ReadCoils { quantity, .. } | Request::ReadDiscreteInputs { quantity, .. } => {
                (MAX_READ_BITS, usize::from(*quantity))
            }
            Request::WriteMultiple { values, .. } => (MAX_WRITE, values.len()),
            Request::WriteCoils { values, .. } => (MAX_WRITE_BITS, values.len()),
            Request::WriteSingle { .. } | Request::WriteCoil { .. } | Request::LoopBack { .. } => {
                return Ok(());
            }
        };
        if quantity == 0 || quantity > usize::from(max) {
            return Err(RequestError::Quantity {
                function: self.function(),
                quantity,
                max,
            });
        }
        let address = self.address().unwrap_or(0);
        if usize::from(address) + quantity > 0x1_0000 {
            return Err(RequestError::AddressOverflow { address, quantity });
        }
        Ok(())
    }

    /// Encodes the PDU into `out`; returns its length.
    pub fn encode(&self, out: &mut [u8]) -> Result<usize, RequestError> {
        self.validate()?;
        let len = self.pdu_len();
        if out.len() < len {
            return Err(RequestError::Buffer {
                needed: len,
                available: out.len(),
            });
        }
        out[0] = self.function();
        match *self {
            Request::ReadHolding { address, quantity }
            | Request::ReadInput { address, quantity }
            | Request::ReadCoils { address, quantity }
            | Request::ReadDiscreteInputs { address, quantity } => {
                put(out, 1, address);
                put(out, 3, quantity);
            }
            Request::WriteCoil { address, value } => {
                put(out, 1, address);
                put(out, 3, if value { COIL_ON } else { 0 });
            }
            Request::WriteCoils { address, values } => {
                put(out, 1, address);
                put(out, 3, values.len() as u16);
                out[5] = values.byte_count() as u8;
                values.write_packed(&mut out[6..len]);
            }
            Request::WriteSingle { address, value } => {
                put(out, 1, address);
                put(out, 3, value);
            }
            Request::LoopBack { data } => {
                put(out, 1, 0x0000);
                put(out, 3, data);
            }
            Request::WriteMultiple { address, values } => {
                put(out, 1, address);
                put(out, 3, values.len() as u16);
                out[5] = (2 * values.len()) as u8;
                values.write_be(&mut out[6..len]);
            }
        }
        Ok(len)
    }
}

fn put(out: &mut [u8], at: usize, word: u16) {
    out[at..at + 2].copy_from_slice(&word.to_be_bytes());
}

fn word(bytes: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_be_bytes([*bytes.get(at)?, *bytes.get(at + 1)?]))
}

/// A decoded response.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Response<'a> {
    /// 03h/04h: the registers read.
    Registers(Words<'a>),
    /// 06h: the echo of the written register.
    WriteSingle {
        /// The register's PDU address.
        address: u16,
        /// The value.
        value: u16,
    },
    /// 08h: the echoed data.
    LoopBack {
        /// The data.
        data: u16,
    },
    /// 10h: the echo of the start address and quantity.
    WriteMultiple {
        /// The PDU address of the first register.
        address: u16,
        /// The number of registers written.
        quantity: u16,
    },
    /// 01h/02h: the coils or discrete inputs read.
    Bits(BitValues<'a>),
    /// 05h: the echo of the written coil.
    WriteCoil {
        /// The coil's PDU address.
        address: u16,
        /// On or off.
        value: bool,
    },
    /// 0Fh: the echo of the start address and quantity.
    WriteCoils {
        /// The PDU address of the first coil.
        address: u16,
        /// The number of coils written.
        quantity: u16,
    },
    /// An exception response: the request's function and the drive's own code.
    Exception {
        /// The request's function code.
        function: u8,
        /// The drive's exception code.
        code: u8,
    },
}

impl Response<'_> {
    /// Length of the encoded PDU.
    pub fn pdu_len(&self) -> usize {
        match self {
            Response::Registers(w) => 2 + 2 * w.len(),
            Response::Bits(b) => 2 + b.byte_count(),
            Response::Exception { .. } => 2,
            _ => 5,
        }
    }

    /// Encodes the response PDU for the request function `function` (slave side, tests).
    pub fn encode(&self, function: u8, out: &mut [u8]) -> Result<usize, RequestError> {
        let len = self.pdu_len();
        if len > MAX_PDU || out.len() < len {
            return Err(RequestError::Buffer {
                needed: len,
                available: out.len().min(MAX_PDU),
            });
        }
        out[0] = function;
        match *self {
            Response::Registers(words) => {
                out[1] = (2 * words.len()) as u8;
                words.write_be(&mut out[2..len]);
            }
            Response::Bits(bits) => {
                out[1] = bits.byte_count() as u8;
                bits.write_packed(&mut out[2..len]);
            }
            Response::WriteCoil { address, value } => {
                put(out, 1, address);
                put(out, 3, if value { COIL_ON } else { 0 });
            }
            Response::WriteCoils { address, quantity } => {
                put(out, 1, address);
                put(out, 3, quantity);
            }
            Response::WriteSingle { address, value } => {
                put(out, 1, address);
                put(out, 3, value);
            }
            Response::LoopBack { data } => {
                put(out, 1, 0);
                put(out, 3, data);
            }
            Response::WriteMultiple { address, quantity } => {
                put(out, 1, address);
                put(out, 3, quantity);
            }
            Response::Exception { function, code } => {
                out[0] = function | function::EXCEPTION_BIT;
                out[1] = code;
            }
        }
        Ok(len)
    }
}

/// Why a received frame is not the answer to the request.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum FrameError {
    /// The frame is shorter or longer than its function code says.
    #[error("frame of {got} bytes, expected {expected}")]
    Length {
        /// The length its function code gives.
        expected: usize,
        /// The length received.
        got: usize,
    },
    /// The CRC does not match the frame.
    #[error("CRC {received:04X}h received, {computed:04X}h computed")]
    Crc {
        /// The CRC computed over the frame.
        computed: u16,
        /// The CRC the frame carries.
        received: u16,
    },
    /// The reply comes from another slave.
    #[error("reply from slave {got}, expected slave {expected}")]
    Slave {
        /// The slave asked.
        expected: u8,
        /// The slave that answered.
        got: u8,
    },
    /// The function code is neither the request's nor its exception code.
    #[error("function {got:02X}h in reply, expected {expected:02X}h")]
    Function {
        /// The request's function code.
        expected: u8,
        /// The function code in the reply.
        got: u8,
    },
    /// A function code the runtime does not implement.
    #[error("unknown function code {0:02X}h")]
    UnknownFunction(u8),
    /// The byte count of a read reply does not match the quantity requested.
    #[error("byte count {got} in reply, expected {expected}")]
    ByteCount {
        /// The byte count the quantity requested gives.
        expected: usize,
        /// The byte count in the reply.
        got: usize,
    },
    /// The address echo differs from the request.
    #[error("address {got:04X}h echoed, {expected:04X}h sent")]
    AddressEcho {
        /// The address sent.
        expected: u16,
        /// The address echoed.
        got: u16,
    },
    /// The quantity echo differs from the request.
    #[error("quantity {got} echoed, {expected} sent")]
    QuantityEcho {
        /// The quantity sent.
        expected: u16,
        /// The quantity echoed.
        got: u16,
    },
    /// The value echo (06h, 08h) differs from the request.
    #[error("value {got:04X}h echoed, {expected:04X}h sent")]
    ValueEcho {
        /// The value sent.
        expected: u16,
        /// The value echoed.
        got: u16,
    },
    /// The loop-back reply carries a sub-function other than 0000h.
    #[error("loop-back sub-function {0:04X}h, expected 0000h")]
    SubFunction(u16),
    /// Modbus TCP: the reply carries another transaction id (a late reply to an earlier request).
    #[error("transaction {got} in reply, expected {expected}")]
    Transaction {
        /// The request's transaction id.
        expected: u16,
        /// The reply's transaction id.
        got: u16,
    },
    /// Modbus TCP: the protocol identifier is not 0.
    #[error("protocol identifier {0}, expected 0")]
    Protocol(u16),
    /// Modbus TCP: the MBAP length field is outside 2 ..= 254.
    #[error("MBAP length {0} outside 2 ..= 254")]
    MbapLength(u16),
    /// Modbus TCP: the reply's unit identifier differs from the request's.
    #[error("unit {got} in reply, expected unit {expected}")]
    Unit {
        /// The request's unit identifier.
        expected: u8,
        /// The reply's unit identifier.
        got: u8,
    },
}

/// Length of a response PDU as its own header says, given at least its first two bytes.
/// `Ok(None)` when more bytes are needed to know.
pub fn response_pdu_len(pdu: &[u8]) -> Result<Option<usize>, FrameError> {
    let Some(&f) = pdu.first() else {
        return Ok(None);
    };
    if f & function::EXCEPTION_BIT != 0 {
        return Ok(Some(2));
    }
    match f {
        function::READ_HOLDING
        | function::READ_INPUT
        | function::READ_COILS
        | function::READ_DISCRETE_INPUTS => Ok(pdu.get(1).map(|&count| 2 + usize::from(count))),
        function::WRITE_SINGLE
        | function::LOOP_BACK
        | function::WRITE_MULTIPLE
        | function::WRITE_COIL
        | function::WRITE_COILS => Ok(Some(5)),
        other => Err(FrameError::UnknownFunction(other)),
    }
}

/// Length of a request PDU as its own header says. `Ok(None)` when more bytes are needed.
pub fn request_pdu_len(pdu: &[u8]) -> Result<Option<usize>, FrameError> {
    let Some(&f) = pdu.first() else {
        return Ok(None);
    };
    match f {
        function::READ_HOLDING
        | function::READ_INPUT
        | function::WRITE_SINGLE
        | function::LOOP_BACK
        | function::READ_COILS
        | function::READ_DISCRETE_INPUTS
        | function::WRITE_COIL => Ok(Some(5)),
        function::WRITE_MULTIPLE | function::WRITE_COILS => {
            Ok(pdu.get(5).map(|&count| 6 + usize::from(count)))
        }
        other => Err(FrameError::UnknownFunction(other)),
    }
}

/// Decodes the response PDU `pdu` to `request`, checking every echo.
pub fn decode_response<'a>(
    request: &Request<'_>,
    pdu: &'a [u8],
) -> Result<Response<'a>, FrameError> {
    let expected_function = request.function();
    let Some(&f) = pdu.first() else {
        return Err(FrameError::Length {
            expected: request.response_pdu_len(),
            got: 0,
        });
    };
    if f == expected_function | function::EXCEPTION_BIT {
        let [_, code] = *pdu else {
            return Err(FrameError::Length {
                expected: 2,
                got: pdu.len(),
            });
        };
        return Ok(Response::Exception {
            function: expected_function,
            code,
        });
    }
    if f != expected_function {
        return Err(FrameError::Function {
            expected: expected_function,
            got: f,
        });
    }
    match *request {
        Request::ReadHolding { quantity, .. } | Request::ReadInput { quantity, .. } => {
            let expected = 2 * usize::from(quantity);
            let count = usize::from(*pdu.get(1).ok_or(FrameError::Length {
                expected: 2 + expected,
                got: pdu.len(),
            })?);
            if count != expected {
                return Err(FrameError::ByteCount {
                    expected,
                    got: count,
                });
            }
            if pdu.len() != 2 + count {
                return Err(FrameError::Length {
                    expected: 2 + count,
                    got: pdu.len(),
                });
            }
            Ok(Response::Registers(Words::Wire(&pdu[2..])))
        }
        Request::ReadCoils { quantity, .. } | Request::ReadDiscreteInputs { quantity, .. } => {
            let expected = usize::from(quantity).div_ceil(8);
            let count = usize::from(*pdu.get(1).ok_or(FrameError::Length {
                expected: 2 + expected,
                got: pdu.len(),
            })?);
            if count != expected {
                return Err(FrameError::ByteCount {
                    expected,
                    got: count,
                });
            }
            if pdu.len() != 2 + count {
                return Err(FrameError::Length {
                    expected: 2 + count,
                    got: pdu.len(),
                });
            }
            Ok(Response::Bits(BitValues::Wire {
                bytes: &pdu[2..],
                count: usize::from(quantity),
            }))
        }
        Request::WriteCoil { address, value } => {
            let (a, v) = two_words(pdu)?;
            echo(address, a, if value { COIL_ON } else { 0 }, v)?;
            Ok(Response::WriteCoil { address: a, value })
        }
        Request::WriteCoils { address, values } => {
            let (a, q) = two_words(pdu)?;
            if a != address {
                return Err(FrameError::AddressEcho {
                    expected: address,
                    got: a,
                });
            }
            let quantity = values.len() as u16;
            if q != quantity {
                return Err(FrameError::QuantityEcho {
                    expected: quantity,
                    got: q,
                });
            }
            Ok(Response::WriteCoils {
                address: a,
                quantity: q,
            })
        }
        Request::WriteSingle { address, value } => {
            let (a, v) = two_words(pdu)?;
            echo(address, a, value, v)?;
            Ok(Response::WriteSingle {
                address: a,
                value: v,
            })
        }
        Request::LoopBack { data } => {
            let (sub, d) = two_words(pdu)?;
            if sub != 0 {
                return Err(FrameError::SubFunction(sub));
            }
            if d != data {
                return Err(FrameError::ValueEcho {
                    expected: data,
                    got: d,
                });
            }
            Ok(Response::LoopBack { data: d })
        }
        Request::WriteMultiple { address, values } => {
            let (a, q) = two_words(pdu)?;
            if a != address {
                return Err(FrameError::AddressEcho {
                    expected: address,
                    got: a,
                });
            }
            let quantity = values.len() as u16;
            if q != quantity {
                return Err(FrameError::QuantityEcho {
                    expected: quantity,
                    got: q,
                });
            }
            Ok(Response::WriteMultiple {
                address: a,
                quantity: q,
            })
        }
    }
}

fn two_words(pdu: &[u8]) -> Result<(u16, u16), FrameError> {
    if pdu.len() != 5 {
        return Err(FrameError::Length {
            expected: 5,
            got: pdu.len(),
        });
    }
    Ok((word(pdu, 1).unwrap_or(0), word(pdu, 3).unwrap_or(0)))
}

fn echo(address: u16, got_address: u16, value: u16, got_value: u16) -> Result<(), FrameError> {
    if address != got_address {
        return Err(FrameError::AddressEcho {
            expected: address,
            got: got_address,
        });
    }
    if value != got_value {
        return Err(FrameError::ValueEcho {
            expected: value,
            got: got_value,
        });
    }
    Ok(())
}

/// Why a slave rejects a request PDU (slave side: simulators and tests).
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum RequestDecodeError {
    /// The function is not one of 01h, 02h, 03h, 04h, 05h, 06h, 08h, 0Fh, 10h: answer exception
    /// 01h.
    #[error("function {0:02X}h not implemented")]
    Function(u8),
    /// A malformed request (and a 05h with a value other than FF00h or 0000h): answer
    /// exception 03h.
    #[error("malformed {0:02X}h request")]
    Malformed(u8),
    /// Loop-back with a sub-function other than 0000h: answer exception 01h.
    #[error("loop-back sub-function {0:04X}h not implemented")]
    SubFunction(u16),
    /// Empty PDU.
    #[error("empty request")]
    Empty,
}

/// Decodes a request PDU (slave side).
pub fn decode_request(pdu: &[u8]) -> Result<Request<'_>, RequestDecodeError> {
    let &f = pdu.first().ok_or(RequestDecodeError::Empty)?;
    let malformed = RequestDecodeError::Malformed(f);
    let request = match f {
        function::READ_HOLDING
        | function::READ_INPUT
        | function::WRITE_SINGLE
        | function::LOOP_BACK
        | function::READ_COILS
        | function::READ_DISCRETE_INPUTS
        | function::WRITE_COIL => {
            let (a, b) = two_words(pdu).map_err(|_| malformed)?;
            match f {
                function::READ_COILS => Request::ReadCoils {
                    address: a,
                    quantity: b,
                },
                function::READ_DISCRETE_INPUTS => Request::ReadDiscreteInputs {
                    address: a,
                    quantity: b,
                },
                function::WRITE_COIL => Request::WriteCoil {
                    address: a,
                    value: match b {
                        COIL_ON => true,
                        0 => false,
                        _ => return Err(malformed),
                    },
                },
                function::READ_HOLDING => Request::ReadHolding {
                    address: a,
                    quantity: b,
                },
                function::READ_INPUT => Request::ReadInput {
                    address: a,
                    quantity: b,
                },
                function::WRITE_SINGLE => Request::WriteSingle {
                    address: a,
                    value: b,
                },
                _ if a != 0 => return Err(RequestDecodeError::SubFunction(a)),
                _ => Request::LoopBack { data: b },
            }
        }
        function::WRITE_MULTIPLE => {
            let address = word(pdu, 1).ok_or(malformed)?;
            let quantity = word(pdu, 3).ok_or(malformed)?;
            let count = usize::from(*pdu.get(5).ok_or(malformed)?);
            if count != 2 * usize::from(quantity) || pdu.len() != 6 + count {
                return Err(malformed);
            }
            Request::WriteMultiple {
                address,
                values: Words::Wire(&pdu[6..]),
            }
        }
        function::WRITE_COILS => {
            let address = word(pdu, 1).ok_or(malformed)?;
            let quantity = word(pdu, 3).ok_or(malformed)?;
            let count = usize::from(*pdu.get(5).ok_or(malformed)?);
            if count != usize::from(quantity).div_ceil(8) || pdu.len() != 6 + count {
                return Err(malformed);
            }
            Request::WriteCoils {
                address,
                values: BitValues::Wire {
                    bytes: &pdu[6..],
                    count: usize::from(quantity),
                },
            }
        }
        other => return Err(RequestDecodeError::Function(other)),
    };
    request.validate().map_err(|_| malformed)?;
    Ok(request)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn read_round_trip_and_echo_checks() {
        let req = Request::ReadHolding {
            address: 0x20,
            quantity: 2,
        };
        let mut buf = [0u8; MAX_PDU];
        let n = req.encode(&mut buf).unwrap();
        assert_eq!(&buf[..n], &[0x03, 0x00, 0x20, 0x00, 0x02]);
        let pdu = [0x03, 0x04, 0x12, 0x34, 0xAB, 0xCD];
        let Response::Registers(words) = decode_response(&req, &pdu).unwrap() else {
            panic!("not registers");
        };
        assert_eq!(words, Words::Native(&[0x1234, 0xABCD]));
        assert_eq!(
            decode_response(&req, &[0x03, 0x02, 0x12, 0x34]),
            Err(FrameError::ByteCount {
                expected: 4,
                got: 2
            })
        );
        assert_eq!(
            decode_response(&req, &[0x04, 0x04, 0, 0, 0, 0]),
            Err(FrameError::Function {
                expected: 3,
                got: 4
            })
        );
        assert_eq!(
            decode_response(&req, &[0x83, 0x02]),
            Ok(Response::Exception {
                function: 3,
                code: 2
            })
        );
        assert!(decode_response(&req, &[0x83]).is_err());
        assert!(decode_response(&req, &[]).is_err());
    }

    #[test]
    fn write_echoes_are_checked() {
        let req = Request::WriteSingle {
            address: 1,
            value: 3,
        };
        assert!(decode_response(&req, &[0x06, 0, 1, 0, 3]).is_ok());
        assert_eq!(
            decode_response(&req, &[0x06, 0, 2, 0, 3]),
            Err(FrameError::AddressEcho {
                expected: 1,
                got: 2
            })
        );
        assert_eq!(
            decode_response(&req, &[0x06, 0, 1, 0, 4]),
            Err(FrameError::ValueEcho {
                expected: 3,
                got: 4
            })
        );
        let req = Request::WriteMultiple {
            address: 1,
            values: Words::Native(&[1, 2]),
        };
        assert!(decode_response(&req, &[0x10, 0, 1, 0, 2]).is_ok());
        assert_eq!(
            decode_response(&req, &[0x10, 0, 1, 0, 3]),
            Err(FrameError::QuantityEcho {
                expected: 2,
                got: 3
            })
        );
        let req = Request::LoopBack { data: 0xA537 };
        assert_eq!(
            decode_response(&req, &[0x08, 0, 1, 0xA5, 0x37]),
            Err(FrameError::SubFunction(1))
        );
    }

    #[test]
    fn limits_are_refused() {
        let mut buf = [0u8; MAX_PDU];
        for quantity in [0, 126] {
            assert!(matches!(
                Request::ReadInput {
                    address: 0,
                    quantity
                }
                .encode(&mut buf),
                Err(RequestError::Quantity { .. })
            ));
        }
        assert!(matches!(
            Request::ReadHolding {
                address: 0xFFFF,
                quantity: 2
            }
            .encode(&mut buf),
            Err(RequestError::AddressOverflow { .. })
        ));
        assert!(matches!(
            Request::WriteMultiple {
                address: 0,
                values: Words::Native(&[0; 124])
            }
            .encode(&mut buf),
            Err(RequestError::Quantity { .. })
        ));
        assert!(matches!(
            Request::LoopBack { data: 0 }.encode(&mut buf[..3]),
            Err(RequestError::Buffer { .. })
        ));
    }

    #[test]
    fn request_decoding_rejects_malformed_pdus() {
        assert_eq!(
            decode_request(&[0x10, 0, 1, 0, 2, 3, 0, 0, 0]),
            Err(RequestDecodeError::Malformed(0x10))
        );
        assert_eq!(
            decode_request(&[0x07]),
            Err(RequestDecodeError::Function(7))
        );
        assert_eq!(
            decode_request(&[0x08, 0, 4, 0, 0]),
            Err(RequestDecodeError::SubFunction(4))
        );
        assert_eq!(
            decode_request(&[0x03, 0, 0, 0, 0]),
            Err(RequestDecodeError::Malformed(3))
        );
    }
}
