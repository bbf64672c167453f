//! `kage view`: the interactive preview window.
//!
//! [`state`] is what the viewer does with its input, apart from any window
//! (tested without one); [`orbit`] is its camera; [`refine`] renders the
//! refinement steps the state asks for, and [`worker`] renders them on a
//! thread of their own, each given up when input makes it stale; [`source`]
//! loads what is shown and says which changes reload it; [`script`] reads
//! scripted input; [`hud`] draws text; [`window`] ties them to a winit window
//! with a softbuffer frame buffer.

pub mod hud;
pub mod orbit;
pub mod refine;
pub mod script;
pub mod source;
pub mod state;
pub mod window;
pub mod worker;

use std::path::PathBuf;

/// Options of `kage view`.
#[derive(clap::Args, Debug)]
pub struct ViewArgs {
    /// Scene or model file to show and watch (omit for the built-in demo).
    pub input: Option<PathBuf>,
    /// Window width in pixels (default: a scene file's, else 1280).
    #[arg(long)]
    pub width: Option<u32>,
    /// Window height in pixels (default: a scene file's, else 720).
    #[arg(long)]
    pub height: Option<u32>,
    /// Input events read from a file, one per line (tests, recordings):
    /// `drag left DX DY [shift]`, `wheel N`, `key K`, `drop FILE`, `wait`,
    /// `wait N` (N jittered passes), `sleep S`, `screenshot FILE` (the image),
    /// `capture FILE` (the window, HUD and all), `copy FROM TO`, `quit`.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    pub threads: Option<usize>,
    /// When the window closes, print the time to the first image, the quick
    /// frames' median time while the camera moved, and the time from the
    /// last input to the fully refined image.
    #[arg(long)]
    pub timings: bool,
}

/// Runs `kage view`.
///
/// # Errors
///
/// A script that cannot be read or parsed, or no window (no display).
pub fn run(args: &ViewArgs) -> Result<(), String> {
    let script = match &args.script {
        Some(path) => {
            let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            script::parse(&text, path)?
        }
        None => Vec::new(),
    };
    let size = match (args.width, args.height) {
        (None, None) => None,
        (w, h) => Some((w.unwrap_or(source::DEFAULT_SIZE.0).max(1), h.unwrap_or(source::DEFAULT_SIZE.1).max(1))),
    };
    window::run(window::Start {
        source: source::Source { path: args.input.clone() },
        size,
        script,
        threads: args.threads,
        timings: args.timings,
    })
}
