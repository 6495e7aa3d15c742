//! A pair of linked pseudo-terminals made by `socat`, for tests that drive a real serial line.
//! A test using it fails, not skips, when socat is missing.

use std::io::{BufRead, BufReader};
use std::process::{Child, Command, Stdio};
use std::thread;

/// A running `socat` linking two pseudo-terminals; killed on drop.
pub struct PtyPair {
    child: Child,
    pub paths: [String; 2],
}

impl PtyPair {
    #[allow(clippy::new_without_default)] // it starts a process: not a default value
    pub fn new() -> PtyPair {
        let mut child = Command::new("socat")
            .args(["-d", "-d", "pty,raw,echo=0", "pty,raw,echo=0"])
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap_or_else(|e| {
                panic!("starting socat: {e}; install it with tests/interop/install.sh (apt-get install socat)")
            });
        let stderr = child.stderr.take().expect("socat stderr");
        let mut lines = BufReader::new(stderr).lines();
        let mut paths = Vec::new();
        // socat -d -d logs "... N PTY is /dev/pts/7" once per side, then the transfer loop.
        while paths.len() < 2 {
            let line = lines
                .next()
                .expect("socat exited before naming both pseudo-terminals")
                .expect("reading socat's log");
            if let Some(at) = line.find("PTY is ") {
                paths.push(line[at + "PTY is ".len()..].trim().to_string());
            }
        }
        // Keep draining socat's log so it never blocks on a full pipe.
        thread::spawn(move || for _ in lines.by_ref() {});
        PtyPair {
            child,
            paths: [paths[0].clone(), paths[1].clone()],
        }
    }
}

impl Drop for PtyPair {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}
