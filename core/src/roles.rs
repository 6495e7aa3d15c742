//! Roles: which register or field of a drive plays each standard part of a variable-frequency
//! drive — the run command, the direction, the fault reset, the frequency reference, the output
//! monitors, the status bits — as the map says, with the manual's line.
//!
//! Ids differ from drive to drive (`run`, `run_command`, `forward_run`; the ACN says *forward*
//! where others say *reverse*; some drives report state as codes of a multi-bit field, others as
//! bits), so a map names, per role, its own register and field and, for a multi-bit field, the
//! codes that mean "on" and "off". The lowering pass turns that into [`Roles`]: plan rows and bit
//! positions, decided once. The drive trait of the runtime, the simulator and the demo all read
//! these places; none of them knows a drive by name.

/// A standard part of a variable-frequency drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[non_exhaustive]
pub enum Role {
    // Commands: fields the master writes.
    /// Run (on) / stop (off), in the direction the direction role gives.
    Run,
    /// Run forward (on) / stop (off): a 2-wire terminal that runs in one direction.
    RunForward,
    /// Run reverse (on) / stop (off): a 2-wire terminal that runs in one direction.
    RunReverse,
    /// Direction: reverse (on) / forward (off).
    Reverse,
    /// Fault reset (on), released (off); [`Edge`] says whether the drive acts on the off → on
    /// transition, on the level, or the manual does not print which.
    FaultReset,
    /// Switches to the drive's operating (DRV) mode, where it accepts run commands.
    ToDriveMode,
    /// Switches to the drive's program (PRG) mode, where parameters are writable.
    ToProgramMode,
    // Setpoints and parameters: whole registers the master writes.
    /// Frequency reference (Hz).
    FrequencyReference,
    /// Acceleration time (s, from 0 to the maximum frequency).
    AccelTime,
    /// Deceleration time (s, from the maximum frequency to 0).
    DecelTime,
    /// Maximum output frequency (Hz): what accel and decel times are measured against.
    MaxFrequency,
    // Monitors: whole registers the master reads.
    /// Output frequency (Hz).
    OutputFrequency,
    /// The frequency reference in force (Hz).
    ReferenceMonitor,
    /// Output current (A).
    OutputCurrent,
    /// Output voltage (V).
    OutputVoltage,
    /// DC bus voltage (V).
    DcBusVoltage,
    /// The code of the active fault (0 or the map's no-fault code when none is active).
    FaultCode,
    /// The code of the last fault the drive recorded (its fault history), kept after a reset.
    LastFault,
    // Status: fields the master reads.
    /// Running (output live or run commanded).
    Running,
    /// Turning, or about to turn, in reverse.
    Reversing,
    /// A fault has tripped the drive.
    Fault,
    /// An alarm (warning) without a trip.
    Alarm,
    /// Ready to run.
    Ready,
    /// Output frequency zero.
    ZeroSpeed,
    /// Output frequency at the reference.
    SpeedAgree,
    /// Ramping up towards the reference.
    Accelerating,
    /// Ramping down towards a lower reference.
    Decelerating,
    /// Ramping down after a stop command.
    Stopping,
    /// In operating (DRV) mode.
    DriveMode,
    // Sources: the parameters that select where the drive takes its commands from.
    /// Where the drive takes its run commands from: the parameter (or the status field that
    /// reports it) and the codes meaning "the network" (V7 n003 = 2 over RTU).
    CommandSource,
    /// Where the drive takes its frequency reference from (V7 n004 = 6 over RTU).
    ReferenceSource,
}

/// What a role is, and so what it may name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RoleKind {
    /// A field the master writes: a 1-bit field (1 = on) or a multi-bit field with its `on` code
    /// and `off` code.
    Command,
    /// A number register the master writes (or an external quantity, for the maximum frequency).
    Setpoint,
    /// A register the master reads.
    Monitor,
    /// A field the master reads: a 1-bit field (1 = on) or the codes of a multi-bit field that
    /// mean "on".
    Status,
    /// A readable parameter (or status field) whose `on` codes say the drive takes commands
    /// from the network on the place's transports; the drive ignores network commands otherwise.
    Source,
}

impl Role {
    /// Every role, in the order of the schema documentation.
    pub const ALL: &'static [Role] = &[
        Role::Run,
        Role::RunForward,
        Role::RunReverse,
        Role::Reverse,
        Role::FaultReset,
        Role::ToDriveMode,
        Role::ToProgramMode,
        Role::FrequencyReference,
        Role::AccelTime,
        Role::DecelTime,
        Role::MaxFrequency,
        Role::OutputFrequency,
        Role::ReferenceMonitor,
        Role::OutputCurrent,
        Role::OutputVoltage,
        Role::DcBusVoltage,
        Role::FaultCode,
        Role::LastFault,
        Role::Running,
        Role::Reversing,
        Role::Fault,
        Role::Alarm,
        Role::Ready,
        Role::ZeroSpeed,
        Role::SpeedAgree,
        Role::Accelerating,
        Role::Decelerating,
        Role::Stopping,
        Role::DriveMode,
        Role::CommandSource,
        Role::ReferenceSource,
    ];

    /// The key of this role under `roles:` in a map.
    pub const fn id(self) -> &'static str {
        match self {
            Role::Run => "run",
            Role::RunForward => "run_forward",
            Role::RunReverse => "run_reverse",
            Role::Reverse => "reverse",
            Role::FaultReset => "fault_reset",
            Role::ToDriveMode => "to_drive_mode",
            Role::ToProgramMode => "to_program_mode",
            Role::FrequencyReference => "frequency_reference",
            Role::AccelTime => "accel_time",
            Role::DecelTime => "decel_time",
            Role::MaxFrequency => "max_frequency",
            Role::OutputFrequency => "output_frequency",
            Role::ReferenceMonitor => "reference_monitor",
            Role::OutputCurrent => "output_current",
            Role::OutputVoltage => "output_voltage",
            Role::DcBusVoltage => "dc_bus_voltage",
            Role::FaultCode => "fault_code",
            Role::LastFault => "last_fault",
            Role::Running => "running",
            Role::Reversing => "reversing",
            Role::Fault => "fault",
            Role::Alarm => "alarm",
            Role::Ready => "ready",
            Role::ZeroSpeed => "zero_speed",
            Role::SpeedAgree => "speed_agree",
            Role::Accelerating => "accelerating",
            Role::Decelerating => "decelerating",
            Role::Stopping => "stopping",
            Role::DriveMode => "drive_mode",
            Role::CommandSource => "command_source",
            Role::ReferenceSource => "reference_source",
        }
    }

    /// The role with this key.
    pub fn from_id(id: &str) -> Option<Role> {
        Role::ALL.iter().copied().find(|r| r.id() == id)
    }

    /// What the role is.
    pub const fn kind(self) -> RoleKind {
        match self {
            Role::Run
            | Role::RunForward
            | Role::RunReverse
            | Role::Reverse
            | Role::FaultReset
            | Role::ToDriveMode
            | Role::ToProgramMode => RoleKind::Command,
            Role::FrequencyReference | Role::AccelTime | Role::DecelTime | Role::MaxFrequency => {
                RoleKind::Setpoint
            }
            Role::OutputFrequency
            | Role::ReferenceMonitor
            | Role::OutputCurrent
            | Role::OutputVoltage
            | Role::DcBusVoltage
            | Role::FaultCode
            | Role::LastFault => RoleKind::Monitor,
            Role::Running
            | Role::Reversing
            | Role::Fault
            | Role::Alarm
            | Role::Ready
            | Role::ZeroSpeed
            | Role::SpeedAgree
            | Role::Accelerating
            | Role::Decelerating
            | Role::Stopping
            | Role::DriveMode => RoleKind::Status,
            Role::CommandSource | Role::ReferenceSource => RoleKind::Source,
        }
    }

    /// The unit a number role is in, where it has one: a register playing it must convert to
    /// this unit.
    pub const fn unit(self) -> Option<&'static str> {
        match self {
            Role::FrequencyReference
            | Role::MaxFrequency
            | Role::OutputFrequency
            | Role::ReferenceMonitor => Some("Hz"),
            Role::AccelTime | Role::DecelTime => Some("s"),
            Role::OutputCurrent => Some("A"),
            Role::OutputVoltage | Role::DcBusVoltage => Some("V"),
            _ => None,
        }
    }
}

/// A field of a register playing a command or status role.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FieldRole {
    /// The register's row in the drive's plan (`REGISTERS`).
    pub row: u16,
    /// Lowest bit of the field.
    pub lsb: u8,
    /// Width in bits.
    pub width: u8,
    /// Codes that mean the role holds. A command writes the first; a status holds while the
    /// field shows any of them.
    pub on: &'static [u16],
    /// The code that releases a command (stop, forward, reset released); for a status, the code
    /// the field shows when the role does not hold, where the map says.
    pub off: Option<u16>,
    /// Whether the drive acts on the off → on transition only (a reset must be released before
    /// the next), on the level, or the manual does not print which.
    pub edge: Edge,
}

/// How a drive acts on a command field, as the manual prints it (or does not).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Edge {
    /// The drive acts while the field shows the `on` code (the default for a command).
    #[default]
    Level,
    /// The drive acts on the off → on transition only: the field must be released before it
    /// acts again.
    Edge,
    /// The manual does not print whether the drive acts on the transition or the level; the
    /// map's reason. The drive trait then does what is safe for both: a momentary command (the
    /// fault reset) is released before it is set where it may be set, and released after.
    NotPrinted(&'static str),
}

impl Edge {
    /// Whether a command must be released before it is set again for the drive to act: on an
    /// edge, and where the manual does not print which (safe for both).
    pub const fn needs_release_first(self) -> bool {
        !matches!(self, Edge::Level)
    }

    /// How the map's documentation shows it: "edge", "level" or "not printed".
    pub const fn describe(self) -> &'static str {
        match self {
            Edge::Level => "level",
            Edge::Edge => "edge",
            Edge::NotPrinted(_) => "not printed",
        }
    }
}

impl FieldRole {
    /// The field's bits in the register's word.
    pub const fn mask(&self) -> u16 {
        ((((1u32 << self.width) - 1) << self.lsb) & 0xFFFF) as u16
    }

    /// The field's code in `word`.
    pub const fn get(&self, word: u16) -> u16 {
        (word & self.mask()) >> self.lsb
    }

    /// `word` with the field set to `code`.
    pub const fn put(&self, word: u16, code: u16) -> u16 {
        (word & !self.mask()) | ((code << self.lsb) & self.mask())
    }

    /// Whether `word` shows the role holding.
    pub fn holds(&self, word: u16) -> bool {
        self.on.contains(&self.get(word))
    }

    /// The code a command writes to set (`true`) or release (`false`) the role. A release with
    /// no `off` code writes 0.
    pub fn code(&self, on: bool) -> u16 {
        if on {
            self.on.first().copied().unwrap_or(1)
        } else {
            self.off.unwrap_or(0)
        }
    }
}

/// A field of a register playing a number role (a fault code in the status word's high byte):
/// its bits, whether they are two's complement, and the decimal scale of one count in the
/// role's unit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NumberField {
    /// The register's row in the drive's plan (`REGISTERS`).
    pub row: u16,
    /// Lowest bit of the field.
    pub lsb: u8,
    /// Width in bits (1..=16).
    pub width: u8,
    /// The field is two's complement (its top bit is the sign).
    pub signed: bool,
    /// One count in the role's unit (1 for a code).
    pub scale: crate::scale::Decimal,
}

impl NumberField {
    /// The field's bits in the register's word.
    pub const fn mask(&self) -> u16 {
        ((((1u32 << self.width) - 1) << self.lsb) & 0xFFFF) as u16
    }

    /// The field's raw bits in `word`, unsigned.
    pub const fn bits(&self, word: u16) -> u16 {
        (word & self.mask()) >> self.lsb
    }

    /// The count the field holds in `word`: sign-extended where the field is signed.
    pub const fn get(&self, word: u16) -> i64 {
        let bits = self.bits(word) as i64;
        if self.signed && self.width > 0 && bits >> (self.width - 1) & 1 == 1 {
            bits - (1i64 << self.width)
        } else {
            bits
        }
    }

    /// The counts the field can hold.
    pub const fn range(&self) -> crate::scale::RawRange {
        let span = 1i64 << self.width;
        if self.signed {
            crate::scale::RawRange {
                min: -(span / 2),
                max: span / 2 - 1,
            }
        } else {
            crate::scale::RawRange {
                min: 0,
                max: span - 1,
            }
        }
    }

    /// `word` with the field set to `count`, or `None` when the field cannot hold it.
    pub const fn put(&self, word: u16, count: i64) -> Option<u16> {
        let r = self.range();
        if count < r.min || count > r.max {
            return None;
        }
        let bits = (count & ((1i64 << self.width) - 1)) as u16;
        Some((word & !self.mask()) | ((bits << self.lsb) & self.mask()))
    }

    /// The value the field holds in `word`, in the role's unit.
    pub fn value(&self, word: u16) -> f64 {
        self.scale.decode(self.get(word))
    }
}

/// Where a role lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// A whole register: its row in the drive's plan.
    Register(u16),
    /// A field of a register playing a command, status or source role.
    Field(FieldRole),
    /// A field of a register playing a number role (setpoint or monitor).
    NumberField(NumberField),
    /// An external quantity of the map (a setting the application supplies, such as a maximum
    /// frequency with no register): its quantity slot in the drive's settings.
    External {
        /// Quantity slot ([`SettingsView::quantity`](crate::plan::SettingsView::quantity)).
        slot: u8,
        /// The quantity's name in the map.
        name: &'static str,
    },
}

impl Target {
    /// The plan row the role reads or writes, if it is a register or a field.
    pub const fn row(&self) -> Option<u16> {
        match self {
            Target::Register(row) => Some(*row),
            Target::Field(f) => Some(f.row),
            Target::NumberField(f) => Some(f.row),
            Target::External { .. } => None,
        }
    }
}

/// One place a role lives. A role may have several (the serial register, the broadcast one, the
/// TCP option card's); users take the first that is usable on their link.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Place {
    /// The role.
    pub role: Role,
    /// Where.
    pub target: Target,
    /// The links the place holds on (every one unless the map says): a source role's codes
    /// differ by link (V7 n003 = 2 for the built-in RTU port, 3 for the TCP option card).
    pub transports: crate::rule::Transports,
    /// The manual line that says so (`file:line`).
    pub source: &'static str,
    /// Another role whose place is the same register (or the same bits of it), as the map
    /// says (`shared_with`, on either of the two): writing one writes the other. One ramp
    /// register for both directions gives `accel_time` and `decel_time` each other.
    pub shared_with: Option<Role>,
}

/// The roles of a drive, as its map gives them: every place, in the order of [`Role::ALL`] and,
/// within a role, of the map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Roles {
    /// Every place.
    pub places: &'static [Place],
    /// The drive's command profile (a control-word state machine), where the map gives one:
    /// then run, stop and fault reset walk it instead of writing run and reset fields.
    pub profile: Option<&'static crate::command_profile::CommandProfile>,
}

impl Roles {
    /// A drive whose map gives no roles.
    pub const NONE: Roles = Roles {
        places: &[],
        profile: None,
    };

    /// The places of `role`, in the map's order.
    pub fn of(&self, role: Role) -> impl Iterator<Item = &'static Place> + '_ {
        self.places.iter().filter(move |p| p.role == role)
    }

    /// Whether the map gives `role`.
    pub fn has(&self, role: Role) -> bool {
        self.of(role).next().is_some()
    }

    /// Whether the map gives any role (or a command profile).
    pub fn is_empty(&self) -> bool {
        self.places.is_empty() && self.profile.is_none()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_are_unique() {
        for (i, r) in Role::ALL.iter().enumerate() {
            assert_eq!(Role::from_id(r.id()), Some(*r));
            assert!(Role::ALL[..i].iter().all(|o| o.id() != r.id()));
        }
        assert_eq!(Role::from_id("runn"), None);
    }

    #[test]
    fn a_multi_bit_field_is_read_and_written_in_place() {
        // A 2-bit run code in bits 4-5: 01b stop, 10b run.
        let f = FieldRole {
            row: 0,
            lsb: 4,
            width: 2,
            on: &[2],
            off: Some(1),
            edge: Edge::Level,
        };
        assert_eq!(f.mask(), 0x0030);
        assert_eq!(f.put(0xFFFF, f.code(true)), 0xFFEF);
        assert_eq!(f.put(0x0000, f.code(false)), 0x0010);
        assert!(f.holds(0x0020));
        assert!(!f.holds(0x0010));
        assert!(!f.holds(0x0030));
    }

    #[test]
    fn a_bit_defaults_to_one_on_zero_off() {
        let f = FieldRole {
            row: 3,
            lsb: 15,
            width: 1,
            on: &[1],
            off: Some(0),
            edge: Edge::Edge,
        };
        assert_eq!(f.put(0, f.code(true)), 0x8000);
        assert_eq!(f.put(0xFFFF, f.code(false)), 0x7FFF);
    }

    #[test]
    fn edge_and_not_printed_need_a_release_first_level_does_not() {
        assert!(!Edge::Level.needs_release_first());
        assert!(Edge::Edge.needs_release_first());
        assert!(Edge::NotPrinted("no timing diagram").needs_release_first());
        assert_eq!(Edge::NotPrinted("x").describe(), "not printed");
    }

    #[test]
    fn a_signed_byte_reads_and_writes_in_place() {
        // A signed high byte: 0xFE is -2, the low byte is kept.
        let f = NumberField {
            row: 0,
            lsb: 8,
            width: 8,
            signed: true,
            scale: crate::scale::Decimal::ONE,
        };
        assert_eq!(f.get(0xFE34), -2);
        assert_eq!(f.get(0x7F00), 127);
        assert_eq!(f.get(0x8000), -128);
        assert_eq!(f.put(0x1234, -1), Some(0xFF34));
        assert_eq!(f.put(0x1234, 127), Some(0x7F34));
        assert_eq!(f.put(0x1234, 128), None);
        assert_eq!(f.put(0x1234, -129), None);
        let u = NumberField { signed: false, ..f };
        assert_eq!(u.get(0xFE34), 254);
        assert_eq!(u.put(0, -1), None);
        assert_eq!(u.put(0x00AB, 255), Some(0xFFAB));
        // A low 4-bit field, scale 0.5.
        let n = NumberField {
            row: 0,
            lsb: 0,
            width: 4,
            signed: false,
            scale: crate::scale::Decimal::new(5, 1),
        };
        assert_eq!(n.value(0xFFF3), 1.5);
        // A whole word, signed.
        let w = NumberField {
            row: 0,
            lsb: 0,
            width: 16,
            signed: true,
            scale: crate::scale::Decimal::ONE,
        };
        assert_eq!(w.get(0xFFFF), -1);
        assert_eq!(w.put(0, -32768), Some(0x8000));
    }
}
