//! How long a stage's workers had no work: measured, not guessed from wall
//! times at two thread counts.
//!
//! Over a stage of wall time W run by N workers, the workers (and the
//! thread that started the stage) ran for R and waited a further Q runnable
//! but off every CPU (another process held it). Linux counts both per thread (`/proc/self/task/*/
//! schedstat`: run time and run-queue wait), so the time during which a
//! worker had nothing to do is N·W − R − Q: a stage whose work one worker
//! does while the others wait shows it whole; one the others share shows
//! none. A worker spinning briefly before it sleeps counts as running, and
//! on a machine busy with other work its spin's yields wait in the run
//! queue, so the figure is an underestimate there: measure on a quiet
//! machine. Elsewhere than Linux nothing is measured.
//!
//! From it, Amdahl's law: at N = 2 the idle time I is a serial part S = I
//! (one worker runs, the other waits), the work is T₁ = 2W − I, and at 16
//! threads the stage would take S + (T₁ − S)/16 ([`IdleTime::predicted`]).

use std::time::Instant;

/// The calling thread's id in `/proc/self/task`, where the kernel says it.
fn thread_id() -> Option<u64> {
    let link = std::fs::read_link("/proc/thread-self").ok()?;
    link.file_name()?.to_str()?.parse().ok()
}

/// The run time and run-queue wait of the threads `ids`, in nanoseconds;
/// `None` where the kernel does not say.
fn thread_times(ids: &[u64]) -> Option<(u64, u64)> {
    let (mut run, mut wait) = (0u64, 0u64);
    for id in ids {
        let text = std::fs::read_to_string(format!("/proc/self/task/{id}/schedstat")).ok()?;
        let mut fields = text.split_whitespace().map(str::parse::<u64>);
        run += fields.next()?.ok()?;
        wait += fields.next()?.ok()?;
    }
    Some((run, wait))
}

/// A stage's start: the wall clock and the threads' times.
#[derive(Debug, Clone)]
pub struct IdleClock {
    start: Instant,
    /// The threads the stage runs on: the current pool's workers and the
    /// calling thread (which runs the stage's serial parts when it is not
    /// one of them); other threads of the process are not counted.
    threads: Vec<u64>,
    times: Option<(u64, u64)>,
    workers: usize,
}

impl IdleClock {
    /// Starts timing a stage that runs on the current pool's workers.
    #[must_use]
    pub fn start() -> IdleClock {
        let mut threads: Vec<u64> =
            rayon::broadcast(|_| thread_id()).into_iter().chain([thread_id()]).flatten().collect();
        threads.sort_unstable();
        threads.dedup();
        let times = thread_times(&threads);
        IdleClock { start: Instant::now(), threads, times, workers: rayon::current_num_threads() }
    }

    /// The stage so far: its wall time and the time its workers had no work.
    #[must_use]
    pub fn stop(&self) -> IdleTime {
        let wall = self.start.elapsed().as_secs_f64() * 1e3;
        let idle = self.times.zip(thread_times(&self.threads)).map(|((r0, q0), (r1, q1))| {
            let busy = (r1.saturating_sub(r0) + q1.saturating_sub(q0)) as f64 * 1e-6;
            (self.workers as f64 * wall - busy).max(0.0)
        });
        IdleTime { wall_ms: wall, idle_ms: idle.unwrap_or(0.0), measured: idle.is_some(), workers: self.workers }
    }
}

/// A stage's wall time and the time its workers had no work, summed over
/// workers, in milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct IdleTime {
    /// Wall time.
    pub wall_ms: f64,
    /// Time workers had no work, summed over them.
    pub idle_ms: f64,
    /// Whether the idle time was measured (the kernel told the threads'
    /// times).
    pub measured: bool,
    /// Workers the stage ran on.
    pub workers: usize,
}

impl IdleTime {
    /// The sum of two stretches of one stage.
    #[must_use]
    pub fn plus(self, other: IdleTime) -> IdleTime {
        IdleTime {
            wall_ms: self.wall_ms + other.wall_ms,
            idle_ms: self.idle_ms + other.idle_ms,
            measured: self.measured || other.measured,
            workers: self.workers.max(other.workers),
        }
    }

    /// The stage less a stretch of it measured on its own.
    #[must_use]
    pub fn minus(self, part: IdleTime) -> IdleTime {
        IdleTime {
            wall_ms: (self.wall_ms - part.wall_ms).max(0.0),
            idle_ms: (self.idle_ms - part.idle_ms).max(0.0),
            ..self
        }
    }

    /// The share of the wall time during which one worker ran alone, as
    /// if every idle moment left all workers but one waiting: idle time over
    /// (N − 1)·W; 0 for one worker.
    #[must_use]
    pub fn serial_share(&self) -> f64 {
        if self.workers < 2 || self.wall_ms <= 0.0 {
            return 0.0;
        }
        (self.idle_ms / ((self.workers - 1) as f64 * self.wall_ms)).min(1.0)
    }

    /// Amdahl's prediction of the stage's wall time on `threads` workers:
    /// its serial part S (the idle time over N − 1) as it is, the rest of
    /// its work T = N·W − idle shared.
    #[must_use]
    pub fn predicted(&self, threads: usize) -> f64 {
        let n = self.workers.max(1) as f64;
        let serial = self.serial_share() * self.wall_ms;
        let work = n * self.wall_ms - self.idle_ms;
        serial + (work - serial).max(0.0) / threads.max(1) as f64
    }
}
