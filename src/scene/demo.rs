//! The built-in demo scene: `examples/scenes/demo.toml` and the meshes it names,
//! compiled into the binary so `kage render` works with no files at all.

use std::path::Path;

use super::file::SceneFile;
use super::load::Embedded;
use super::Scene;
use crate::error::Result;

/// The demo scene's text.
pub const DEMO_SCENE: &str = include_str!("../../examples/scenes/demo.toml");

static FILES: [(&str, &[u8]); 5] = [
    ("teapot.obj", include_bytes!("../../assets/teapot.obj")),
    ("default.mtl", include_bytes!("../../assets/default.mtl")),
    ("default.png", include_bytes!("../../assets/default.png")),
    ("spot_triangulated.obj", include_bytes!("../../assets/spot_triangulated.obj")),
    ("spot_texture.png", include_bytes!("../../assets/spot_texture.png")),
];

/// Builds the demo scene from the embedded files.
///
/// # Errors
///
/// None in a released build: the scene and its files are compiled in (an
/// error would mean they were edited into something that does not load).
pub fn demo_scene() -> Result<Scene> {
    SceneFile::parse(DEMO_SCENE, Path::new("<builtin demo>"))?.build(&Embedded(&FILES))
}
