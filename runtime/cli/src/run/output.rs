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
    pub fn pump(&self, stream: impl Read + Send + 'static, prefix: String, log: Arc<Mutex<File>>) {
        let console = self.clone();
        std::thread::spawn(move || {
            for line in BufReader::new(stream).lines() {
                let Ok(line) = line else { break };
                console.line(&prefix, &line);
                if let Ok(mut f) = log.lock() {
                    let _ = writeln!(f, "{line}");
                }
            }
        });
    }
}
