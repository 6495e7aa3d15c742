//! An emulated RS-485 line between two pseudo-terminals: each character takes its time on the
//! wire (start, data, parity and stop bits at the baud rate), and every character is recorded
//! with when it started and ended, per direction.
//!
//! A pseudo-terminal pair delivers bytes at once: a serial test over one runs at an infinite
//! baud rate, where a client that waits three times too long, or too little, passes. Here the
//! relay thread holds the master side of two pseudo-terminals, one for the Modbus master (the
//! client under test) and one for the drive (a simulator); a byte written on one side is put
//! on the wire when the line in that direction is free, and handed to the other side when its
//! last stop bit has gone, as a UART receiver would. The relay sleeps in `ppoll` until the next
//! character is due (its thread's timer slack set to 1 ns): it does not spin. What it cannot
//! emulate: a pseudo-terminal's `tcdrain` returns at once, so a master that times a silence from
//! the end of its own request sees that end earlier than the wire does (only a request with no
//! reply, a broadcast or a timeout, is followed by such a silence).
//!
//! [`analyse`] turns the record into a [`LineReport`]: per request, when the master started
//! sending, when the last character of the reply arrived, the silence before each frame, and
//! the timing rules broken ([`Violation`]): a frame inside a required silence, a gap of more
//! than 1.5 characters inside a frame, two stations sending at once.

use std::collections::VecDeque;
use std::ffi::CString;
use std::io;
use std::num::NonZeroU64;
use std::os::fd::OwnedFd;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::{self, JoinHandle};
use std::time::Instant;

use drivemap_runtime::bus_time::{BusModel, SerialConfig};
use drivemap_runtime::rtu;
use rustix::event::{PollFd, PollFlags, Timespec};
use rustix::fs::{Mode, OFlags};
use rustix::pty::OpenptFlags;

/// Which way a character travels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Direction {
    /// From the master (the client) to the drive: requests.
    ToDrive,
    /// From the drive to the master: replies.
    ToMaster,
}

/// One character on the wire, in nanoseconds since the line started.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Char {
    pub direction: Direction,
    pub byte: u8,
    /// The start bit begins.
    pub start_ns: u64,
    /// The last stop bit ends: the receiver has the byte.
    pub end_ns: u64,
}

/// What the relay measured of itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RelayStats {
    /// CPU time of the relay thread so far.
    pub cpu_ns: u64,
    /// The latest a character was handed over after its last stop bit (the relay thread's
    /// wake-up latency; the record holds the wire times, not these).
    pub max_late_ns: u64,
    /// Characters handed over more than one character time late.
    pub late_chars: u64,
}

struct Shared {
    stop: AtomicBool,
    record: Mutex<Vec<Char>>,
    cpu_ns: AtomicU64,
    max_late_ns: AtomicU64,
    late_chars: AtomicU64,
}

/// A serial line at a baud rate and character format, between a master's pseudo-terminal
/// ([`EmulatedLine::master_path`]) and a drive's ([`EmulatedLine::drive_path`]). Stops on drop.
pub struct EmulatedLine {
    master_path: String,
    drive_path: String,
    serial: SerialConfig,
    epoch: Instant,
    shared: Arc<Shared>,
    thread: Option<JoinHandle<io::Result<()>>>,
    /// The slave sides, held open so that the master sides never see a hang-up while no
    /// station has its end open.
    slaves: [OwnedFd; 2],
}

/// A pseudo-terminal: its master side (the relay's) and the path and an open descriptor of
/// its slave side, in raw mode.
fn pty() -> io::Result<(OwnedFd, String, OwnedFd)> {
    let master =
        rustix::pty::openpt(OpenptFlags::RDWR | OpenptFlags::NOCTTY | OpenptFlags::CLOEXEC)?;
    rustix::pty::grantpt(&master)?;
    rustix::pty::unlockpt(&master)?;
    let name: CString = rustix::pty::ptsname(&master, Vec::new())?;
    let path = name
        .into_string()
        .map_err(|_| io::Error::other("a pseudo-terminal name that is not UTF-8"))?;
    let slave = rustix::fs::open(
        path.as_str(),
        OFlags::RDWR | OFlags::NOCTTY | OFlags::CLOEXEC,
        Mode::empty(),
    )?;
    let mut t = rustix::termios::tcgetattr(&slave)?;
    t.make_raw();
    rustix::termios::tcsetattr(&slave, rustix::termios::OptionalActions::Now, &t)?;
    rustix::io::ioctl_fionbio(&master, true)?;
    Ok((master, path, slave))
}

impl EmulatedLine {
    /// A line with `serial`'s baud rate and character format, relaying between two new
    /// pseudo-terminals.
    pub fn new(serial: SerialConfig) -> io::Result<EmulatedLine> {
        let (m0, master_path, s0) = pty()?;
        let (m1, drive_path, s1) = pty()?;
        let shared = Arc::new(Shared {
            stop: AtomicBool::new(false),
            record: Mutex::new(Vec::new()),
            cpu_ns: AtomicU64::new(0),
            max_late_ns: AtomicU64::new(0),
            late_chars: AtomicU64::new(0),
        });
        let epoch = Instant::now();
        let char_ns = serial.char_ns();
        let s = shared.clone();
        let thread = thread::Builder::new()
            .name("emulated-line".into())
            .spawn(move || relay([m0, m1], char_ns, &s, epoch))?;
        Ok(EmulatedLine {
            master_path,
            drive_path,
            serial,
            epoch,
            shared,
            thread: Some(thread),
            slaves: [s0, s1],
        })
    }

    /// The pseudo-terminal the master (the client under test) opens.
    pub fn master_path(&self) -> &str {
        &self.master_path
    }

    /// The pseudo-terminal the drive (a simulator) opens.
    pub fn drive_path(&self) -> &str {
        &self.drive_path
    }

    /// The line's baud rate and character format.
    pub fn serial(&self) -> SerialConfig {
        self.serial
    }

    /// Nanoseconds since the line started, on the record's clock.
    pub fn now_ns(&self) -> u64 {
        self.epoch.elapsed().as_nanos() as u64
    }

    /// The characters recorded so far, in the order they went on the wire per direction.
    pub fn record(&self) -> Vec<Char> {
        self.shared.record.lock().expect("record").clone()
    }

    /// Takes the characters recorded so far, leaving the record empty.
    pub fn take_record(&self) -> Vec<Char> {
        std::mem::take(&mut *self.shared.record.lock().expect("record"))
    }

    /// The relay's own figures (CPU time, lateness).
    pub fn relay_stats(&self) -> RelayStats {
        RelayStats {
            cpu_ns: self.shared.cpu_ns.load(Ordering::Relaxed),
            max_late_ns: self.shared.max_late_ns.load(Ordering::Relaxed),
            late_chars: self.shared.late_chars.load(Ordering::Relaxed),
        }
    }

    /// Lets another station open an end that a station which set exclusive access
    /// (`TIOCEXCL`, as the `serialport` crate does) has closed.
    pub fn release_ends(&self) -> io::Result<()> {
        for s in &self.slaves {
            rustix::termios::ioctl_tiocnxcl(s)?;
        }
        Ok(())
    }
}

impl Drop for EmulatedLine {
    fn drop(&mut self) {
        self.shared.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

/// Asks for real-time scheduling (`SCHED_FIFO`, priority 10) for the calling thread and the
/// threads it spawns from now on, through `chrt` (util-linux), where the system permits it
/// (root, as in CI); returns whether it was granted. The line's relay, the simulated drive and
/// the client all sleep between characters; at this priority a build running beside them on
/// a shared machine does not delay their wake-ups by milliseconds, which the record would
/// otherwise count as the client's time. A thread that spins would be throttled by the
/// kernel (real-time threads get at most 95 % of a core by default).
pub fn realtime() -> bool {
    let tid = rustix::thread::gettid().as_raw_nonzero().get();
    std::process::Command::new("chrt")
        .args(["-f", "-p", "10", &tid.to_string()])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

fn thread_cpu_ns() -> u64 {
    let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
    t.tv_sec as u64 * 1_000_000_000 + t.tv_nsec as u64
}

/// The relay: reads what each side writes, schedules each byte on the wire in its direction
/// and hands it to the other side when its last bit has gone.
fn relay(ends: [OwnedFd; 2], char_ns: f64, shared: &Shared, epoch: Instant) -> io::Result<()> {
    // Wake when a character is due, not up to 50 µs later (the default slack).
    let _ = rustix::thread::set_current_timer_slack(NonZeroU64::new(1));
    let now_ns = || epoch.elapsed().as_nanos() as u64;
    // Per direction (0: master to drive, 1: drive to master): bytes on the wire with the time
    // their last bit ends, and when the line in that direction is next free (fractional ns,
    // so that long frames do not drift).
    let mut queues: [VecDeque<(u8, u64)>; 2] = [VecDeque::new(), VecDeque::new()];
    let mut free_at = [0f64; 2];
    let mut buf = [0u8; 1024];
    let mut out = Vec::with_capacity(1024);
    let cpu_start = thread_cpu_ns();
    while !shared.stop.load(Ordering::Relaxed) {
        let now = now_ns();
        for d in 0..2 {
            out.clear();
            while let Some(&(byte, end)) = queues[d].front() {
                if end > now {
                    break;
                }
                let late = now - end;
                shared.max_late_ns.fetch_max(late, Ordering::Relaxed);
                if late as f64 > char_ns {
                    shared.late_chars.fetch_add(1, Ordering::Relaxed);
                }
                out.push(byte);
                queues[d].pop_front();
            }
            let mut written = 0;
            while written < out.len() {
                match rustix::io::write(&ends[1 - d], &out[written..]) {
                    Ok(n) => written += n,
                    // Nobody reads that side and its buffer is full: the bytes are lost, as
                    // on a line with no receiver.
                    Err(rustix::io::Errno::AGAIN) => break,
                    Err(rustix::io::Errno::INTR) => continue,
                    Err(e) => return Err(e.into()),
                }
            }
        }
        shared
            .cpu_ns
            .store(thread_cpu_ns() - cpu_start, Ordering::Relaxed);
        let next = queues
            .iter()
            .filter_map(|q| q.front().map(|&(_, e)| e))
            .min();
        let wait = next.map_or(50_000_000, |e| e.saturating_sub(now_ns()).min(50_000_000));
        let timeout = Timespec {
            tv_sec: (wait / 1_000_000_000) as i64,
            tv_nsec: (wait % 1_000_000_000) as i64,
        };
        let mut fds = [
            PollFd::new(&ends[0], PollFlags::IN),
            PollFd::new(&ends[1], PollFlags::IN),
        ];
        match rustix::event::poll(&mut fds, Some(&timeout)) {
            Ok(_) | Err(rustix::io::Errno::INTR) => {}
            Err(e) => return Err(e.into()),
        }
        let ready = [!fds[0].revents().is_empty(), !fds[1].revents().is_empty()];
        for d in 0..2 {
            if !ready[d] {
                continue;
            }
            loop {
                let n = match rustix::io::read(&ends[d], &mut buf) {
                    Ok(0) => break,
                    Ok(n) => n,
                    Err(rustix::io::Errno::AGAIN) | Err(rustix::io::Errno::IO) => break,
                    Err(rustix::io::Errno::INTR) => continue,
                    Err(e) => return Err(e.into()),
                };
                let at = now_ns() as f64;
                let direction = if d == 0 {
                    Direction::ToDrive
                } else {
                    Direction::ToMaster
                };
                let mut record = shared.record.lock().expect("record");
                for &byte in &buf[..n] {
                    let start = free_at[d].max(at);
                    let end = start + char_ns;
                    free_at[d] = end;
                    queues[d].push_back((byte, end.round() as u64));
                    record.push(Char {
                        direction,
                        byte,
                        start_ns: start.round() as u64,
                        end_ns: end.round() as u64,
                    });
                }
            }
        }
    }
    Ok(())
}

/// One frame as it went over the line.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Frame {
    pub direction: Direction,
    pub bytes: Vec<u8>,
    pub start_ns: u64,
    pub end_ns: u64,
    /// The silence on the line before it (from the end of the previous frame in either
    /// direction; `None` for the first).
    pub silence_before_ns: Option<u64>,
    /// The longest gap between two of its characters.
    pub max_gap_ns: u64,
}

/// One request and what answered it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Transaction {
    /// When the master started sending.
    pub start_ns: u64,
    /// When its last character ended.
    pub request_end_ns: u64,
    /// The silence before the request.
    pub silence_before_ns: Option<u64>,
    /// When the first character of the reply started (none: no reply).
    pub reply_start_ns: Option<u64>,
    /// When the last character of the reply arrived.
    pub reply_end_ns: Option<u64>,
    /// Frames of the request and its reply(ies), indexes into [`LineReport::frames`].
    pub frames: Vec<usize>,
}

/// A timing rule broken on the line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Violation {
    /// A frame started before the silence the rules require after the previous frame: the
    /// frame gap (3.5 characters) before any frame, and before a request that follows a
    /// reply the master's wait the drive's manual requires (V7/J7: 24 bits + 10 ms).
    EarlyFrame {
        frame: usize,
        direction: Direction,
        silence_ns: u64,
        required_ns: u64,
    },
    /// A gap of more than 1.5 characters between two characters of one frame.
    GapInFrame {
        frame: usize,
        direction: Direction,
        gap_ns: u64,
        limit_ns: u64,
    },
    /// Both directions on the wire at once (RS-485 is half duplex).
    Collision { at_ns: u64 },
}

impl std::fmt::Display for Violation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let ms = |ns: u64| ns as f64 / 1e6;
        match *self {
            Violation::EarlyFrame {
                frame,
                direction,
                silence_ns,
                required_ns,
            } => write!(
                f,
                "frame {frame} ({direction:?}) started after {:.3} ms of silence; the rules require {:.3} ms",
                ms(silence_ns),
                ms(required_ns)
            ),
            Violation::GapInFrame {
                frame,
                direction,
                gap_ns,
                limit_ns,
            } => write!(
                f,
                "frame {frame} ({direction:?}) has a gap of {:.3} ms between two characters (more than 1.5 characters, {:.3} ms)",
                ms(gap_ns),
                ms(limit_ns)
            ),
            Violation::Collision { at_ns } => {
                write!(f, "both directions on the wire at {:.3} ms", ms(at_ns))
            }
        }
    }
}

/// What a record shows: frames, transactions, broken rules.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct LineReport {
    pub frames: Vec<Frame>,
    pub transactions: Vec<Transaction>,
    pub violations: Vec<Violation>,
}

/// Cuts one direction's characters into frames: a frame ends where its header says (an RTU
/// request or reply of known length) or at a silence of at least the frame gap.
fn frames_of(chars: &[Char], direction: Direction, frame_gap_ns: u64) -> Vec<Vec<Char>> {
    let mut frames: Vec<Vec<Char>> = Vec::new();
    let mut current: Vec<Char> = Vec::new();
    let mut bytes: Vec<u8> = Vec::new();
    for c in chars.iter().filter(|c| c.direction == direction) {
        let silent = current
            .last()
            .is_some_and(|p| c.start_ns.saturating_sub(p.end_ns) >= frame_gap_ns);
        if silent {
            frames.push(std::mem::take(&mut current));
            bytes.clear();
        }
        current.push(*c);
        bytes.push(c.byte);
        let len = match direction {
            Direction::ToDrive => rtu::request_frame_len(&bytes),
            Direction::ToMaster => rtu::response_frame_len(&bytes),
        };
        if matches!(len, Ok(Some(n)) if bytes.len() >= n) {
            frames.push(std::mem::take(&mut current));
            bytes.clear();
        }
    }
    if !current.is_empty() {
        frames.push(current);
    }
    frames
}

/// Reads a record against the rules of `model` (the drive's profile on the line): frames,
/// transactions, violations.
pub fn analyse(record: &[Char], model: &BusModel) -> LineReport {
    let char_ns = model.serial.char_ns();
    let frame_gap = model.frame_gap_ns().ceil() as u64;
    let request_gap = model.turnaround_ns().ceil() as u64;
    let gap_limit = (1.5 * char_ns).round() as u64;
    let mut cut: Vec<Vec<Char>> = frames_of(record, Direction::ToDrive, frame_gap);
    cut.extend(frames_of(record, Direction::ToMaster, frame_gap));
    cut.sort_by_key(|f| f[0].start_ns);
    let mut report = LineReport::default();
    let mut previous: Option<(Direction, u64)> = None;
    for chars in cut {
        let index = report.frames.len();
        let direction = chars[0].direction;
        let start_ns = chars[0].start_ns;
        let end_ns = chars.last().map_or(start_ns, |c| c.end_ns);
        let mut max_gap_ns = 0;
        for pair in chars.windows(2) {
            let gap = pair[1].start_ns.saturating_sub(pair[0].end_ns);
            max_gap_ns = max_gap_ns.max(gap);
            if gap > gap_limit {
                report.violations.push(Violation::GapInFrame {
                    frame: index,
                    direction,
                    gap_ns: gap,
                    limit_ns: gap_limit,
                });
            }
        }
        let silence_before_ns = previous.map(|(_, end)| start_ns.saturating_sub(end));
        if let Some((before, end)) = previous {
            if start_ns < end {
                report
                    .violations
                    .push(Violation::Collision { at_ns: start_ns });
            } else {
                let required = if direction == Direction::ToDrive && before == Direction::ToMaster {
                    request_gap
                } else {
                    frame_gap
                };
                let silence = start_ns - end;
                if silence < required {
                    report.violations.push(Violation::EarlyFrame {
                        frame: index,
                        direction,
                        silence_ns: silence,
                        required_ns: required,
                    });
                }
            }
        }
        previous = Some(match previous {
            Some((d, e)) if e > end_ns => (d, e),
            _ => (direction, end_ns),
        });
        if direction == Direction::ToDrive {
            report.transactions.push(Transaction {
                start_ns,
                request_end_ns: end_ns,
                silence_before_ns,
                reply_start_ns: None,
                reply_end_ns: None,
                frames: vec![index],
            });
        } else if let Some(t) = report.transactions.last_mut() {
            t.reply_start_ns.get_or_insert(start_ns);
            t.reply_end_ns = Some(end_ns);
            t.frames.push(index);
        }
        report.frames.push(Frame {
            direction,
            bytes: chars.iter().map(|c| c.byte).collect(),
            start_ns,
            end_ns,
            silence_before_ns,
            max_gap_ns,
        });
    }
    report
}
