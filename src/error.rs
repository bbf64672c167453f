//! Typed errors of the library.
//!
//! Every error that comes from a user's file names the file; errors inside a scene
//! file also carry a [`SourceLocation`] (line, column, byte span and the text), which
//! the command line turns into a report that points at the offending characters.

use std::ops::Range;
use std::path::PathBuf;
use std::sync::Arc;

/// Where in a text file something went wrong.
#[derive(Debug, Clone)]
pub struct SourceLocation {
    /// The file, as the user named it (or `<builtin demo>` for embedded scenes).
    pub path: PathBuf,
    /// 1-based line.
    pub line: usize,
    /// 1-based column, in characters.
    pub column: usize,
    /// Byte range of the offending text.
    pub span: Range<usize>,
    /// The whole file, so a report can show the line in context.
    pub text: Arc<str>,
}

impl SourceLocation {
    /// Locates byte range `span` of `text` (clamped to the text).
    #[must_use]
    pub fn new(path: impl Into<PathBuf>, text: Arc<str>, span: Range<usize>) -> Self {
        let start = floor_char_boundary(&text, span.start.min(text.len()));
        let end = floor_char_boundary(&text, span.end.clamp(start, text.len()));
        let before = &text[..start];
        let line = before.matches('\n').count() + 1;
        let line_start = before.rfind('\n').map_or(0, |i| i + 1);
        let column = text[line_start..start].chars().count() + 1;
        Self { path: path.into(), line, column, span: start..end, text }
    }
}

fn floor_char_boundary(text: &str, mut i: usize) -> usize {
    while !text.is_char_boundary(i) {
        i -= 1;
    }
    i
}

impl std::fmt::Display for SourceLocation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}:{}:{}", self.path.display(), self.line, self.column)
    }
}

/// Everything that can go wrong between a scene file and an image.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The scene file is not valid TOML or does not match the scene format.
    #[error("{location}: {message}")]
    SceneSyntax {
        /// Where the parser stopped.
        location: Box<SourceLocation>,
        /// What was expected there.
        message: String,
    },
    /// An OpenSCAD `.csg` file does not follow the grammar OpenSCAD writes.
    #[error("{location}: {message}")]
    CsgSyntax {
        /// Where the parser stopped.
        location: Box<SourceLocation>,
        /// What was expected there.
        message: String,
    },
    /// An OpenSCAD `.csg` file parses but holds what kage cannot render (a
    /// non-convex polyhedron, a node out of scope, a malformed argument).
    #[error("{location}: {message}")]
    CsgInvalid {
        /// The offending node or argument.
        location: Box<SourceLocation>,
        /// What is wrong with it.
        message: String,
    },
    /// The scene file parses but says something impossible (unknown material, bad value).
    #[error("{location}: {message}")]
    SceneInvalid {
        /// The offending value.
        location: Box<SourceLocation>,
        /// What is wrong with it.
        message: String,
    },
    /// A file could not be read.
    #[error("cannot read {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A mesh file could not be parsed.
    #[error("cannot load mesh {}: {message}", path.display())]
    MeshLoad {
        /// The mesh file.
        path: PathBuf,
        /// What the loader said.
        message: String,
    },
    /// A mesh loaded but its data cannot be rendered (NaN vertices, no triangles...).
    #[error("invalid mesh {}: {message}", path.display())]
    MeshInvalid {
        /// The mesh file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A texture could not be read or decoded.
    #[error("cannot load texture {}: {message}", path.display())]
    TextureLoad {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        message: String,
    },
    /// The requested image size is zero or too large; refused before allocating.
    #[error("invalid image size {width}x{height}: {reason}")]
    ImageSize {
        /// Requested width in pixels.
        width: u64,
        /// Requested height in pixels.
        height: u64,
        /// Why it is refused.
        reason: &'static str,
    },
    /// The worker threads asked for cannot be had: more than kage allows, or
    /// more than the system starts.
    #[error("{requested} threads requested, but {reason}")]
    Threads {
        /// Threads asked for.
        requested: usize,
        /// Why not.
        reason: String,
    },
    /// The scene has nothing that can be drawn, or a value makes the camera unusable.
    #[error("invalid scene: {0}")]
    Scene(String),
    /// A file or scene asks for more than its [`crate::limits::Limits`] allow:
    /// refused before the work, naming the limit and how to raise it.
    #[error("{0}")]
    Limit(#[from] crate::limits::LimitExceeded),
    /// An image to measure could not be read or decoded.
    #[error("cannot read image {}: {message}", path.display())]
    ImageRead {
        /// The image file.
        path: PathBuf,
        /// What the decoder said.
        message: String,
    },
    /// Two images that must match in size do not.
    #[error("images differ in size: {}x{} vs {}x{}", a.0, a.1, b.0, b.1)]
    SizeMismatch {
        /// Width and height of the first.
        a: (u32, u32),
        /// Width and height of the second.
        b: (u32, u32),
    },
    /// An input file of a kind kage does not read.
    #[error("{}: not a file kage reads; it reads {reads}", path.display())]
    UnknownInput {
        /// The file.
        path: PathBuf,
        /// What it reads (`scene::load::InputFormat::described`).
        reads: String,
    },
    /// A region of the frame to render that is empty or does not lie inside it.
    #[error("the region {}..{} x {}..{} is not a part of the {width}x{height} image", region.0, region.2, region.1, region.3)]
    Region {
        /// The region asked for: its first column and row, one past its
        /// last column and row.
        region: (u32, u32, u32, u32),
        /// The frame's width.
        width: u32,
        /// The frame's height.
        height: u32,
    },
    /// A frame was given up because its caller raised the stop flag
    /// ([`crate::Renderer::render_or_stop`]).
    #[error("the frame was stopped before it was done")]
    Stopped,
    /// The output image could not be written.
    #[error("cannot write {}: {message}", path.display())]
    Output {
        /// The output file.
        path: PathBuf,
        /// Why.
        message: String,
    },
}

/// Shorthand for results of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;
