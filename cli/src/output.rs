//! Standard output that a closed pipe ends quietly: `drivemap export | head` stops when `head`
//! exits, with no panic message and exit status 141 (128 + SIGPIPE), what a shell reports for
//! `cat` or `seq` in the same place. `println!` would panic instead; restoring the default
//! SIGPIPE action would need `unsafe` (or a crate wrapping it) and would not cover Windows.

use std::fmt;
use std::io::{self, Write};

/// Exit status of a command whose output pipe was closed.
pub(crate) const BROKEN_PIPE_EXIT: i32 = 141;

/// Writes to standard output; on a closed pipe ends the process quietly, on any other error
/// reports it and exits with status 2.
pub(crate) fn write(args: fmt::Arguments<'_>) {
    let mut out = io::stdout().lock();
    if let Err(e) = out.write_fmt(args).and_then(|()| out.flush()) {
        if e.kind() == io::ErrorKind::BrokenPipe {
            std::process::exit(BROKEN_PIPE_EXIT);
        }
        eprintln!("drivemap: writing to standard output: {e}");
        std::process::exit(2);
    }
}

/// `print!` that ends quietly on a closed pipe.
macro_rules! out {
    ($($arg:tt)*) => { $crate::output::write(format_args!($($arg)*)) };
}

/// `println!` that ends quietly on a closed pipe.
macro_rules! outln {
    () => { $crate::output::write(format_args!("\n")) };
    ($($arg:tt)*) => { $crate::output::write(format_args!("{}\n", format_args!($($arg)*))) };
}

/// Prints, on standard error, a warning for each protocol fact of `facts` the command relies on
/// although `drive`'s manual does not print it (`drivemap_live::unprinted::warnings`).
pub(crate) fn warn_unprinted(
    drive: &drivemap_map::Map,
    link: &drivemap_live::link::Link,
    facts: &[drivemap_runtime::core::stated::ProtocolFact],
) {
    for w in drivemap_live::unprinted::warnings(drive, link, facts, None) {
        eprintln!("{w}");
    }
}
