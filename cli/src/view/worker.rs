//! The refinement's steps rendered on a thread of their own, so the window
//! keeps taking input while a step renders. Each step carries a stop flag:
//! input that makes the step stale raises it, and the renderer gives the
//! step up before its next stage ([`kage::Renderer::render_or_stop`]).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use kage::{FrameStats, Scene};

use super::refine::{Refiner, Shown};
use super::state::{Step, Viewer};

/// A step to render.
#[derive(Debug)]
pub struct Job {
    /// The scene as loaded (the viewer's camera and toggles apply on top).
    pub scene: Arc<Scene>,
    /// The viewer as it was when the step was asked for.
    pub viewer: Viewer,
    /// Which step.
    pub step: Step,
    /// Raised when the step is no longer wanted.
    pub stop: Arc<AtomicBool>,
}

/// How a step ended.
#[derive(Debug, Clone)]
pub enum Outcome {
    /// Rendered (what is shown updated, unless the step is a pass averaged
    /// but not shown yet): the frame's statistics.
    Rendered(Box<FrameStats>),
    /// Given up: its stop flag was raised before what it shows was written.
    Stopped,
    /// The scene could not be rendered.
    Failed(String),
}

/// A step the worker finished with.
#[derive(Debug, Clone)]
pub struct Done {
    /// Which step.
    pub step: Step,
    /// How it ended.
    pub outcome: Outcome,
    /// How long it took.
    pub took: Duration,
    /// When it ended.
    pub at: Instant,
}

/// The rendering thread.
pub struct Worker {
    jobs: Option<mpsc::Sender<Job>>,
    thread: Option<JoinHandle<()>>,
}

impl Worker {
    /// Starts the thread, rendering on `threads` workers (`None`: one per
    /// core) into `shown`; `report` hears of each step it finishes with.
    ///
    /// # Panics
    ///
    /// When the system cannot start a thread.
    pub fn spawn(threads: Option<usize>, shown: Arc<Mutex<Shown>>, report: impl Fn(Done) + Send + 'static) -> Worker {
        let (jobs, inbox) = mpsc::channel::<Job>();
        let thread = std::thread::Builder::new()
            .name("kage-view-render".into())
            .spawn(move || {
                let mut refiner = Refiner::new(threads);
                for job in inbox {
                    report(render(&mut refiner, &job, &shown));
                }
            })
            .expect("the rendering thread starts");
        Worker { jobs: Some(jobs), thread: Some(thread) }
    }

    /// Queues `job` (the window sends one at a time, the next when it hears
    /// the last is done).
    pub fn send(&self, job: Job) {
        if let Some(jobs) = &self.jobs {
            jobs.send(job).ok();
        }
    }
}

impl Drop for Worker {
    /// Waits for the thread to finish its step (stop it first to be quick).
    fn drop(&mut self) {
        self.jobs = None;
        if let Some(thread) = self.thread.take() {
            thread.join().ok();
        }
    }
}

/// Renders one job into `shown`.
fn render(refiner: &mut Refiner, job: &Job, shown: &Mutex<Shown>) -> Done {
    let start = Instant::now();
    let outcome = if job.stop.load(Ordering::Relaxed) {
        Outcome::Stopped
    } else {
        match refiner.render(&job.scene, &job.viewer, job.step, &job.stop, shown) {
            Ok(stats) => Outcome::Rendered(Box::new(stats)),
            Err(kage::Error::Stopped) => Outcome::Stopped,
            Err(e) => Outcome::Failed(e.to_string()),
        }
    };
    Done { step: job.step, outcome, took: start.elapsed(), at: Instant::now() }
}
