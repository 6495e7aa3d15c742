//! How a simulator is started ([`SimOptions`]) and why it cannot be ([`SimError`]).

use std::collections::BTreeMap;
use std::sync::Arc;

use drivemap_runtime::core::scale::ValueError;

use crate::clock::{Clock, SystemClock};

use super::RolesChoice;

/// How to start a simulator.
#[derive(Debug, Clone)]
pub struct SimOptions {
    /// Slave address; default: the map's default slave address, else 1.
    pub slave: Option<u8>,
    /// Variant axis id → option id; axes not named take their first option.
    pub variants: BTreeMap<String, String>,
    /// External quantities (drive rating...); one not given is [`Plausible::EXTERNAL`], or
    /// [`Plausible::MAX_FREQUENCY`] for the maximum frequency.
    ///
    /// [`Plausible::EXTERNAL`]: crate::roles::Plausible::EXTERNAL
    /// [`Plausible::MAX_FREQUENCY`]: crate::roles::Plausible::MAX_FREQUENCY
    pub externals: BTreeMap<String, f64>,
    /// Power-on values, applied last: register id, parameter number or name → engineering
    /// value (a code for enumerations, the raw word for bit fields and plain words).
    pub initial: Vec<(String, f64)>,
    /// Whether to run the drive model the map's roles describe.
    pub roles: RolesChoice,
    /// Time for the drive model.
    pub clock: Arc<dyn Clock>,
    /// Power on with the source parameters (`command_source`, `reference_source`) selecting
    /// the network on this link, as an installer would set them (one parameter may select only
    /// one link: V7 n003 = 2 for RTU, 3 for TCP); `None`: they start at the manual's factory
    /// setting, and the drive ignores network run commands and references.
    pub network_source: Option<drivemap_runtime::core::profile::TransportKind>,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions {
            slave: None,
            variants: BTreeMap::new(),
            externals: BTreeMap::new(),
            initial: Vec::new(),
            roles: RolesChoice::FromMap,
            clock: Arc::new(SystemClock::new()),
            network_source: None,
        }
    }
}

impl SimOptions {
    /// Defaults: the map's slave address, base variants, the drive model from the map's roles, the system clock.
    pub fn new() -> SimOptions {
        SimOptions::default()
    }

    /// Sets the slave address.
    pub fn slave(mut self, slave: u8) -> SimOptions {
        self.slave = Some(slave);
        self
    }

    /// Sets the clock.
    pub fn clock(mut self, clock: Arc<dyn Clock>) -> SimOptions {
        self.clock = clock;
        self
    }

    /// Chooses a variant option on an axis.
    pub fn variant(mut self, axis: &str, option: &str) -> SimOptions {
        self.variants.insert(axis.into(), option.into());
        self
    }

    /// Sets an external quantity.
    pub fn external(mut self, name: &str, value: f64) -> SimOptions {
        self.externals.insert(name.into(), value);
        self
    }

    /// Sets a register's power-on value (engineering units).
    pub fn set(mut self, register: &str, value: f64) -> SimOptions {
        self.initial.push((register.into(), value));
        self
    }

    /// Powers on with the network selected as the source of run commands and the reference on
    /// link `kind` ([`SimOptions::network_source`](SimOptions#structfield.network_source)).
    pub fn network_source(
        mut self,
        kind: drivemap_runtime::core::profile::TransportKind,
    ) -> SimOptions {
        self.network_source = Some(kind);
        self
    }

    /// Chooses whether to run the drive model.
    pub fn roles(mut self, roles: RolesChoice) -> SimOptions {
        self.roles = roles;
        self
    }
}

/// Why a simulator cannot start, or a register cannot be set.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    /// No register by that name.
    #[error(transparent)]
    NotFound(#[from] drivemap_live::lookup::NotFound),
    /// A value the register cannot hold.
    #[error("cannot set {register} to {value}: {error}")]
    Value {
        /// The register.
        register: String,
        /// The value.
        value: f64,
        /// Why it cannot hold it.
        error: ValueError,
    },
    /// A slave address outside the drive's range.
    #[error("slave address {slave} is outside {drive}'s range {min} ..= {max}")]
    Slave {
        /// The drive's id.
        drive: String,
        /// The slave address asked for.
        slave: u8,
        /// The lowest address the drive answers to.
        min: u8,
        /// The highest.
        max: u8,
    },
    /// A variant the map does not define.
    #[error("{drive} has no variant `{option}` on axis `{axis}`; known: {known}")]
    Variant {
        /// The drive's id.
        drive: String,
        /// The variant axis asked for.
        axis: String,
        /// The option asked for.
        option: String,
        /// The variants the map defines (`axis=option`, listed).
        known: String,
    },
    /// An external quantity the map does not use.
    #[error("{drive} has no external quantity `{name}`; known: {known}")]
    External {
        /// The drive's id.
        drive: String,
        /// The quantity asked for.
        name: String,
        /// The external quantities the map uses, listed.
        known: String,
    },
}

pub(super) fn known_list(items: impl IntoIterator<Item = String>) -> String {
    let v: Vec<String> = items.into_iter().collect();
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}
