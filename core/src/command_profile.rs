//! Command profiles: a drive run through a control-word state machine (CiA 402, PROFIdrive, the
//! ABB Drives profile) rather than by one run bit, as its map gives it (`profile:`).
//!
//! The drive reports its state in a status word: each state is a mask and a value (CiA 402
//! *operation enabled* is `xxxx xxxx x01x 0111`: mask `0x006F`, value `0x0027`). The master
//! moves it by writing the control word: each transition is a word (with the bits the master
//! keeps from its own composition, such as a direction bit), the states it is taken from and the
//! state it leads to, with a time limit. What `run`, `stop` (ramp), `coast`, `quick_stop` and
//! `reset_fault` mean are paths: the transitions to take, in order of preference, and the states
//! that end the path. The lowering pass decides all of it once; the drive trait walks a path
//! (reads the state, writes the one transition that leaves it, waits for the state it leads
//! to), and the simulator follows the same data. Nothing here knows a profile by name.

/// One state of the machine, as the status word shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ProfileState {
    /// The state's id (`operation_enabled`).
    pub id: &'static str,
    /// The bits of the status word that decide the state.
    pub mask: u16,
    /// What those bits show in this state.
    pub value: u16,
    /// The manual line that prints the state (`file:line`).
    pub source: &'static str,
}

impl ProfileState {
    /// Whether status word `word` shows this state.
    pub const fn shows(&self, word: u16) -> bool {
        word & self.mask == self.value
    }
}

/// One transition: a control word that moves the drive from one of `from` to `to`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Transition {
    /// The transition's id (`enable_operation`).
    pub id: &'static str,
    /// The control word to write.
    pub word: u16,
    /// Bits the master keeps from its own composition of the control word (the direction bit,
    /// command fields of the map's roles) instead of taking them from `word`.
    pub keep: u16,
    /// Bits the drive acts on when they rise (a fault acknowledge): written cleared first where
    /// they may be set, then set, then cleared again. 0 for a level transition.
    pub edge: u16,
    /// The states (indices into [`CommandProfile::states`]) the drive takes it from.
    pub from: &'static [u8],
    /// The state it leads to.
    pub to: u8,
    /// How long the drive may take to show `to` (ms).
    pub limit_ms: u32,
    /// The manual line that prints the word (`file:line`).
    pub source: &'static str,
}

impl Transition {
    /// The word written when the master's own composition is `base`: `word`, with the `keep`
    /// bits from `base`.
    pub const fn compose(&self, base: u16) -> u16 {
        (self.word & !self.keep) | (base & self.keep)
    }

    /// Whether control word `word` asks for this transition: it agrees with `word` on every bit
    /// the transition decides (all but `keep`).
    pub const fn asked_by(&self, word: u16) -> bool {
        (word ^ self.word) & !self.keep == 0
    }

    /// Whether it is taken from state `state`.
    pub fn leaves(&self, state: u8) -> bool {
        self.from.contains(&state)
    }
}

/// What a path is for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PathKind {
    /// Run (the target state drives the motor).
    Run,
    /// Stop on the ramp.
    Stop,
    /// Coast to a stop (the output off at once).
    Coast,
    /// Quick stop (the drive's quick-stop ramp).
    QuickStop,
    /// Acknowledge a fault.
    ResetFault,
}

impl PathKind {
    /// Every path kind, in the order of the schema documentation.
    pub const ALL: [PathKind; 5] = [
        PathKind::Run,
        PathKind::Stop,
        PathKind::Coast,
        PathKind::QuickStop,
        PathKind::ResetFault,
    ];

    /// The key of this path under `profile.paths` in a map.
    pub const fn id(self) -> &'static str {
        match self {
            PathKind::Run => "run",
            PathKind::Stop => "stop",
            PathKind::Coast => "coast",
            PathKind::QuickStop => "quick_stop",
            PathKind::ResetFault => "reset_fault",
        }
    }

    /// The path kind with this key.
    pub fn from_id(id: &str) -> Option<PathKind> {
        PathKind::ALL.iter().copied().find(|k| k.id() == id)
    }
}

/// A path: the transitions to take (the first that leaves the state the drive is in, each
/// time) until the drive shows one of the `to` states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Path {
    /// What it is for.
    pub kind: PathKind,
    /// Transitions (indices into [`CommandProfile::transitions`]) in order of preference.
    pub via: &'static [u8],
    /// The states that end it.
    pub to: &'static [u8],
}

/// A drive's command profile: the control and status registers, the states, the transitions and
/// the paths, as the map gives them.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CommandProfile {
    /// The standard it follows (`cia402`, `profidrive`, `abb_drives`), or the map's own name.
    pub name: &'static str,
    /// The plan row of the control word.
    pub control: u16,
    /// The plan row of the status word.
    pub status: u16,
    /// The states.
    pub states: &'static [ProfileState],
    /// The transitions.
    pub transitions: &'static [Transition],
    /// The paths the map gives.
    pub paths: &'static [Path],
    /// The state the drive is in at power-on (index into `states`).
    pub power_on: u8,
    /// The manual line that says the drive uses the profile.
    pub source: &'static str,
}

impl CommandProfile {
    /// The state status word `word` shows (its index), or `None` when it shows none.
    pub fn state_of(&self, word: u16) -> Option<u8> {
        self.states
            .iter()
            .position(|s| s.shows(word))
            .map(|i| i as u8)
    }

    /// The state's id, or `"?"` for an index out of range.
    pub fn state_id(&self, state: u8) -> &'static str {
        self.states.get(usize::from(state)).map_or("?", |s| s.id)
    }

    /// The path of `kind`, where the map gives one.
    pub fn path(&self, kind: PathKind) -> Option<&'static Path> {
        self.paths.iter().find(|p| p.kind == kind)
    }

    /// The transition at index `t`.
    pub fn transition(&self, t: u8) -> Option<&'static Transition> {
        self.transitions.get(usize::from(t))
    }

    /// The next transition of `path` from state `state`: of its `via` that leave it, the one
    /// on the fewest transitions to a state that ends the path (the first in `via` among
    /// equals); `None` where no transition of the path leads there from `state`.
    pub fn next(&self, path: &Path, state: u8) -> Option<&'static Transition> {
        // Transitions still to take from each state (u8::MAX: no way), at most 64 states.
        let mut left = [u8::MAX; 64];
        for &s in path.to {
            if let Some(d) = left.get_mut(usize::from(s)) {
                *d = 0;
            }
        }
        for _ in 0..self.states.len().min(64) {
            for t in path.via.iter().filter_map(|&t| self.transition(t)) {
                let Some(&after) = left.get(usize::from(t.to)) else {
                    continue;
                };
                for &f in t.from {
                    if let Some(d) = left.get_mut(usize::from(f))
                        && after != u8::MAX
                        && after + 1 < *d
                    {
                        *d = after + 1;
                    }
                }
            }
        }
        path.via
            .iter()
            .filter_map(|&t| self.transition(t))
            .filter(|t| t.leaves(state))
            .filter(|t| left.get(usize::from(t.to)).is_some_and(|&d| d != u8::MAX))
            .min_by_key(|t| left[usize::from(t.to)])
    }

    /// Whether transition `t` is a run transition: it leads to a state that ends the run path
    /// (the motor is driven there). No stop, coast, quick stop or reset may take one.
    pub fn runs(&self, t: &Transition) -> bool {
        self.path(PathKind::Run)
            .is_some_and(|p| p.to.contains(&t.to))
    }

    /// Whether state `state` is one the run path ends in.
    pub fn is_running(&self, state: u8) -> bool {
        self.path(PathKind::Run)
            .is_some_and(|p| p.to.contains(&state))
    }

    /// Whether control word `word` asks for a run transition from some state.
    pub fn word_runs(&self, word: u16) -> bool {
        self.transitions
            .iter()
            .any(|t| self.runs(t) && t.asked_by(word))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const STATES: &[ProfileState] = &[
        ProfileState {
            id: "switch_on_disabled",
            mask: 0x4F,
            value: 0x40,
            source: "",
        },
        ProfileState {
            id: "ready_to_switch_on",
            mask: 0x6F,
            value: 0x21,
            source: "",
        },
        ProfileState {
            id: "operation_enabled",
            mask: 0x6F,
            value: 0x27,
            source: "",
        },
    ];
    const T: &[Transition] = &[
        Transition {
            id: "shutdown",
            word: 0x0006,
            keep: 0xFF70,
            edge: 0,
            from: &[0, 2],
            to: 1,
            limit_ms: 100,
            source: "",
        },
        Transition {
            id: "enable_operation",
            word: 0x000F,
            keep: 0xFF70,
            edge: 0,
            from: &[1],
            to: 2,
            limit_ms: 100,
            source: "",
        },
    ];
    const P: CommandProfile = CommandProfile {
        name: "t",
        control: 0,
        status: 1,
        states: STATES,
        transitions: T,
        paths: &[
            Path {
                kind: PathKind::Run,
                via: &[0, 1],
                to: &[2],
            },
            Path {
                kind: PathKind::Stop,
                via: &[0],
                to: &[0, 1],
            },
        ],
        power_on: 0,
        source: "",
    };

    #[test]
    fn states_decode_by_mask_and_paths_walk_in_order() {
        assert_eq!(P.state_of(0x0250), Some(0));
        assert_eq!(P.state_of(0x0231), Some(1));
        assert_eq!(P.state_of(0x0637), Some(2));
        assert_eq!(P.state_of(0x0008), None);
        let run = P.path(PathKind::Run).unwrap();
        assert_eq!(P.next(run, 0).unwrap().id, "shutdown");
        assert_eq!(P.next(run, 1).unwrap().id, "enable_operation");
        // Of two transitions that leave a state, the one nearer the end of the path.
        assert_eq!(
            P.next(P.path(PathKind::Stop).unwrap(), 2).unwrap().id,
            "shutdown"
        );
        assert!(P.is_running(2));
        assert!(P.runs(&T[1]) && !P.runs(&T[0]));
        assert!(P.word_runs(0x080F) && !P.word_runs(0x0806));
    }

    #[test]
    fn a_transition_keeps_the_masters_bits() {
        assert_eq!(T[1].compose(0x0800), 0x080F);
        assert!(T[1].asked_by(0x080F));
        assert!(!T[1].asked_by(0x0807));
        assert_eq!(PathKind::from_id("quick_stop"), Some(PathKind::QuickStop));
    }
}
