//! Where and how a study ran: the commit, the CPU, the threads, the load before and after,
//! and the CPU time used — the context its timings need.

use serde::{Deserialize, Serialize};

/// The commit the study crate was built from (`git rev-parse HEAD` when the build script ran,
/// `-dirty` when tracked files had changes then; `unknown` outside a git checkout).
pub const COMMIT: &str = env!("BRDF_LAB_COMMIT");

/// The machine and load of one run (a merged study lists each shard's).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunInfo {
    /// [`COMMIT`].
    pub commit: String,
    /// `model name` of /proc/cpuinfo (`unknown` elsewhere).
    pub cpu_model: String,
    /// Logical CPUs the process may use.
    pub logical_cpus: usize,
    /// Worker threads of the statistics (the timings use one).
    pub threads: usize,
    /// /proc/loadavg's 1, 5 and 15 minute load averages when the run started (empty
    /// elsewhere).
    pub load_start: Vec<f64>,
    /// The same when it ended.
    pub load_end: Vec<f64>,
    /// Wall time of the run (s).
    pub wall_seconds: f64,
    /// CPU time (user + system) of the process at the end of the run (s), from
    /// /proc/self/stat (`None` elsewhere): with [`Self::wall_seconds`] it tells how much of
    /// the machine the run had.
    pub cpu_seconds: Option<f64>,
    /// CPU time (user + system, s) of the process in each phase of the run, in order (builds,
    /// map samplers, references, statistics, timings; the command line adds its images and
    /// outputs): where a run's CPU goes. Empty where the platform gives no process CPU time,
    /// and in results written before the phases were recorded.
    #[serde(default)]
    pub phases: Vec<PhaseCpu>,
}

/// The CPU time of one phase of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhaseCpu {
    /// `builds`, `map samplers`, `references`, `statistics`, `timings`, …
    pub phase: String,
    /// User + system CPU seconds of the process during the phase (every thread).
    pub cpu_seconds: f64,
}

/// Records the process CPU time of consecutive phases: [`PhaseClock::lap`] closes the current
/// phase under a name and starts the next.
#[derive(Debug)]
pub(crate) struct PhaseClock {
    last: Option<f64>,
    phases: Vec<PhaseCpu>,
}

impl PhaseClock {
    pub(crate) fn start() -> Self {
        Self {
            last: process_cpu_seconds(),
            phases: Vec::new(),
        }
    }

    /// Ends the phase `phase` (nothing is recorded where there is no process CPU clock).
    pub(crate) fn lap(&mut self, phase: &str) {
        let now = process_cpu_seconds();
        if let (Some(a), Some(b)) = (self.last, now) {
            self.phases.push(PhaseCpu {
                phase: phase.to_string(),
                cpu_seconds: (b - a).max(0.0),
            });
        }
        self.last = now;
    }

    pub(crate) fn finish(self) -> Vec<PhaseCpu> {
        self.phases
    }
}

impl RunInfo {
    /// `builds 11 s, references 2 s, …` (CPU seconds per phase), or `None` without phases.
    pub fn phase_summary(&self) -> Option<String> {
        (!self.phases.is_empty()).then(|| {
            self.phases
                .iter()
                .map(|p| format!("{} {:.0} s", p.phase, p.cpu_seconds))
                .collect::<Vec<_>>()
                .join(", ")
        })
    }
}

/// The three load averages of /proc/loadavg (empty when unreadable).
pub(crate) fn load_average() -> Vec<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .map(|s| {
            s.split_whitespace()
                .take(3)
                .filter_map(|x| x.parse().ok())
                .collect()
        })
        .unwrap_or_default()
}

/// The CPU model name.
pub(crate) fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".to_string())
}

/// User + system CPU time of this process (s), from fields 14 and 15 of /proc/self/stat in
/// clock ticks of 1/100 s (Linux's `USER_HZ` on every mainstream architecture).
pub fn process_cpu_seconds() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The command name (field 2) is in parentheses and may hold spaces: split after it.
    let rest = &s[s.rfind(')')? + 1..];
    let f: Vec<&str> = rest.split_whitespace().collect();
    // `rest` starts at field 3, so fields 14 and 15 are at 11 and 12.
    let utime: f64 = f.get(11)?.parse().ok()?;
    let stime: f64 = f.get(12)?.parse().ok()?;
    Some((utime + stime) / 100.0)
}

/// CPU time of the calling thread (s): `clock_gettime(CLOCK_THREAD_CPUTIME_ID)` on Unix,
/// `None` elsewhere. Unlike wall time it does not count the time the thread waits while other
/// processes run, so the timings of a loaded machine stay comparable.
pub(crate) fn thread_cpu_seconds() -> Option<f64> {
    #[cfg(unix)]
    {
        let t = rustix::time::clock_gettime(rustix::time::ClockId::ThreadCPUTime);
        Some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(unix))]
    {
        None
    }
}

/// Started at the beginning of a run; [`RunClock::finish`] gives its [`RunInfo`].
#[derive(Debug)]
pub(crate) struct RunClock {
    start: std::time::Instant,
    load_start: Vec<f64>,
}

impl RunClock {
    pub(crate) fn start() -> Self {
        Self {
            start: std::time::Instant::now(),
            load_start: load_average(),
        }
    }

    pub(crate) fn finish(self, phases: Vec<PhaseCpu>) -> RunInfo {
        RunInfo {
            commit: COMMIT.to_string(),
            cpu_model: cpu_model(),
            logical_cpus: std::thread::available_parallelism().map_or(1, |n| n.get()),
            threads: rayon::current_num_threads(),
            load_start: self.load_start,
            load_end: load_average(),
            wall_seconds: self.start.elapsed().as_secs_f64(),
            cpu_seconds: process_cpu_seconds(),
            phases,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_run_info_is_read_where_linux_gives_it() {
        let mut phases = PhaseClock::start();
        let x: f64 = (0..2_000_000).map(|i| (i as f64).sqrt()).sum();
        std::hint::black_box(x);
        phases.lap("work");
        let info = RunClock::start().finish(phases.finish());
        assert!(!info.commit.is_empty());
        assert!(info.threads >= 1 && info.logical_cpus >= 1);
        if std::path::Path::new("/proc/loadavg").exists() {
            assert_eq!(info.load_start.len(), 3);
            assert!(info.cpu_seconds.is_some_and(|s| s >= 0.0));
            assert_ne!(info.cpu_model, "");
            assert_eq!(info.phases.len(), 1);
            assert!(info.phases[0].cpu_seconds >= 0.0);
            assert_eq!(
                info.phase_summary().unwrap(),
                format!("work {:.0} s", info.phases[0].cpu_seconds)
            );
        }
    }
}
