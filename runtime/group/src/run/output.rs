//! Process output: each line goes to the terminal with a coloured `[name]` prefix and to the
//! process's own log file.

use std::fs::File;
use std::io::{BufRead, BufReader, Read, Write};
use std::sync::{Arc, Mutex};

const COLOURS: [&str; 6] = [
    "\x1b[36m", "\x1b[32m", "\x1b[35m", "\x1b[33m", "\x1b[34m", "\x1b[31m",
];
const RESET: &str = "\x1b[0m";

/// Where prefixed lines go: the terminal (shared, so lines never interleave mid-line).
#[derive(Clone)]
pub struct Console {
    colour: bool,
    quiet: bool,
    lock: Arc<Mutex<()>>,
}

impl Console {
    pub fn new(quiet: bool) -> Self {
        // SAFETY: isatty only inspects the descriptor.
        let colour = unsafe { libc::isatty(libc::STDERR_FILENO) } == 1;
        Self {
            colour,
            quiet,
            lock: Arc::new(Mutex::new(())),
        }
    }

    pub fn prefix(&self, index: usize, name: &str) -> String {
        if self.colour {
            format!("{}[{name}]{RESET} ", COLOURS[index % COLOURS.len()])
        } else {
            format!("[{name}] ")
        }
    }

    pub fn line(&self, prefix: &str, line: &str) {
        if self.quiet {
            return;
        }
        let _guard = self.lock.lock();
        eprintln!("{prefix}{line}");
    }

    /// A message of the launcher itself.
    pub fn say(&self, line: &str) {
        let _guard = self.lock.lock();
        eprintln!("caravan: {line}");
    }

    /// Copies `stream` line by line to the console and `log` on a thread of its own.
    /// Returns the stream's last non-empty line (shared, updated as lines arrive) and a
    /// receiver that disconnects when the stream ends.
    pub fn pump(
        &self,
        stream: impl Read + Send + 'static,
        prefix: String,
        log: Arc<Mutex<File>>,
    ) -> (Arc<Mutex<String>>, crossbeam::channel::Receiver<()>) {
        let console = self.clone();
        let last = Arc::new(Mutex::new(String::new()));
        let (eof_tx, eof_rx) = crossbeam::channel::bounded::<()>(0);
        let tail = last.clone();
        std::thread::spawn(move || {
            let _eof = eof_tx; // dropped at the end of the stream
            for line in BufReader::new(stream).lines() {
                let Ok(line) = line else { break };
                console.line(&prefix, &line);
                if let Ok(mut f) = log.lock() {
                    let _ = writeln!(f, "{line}");
                }
                // A panic says why in its line and the next; Rust's backtrace hint follows.
                if !line.trim().is_empty()
                    && let Ok(mut t) = tail.lock()
                {
                    // After a panic, its message stays the reason (a backtrace may follow).
                    if t.contains("panicked at") {
                        if t.ends_with(':') && !line.starts_with("note: ") {
                            t.push(' ');
                            t.push_str(line.trim());
                        }
                        continue;
                    }
                    *t = line;
                }
            }
        });
        (last, eof_rx)
    }
}
