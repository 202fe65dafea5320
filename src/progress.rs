//! Progress on stderr, one [`Progress`] per task (a dataset, a training, a Monte Carlo
//! block, a download). On a terminal it is a bar. Where stderr is a file (a cluster
//! job's log, CI, `2>run.log`) it is a plain line at most every [`log_every`] seconds
//! (30 by default, `--log-every`) naming the task, what it is doing, how far it is, its
//! rate since the last line and its ETA; the stages print one line as each task ends.

use indicatif::{MultiProgress, ProgressBar, ProgressStyle};
use std::io::IsTerminal;
use std::sync::{Arc, Mutex, OnceLock};
use std::time::{Duration, Instant};

/// How long a task waits between two log lines where stderr is not a terminal.
pub const DEFAULT_LOG_EVERY: Duration = Duration::from_secs(30);

static LOG_EVERY: OnceLock<Duration> = OnceLock::new();

/// Sets the interval of the log lines for the rest of the process (`--log-every`).
pub fn set_log_every(every: Duration) {
    LOG_EVERY
        .set(every)
        .expect("the log interval is set once, before any task starts");
}

/// The interval of the log lines: `--log-every`, or [`DEFAULT_LOG_EVERY`].
pub fn log_every() -> Duration {
    *LOG_EVERY.get().unwrap_or(&DEFAULT_LOG_EVERY)
}

/// One task's progress: `len` steps of `unit`, with a message saying what it is doing.
#[derive(Clone)]
pub struct Progress {
    bar: ProgressBar,
    log: Option<Arc<Mutex<LogLines>>>,
}

impl Progress {
    /// The progress of `task`, `len` steps of `unit` (a plural noun: "samples").
    pub fn new(task: impl Into<String>, len: usize, unit: &'static str) -> Self {
        let task = task.into();
        if std::io::stderr().is_terminal() {
            let style = ProgressStyle::with_template(
                "{prefix} {msg} [{bar:30}] {pos}/{len} {elapsed_precise} (eta {eta})",
            )
            .expect("the template is valid")
            .progress_chars("=> ");
            let bar = ProgressBar::new(len as u64)
                .with_style(style)
                .with_prefix(task);
            return Progress { bar, log: None };
        }
        let bar = ProgressBar::hidden();
        bar.set_length(len as u64);
        let log = LogLines::new(task, unit, log_every(), Instant::now());
        Progress {
            bar,
            log: Some(Arc::new(Mutex::new(log))),
        }
    }

    /// Progress that shows nothing (benchmarks, tests, nested work).
    pub fn hidden() -> Self {
        Progress {
            bar: ProgressBar::hidden(),
            log: None,
        }
    }

    /// Shows this bar among `bars` on a terminal, where several tasks run at once.
    pub fn shown_in(mut self, bars: &MultiProgress) -> Self {
        if self.log.is_none() {
            self.bar = bars.add(self.bar);
        }
        self
    }

    /// Says what the task is doing now ("epoch 3/20, loss 0.1234").
    pub fn set_message(&self, message: String) {
        self.bar.set_message(message);
    }

    /// Sets how far the task is without counting it as progress (a resumed training).
    pub fn set_position(&self, position: usize) {
        self.bar.set_position(position as u64);
        if let Some(log) = &self.log {
            log.lock().expect("no logger panics").last_position = position as u64;
        }
    }

    /// Advances the task by `steps`, and logs a line if one is due.
    pub fn inc(&self, steps: usize) {
        if let Some(line) = self.step(steps) {
            eprintln!("{line}");
        }
    }

    /// Advances the task by `steps`; the log line due, if any. The step and the line are
    /// taken under the log's lock, so that workers stepping at once each log the position
    /// they reached (never one another's), in order.
    fn step(&self, steps: usize) -> Option<String> {
        let Some(log) = &self.log else {
            self.bar.inc(steps as u64);
            return None;
        };
        let mut log = log.lock().expect("no logger panics");
        self.bar.inc(steps as u64);
        log.due(
            Instant::now(),
            self.bar.position(),
            self.bar.length().unwrap_or(0),
            &self.bar.message(),
        )
    }

    /// Removes the bar; the stage prints the line that says how the task ended.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}

/// The log lines of one task: when the last was written, and how far the task was then.
struct LogLines {
    task: String,
    unit: &'static str,
    every: Duration,
    last_time: Instant,
    last_position: u64,
}

impl LogLines {
    fn new(task: String, unit: &'static str, every: Duration, start: Instant) -> Self {
        LogLines {
            task,
            unit,
            every,
            last_time: start,
            last_position: 0,
        }
    }

    /// The line to log at `now`, at `position` of `len` doing `message`, if `every` has
    /// passed since the last one (or the task's start). The rate is that since then, and
    /// the ETA assumes it holds.
    fn due(&mut self, now: Instant, position: u64, len: u64, message: &str) -> Option<String> {
        let since = now.duration_since(self.last_time);
        if since < self.every || since.is_zero() {
            return None;
        }
        let rate = position.saturating_sub(self.last_position) as f64 / since.as_secs_f64();
        self.last_time = now;
        self.last_position = position;
        let eta = if rate > 0.0 {
            let seconds = (len.saturating_sub(position) as f64 / rate).round();
            humantime::format_duration(Duration::from_secs(seconds as u64)).to_string()
        } else {
            "unknown".to_string()
        };
        let unit = self.unit;
        let doing = if message.is_empty() {
            String::new()
        } else {
            format!("{message}, ")
        };
        Some(format!(
            "{}: {doing}{position}/{len} {unit}, {} {unit}/s, ETA {eta}",
            self.task,
            format_rate(rate)
        ))
    }
}

/// A rate with as many decimals as it needs to read at a glance.
fn format_rate(rate: f64) -> String {
    match rate {
        r if r >= 100.0 => format!("{r:.0}"),
        r if r >= 1.0 => format!("{r:.1}"),
        r => format!("{r:.2}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn workers_stepping_at_once_each_log_their_own_position() {
        let steps = 2000;
        let bar = ProgressBar::hidden();
        bar.set_length(steps);
        let log = LogLines::new(
            "monte carlo".into(),
            "passes",
            Duration::ZERO,
            Instant::now(),
        );
        let progress = Progress {
            bar,
            log: Some(Arc::new(Mutex::new(log))),
        };
        let lines: Vec<String> = std::thread::scope(|scope| {
            let workers: Vec<_> = (0..4)
                .map(|_| {
                    scope.spawn(|| {
                        (0..steps / 4)
                            .filter_map(|_| progress.step(1))
                            .collect::<Vec<_>>()
                    })
                })
                .collect();
            workers
                .into_iter()
                .flat_map(|w| w.join().unwrap())
                .collect()
        });
        let mut positions: Vec<u64> = lines
            .iter()
            .map(|line| {
                let done = line.split(", ").next().unwrap();
                done.split(": ")
                    .nth(1)
                    .unwrap()
                    .split('/')
                    .next()
                    .unwrap()
                    .parse()
                    .unwrap()
            })
            .collect();
        assert!(positions.len() > 1, "{lines:?}");
        let logged = positions.len();
        positions.sort_unstable();
        positions.dedup();
        assert_eq!(positions.len(), logged, "two lines logged one position");
        assert_eq!(progress.bar.position(), steps);
    }

    #[test]
    fn a_line_is_logged_once_the_interval_has_passed_with_the_rate_since_the_last() {
        let start = Instant::now();
        let at = |seconds: u64| start + Duration::from_secs(seconds);
        let mut log = LogLines::new(
            "DCNet EM5 0123456789abcdef".into(),
            "samples",
            Duration::from_secs(30),
            start,
        );
        assert_eq!(log.due(at(10), 1000, 12_000, "epoch 1/4, loss 0.5"), None);
        assert_eq!(log.due(at(29), 2900, 12_000, "epoch 1/4, loss 0.5"), None);
        assert_eq!(
            log.due(at(30), 3000, 12_000, "epoch 1/4, loss 0.4321")
                .as_deref(),
            Some(
                "DCNet EM5 0123456789abcdef: epoch 1/4, loss 0.4321, 3000/12000 samples, \
                 100 samples/s, ETA 1m 30s"
            )
        );
        // The next line waits another interval, and its rate is that since the last.
        assert_eq!(log.due(at(59), 3000, 12_000, "epoch 2/4, loss 0.3"), None);
        assert_eq!(
            log.due(at(90), 4500, 12_000, "epoch 2/4, loss 0.3")
                .as_deref(),
            Some(
                "DCNet EM5 0123456789abcdef: epoch 2/4, loss 0.3, 4500/12000 samples, \
                 25.0 samples/s, ETA 5m"
            )
        );
        // A task that did not advance has no ETA.
        assert_eq!(
            log.due(at(120), 4500, 12_000, "").as_deref(),
            Some("DCNet EM5 0123456789abcdef: 4500/12000 samples, 0.00 samples/s, ETA unknown")
        );
    }

    #[test]
    fn a_resumed_position_is_not_counted_in_the_rate() {
        let start = Instant::now();
        let mut log = LogLines::new("dataset".into(), "combinations", Duration::ZERO, start);
        log.last_position = 500;
        let line = log.due(start + Duration::from_secs(2), 700, 1134, "");
        assert_eq!(
            line.as_deref(),
            Some("dataset: 700/1134 combinations, 100 combinations/s, ETA 4s")
        );
    }
}
