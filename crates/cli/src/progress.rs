//! Progress of long runs on stderr: a bar on a terminal; otherwise (logs, CI, pipes) one line
//! every [`DEFAULT_INTERVAL_SECS`] seconds, e.g. `validating: 120/1100 (11 %), ETA 343 s, 42 s elapsed`,
//! so a long run is never silent. `BRDF_LAB_PROGRESS_SECS` sets that interval.

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering::Relaxed};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Seconds between two progress lines when stderr is not a terminal.
pub(crate) const DEFAULT_INTERVAL_SECS: f64 = 10.0;

/// Environment variable overriding [`DEFAULT_INTERVAL_SECS`] (seconds, > 0).
pub(crate) const INTERVAL_VAR: &str = "BRDF_LAB_PROGRESS_SECS";

/// State shared with the line printer.
struct Shared {
    label: String,
    len: AtomicU64,
    pos: AtomicU64,
    done: AtomicBool,
    started: Instant,
}

impl Shared {
    fn line(&self) -> String {
        let (pos, len) = (self.pos.load(Relaxed), self.len.load(Relaxed));
        let secs = self.started.elapsed().as_secs_f64();
        if len > 0 {
            // The remaining steps at the mean pace so far.
            let eta = if pos > 0 && pos < len {
                format!("ETA {:.0} s, ", secs * (len - pos) as f64 / pos as f64)
            } else {
                String::new()
            };
            format!(
                "{}: {pos}/{len} ({:.0} %), {eta}{secs:.0} s elapsed",
                self.label,
                100.0 * pos as f64 / len as f64
            )
        } else {
            format!("{}: {pos} done, {secs:.0} s elapsed", self.label)
        }
    }
}

/// A progress indicator over a number of steps (see the module docs). Methods take `&self`
/// and it is `Sync`, so parallel workers can advance it.
pub(crate) struct Progress {
    bar: Option<ProgressBar>,
    shared: Arc<Shared>,
    printer: Mutex<Option<JoinHandle<()>>>,
}

/// A progress indicator over `len` steps (0: not known yet) with a short label.
pub(crate) fn bar(len: u64, label: &str) -> Progress {
    let shared = Arc::new(Shared {
        label: label.to_string(),
        len: AtomicU64::new(len),
        pos: AtomicU64::new(0),
        done: AtomicBool::new(false),
        started: Instant::now(),
    });
    if std::io::stderr().is_terminal() {
        let pb = ProgressBar::new(len);
        let style = ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} ({eta})")
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
        pb.set_style(style);
        pb.set_message(label.to_string());
        return Progress {
            bar: Some(pb),
            shared,
            printer: Mutex::new(None),
        };
    }
    let interval = std::env::var(INTERVAL_VAR)
        .ok()
        .and_then(|v| v.trim().parse::<f64>().ok())
        .filter(|s| s.is_finite() && *s > 0.0)
        .unwrap_or(DEFAULT_INTERVAL_SECS);
    let s = Arc::clone(&shared);
    // A printer thread, so a line appears on time even while one step takes long; if it
    // cannot be started, the run just goes without progress lines.
    let printer = std::thread::Builder::new()
        .name("progress".into())
        .spawn(move || {
            let period = Duration::from_secs_f64(interval);
            let mut next = s.started + period;
            while !s.done.load(Relaxed) {
                let now = Instant::now();
                if now >= next {
                    eprintln!("{}", s.line());
                    next += period;
                    if next < now {
                        next = now + period;
                    }
                } else {
                    std::thread::park_timeout(next - now);
                }
            }
        })
        .ok();
    Progress {
        bar: None,
        shared,
        printer: Mutex::new(printer),
    }
}

impl Progress {
    /// Sets the number of steps.
    pub(crate) fn set_length(&self, len: u64) {
        self.shared.len.store(len, Relaxed);
        if let Some(b) = &self.bar {
            b.set_length(len);
        }
    }

    /// Sets the steps done.
    pub(crate) fn set_position(&self, pos: u64) {
        self.shared.pos.store(pos, Relaxed);
        if let Some(b) = &self.bar {
            b.set_position(pos);
        }
    }

    /// Adds `n` steps done.
    pub(crate) fn inc(&self, n: u64) {
        self.shared.pos.fetch_add(n, Relaxed);
        if let Some(b) = &self.bar {
            b.inc(n);
        }
    }

    /// Ends the indicator: clears the bar, or stops the line printer.
    pub(crate) fn finish_and_clear(&self) {
        if let Some(b) = &self.bar {
            b.finish_and_clear();
        }
        self.stop();
    }

    /// Stops the line printer and waits for it (no line can follow the command's own output).
    fn stop(&self) {
        self.shared.done.store(true, Relaxed);
        let handle = self.printer.lock().ok().and_then(|mut p| p.take());
        if let Some(p) = handle {
            p.thread().unpark();
            let _ = p.join();
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        self.stop();
    }
}
