//! What the viewer shows: the demo, a scene file or a model, loaded again
//! when it (or a file beside it) changes, with the toggles that change how a
//! model is loaded (the ground, a `.csg` model's exact or faceted quadrics).
//! An OpenSCAD `.scad` file is turned into a `.csg` by `openscad -o` (when
//! `openscad` is on the PATH) at every load.

use std::path::{Path, PathBuf};

use kage::csg::openscad::{CsgOptions, Geometry};
use kage::scene::demo::demo_scene;
use kage::scene::framing::CameraOverride;
use kage::scene::load::InputFormat;
use kage::scene::model::{self, ModelOptions};
use kage::scene::{file, Scene};
use kage::Limits;

use super::state::{Toggles, SECTION_STEP};
use crate::render::extension;

/// Window size when neither the command line nor the scene file gives one.
pub const DEFAULT_SIZE: (u32, u32) = (1280, 720);

/// A file to show, or the demo.
#[derive(Debug, Clone, PartialEq)]
pub struct Source {
    /// The file (`None`: the built-in demo).
    pub path: Option<PathBuf>,
}

impl Source {
    /// Loads the scene with `toggles`' ground and CSG geometry; its size
    /// stays the file's (a scene file's `[image]`) or [`DEFAULT_SIZE`].
    ///
    /// # Errors
    ///
    /// The library's message (with file, line and column for a scene or
    /// `.csg` file) when the file cannot be read or understood.
    pub fn load(&self, toggles: &Toggles) -> Result<Scene, String> {
        let Some(path) = &self.path else {
            return demo_scene().map(|s| cut_across(s, toggles)).map_err(|e| e.to_string());
        };
        match InputFormat::from_path(path) {
            Some(InputFormat::Scene) => {
                file::load_scene(path).map(|s| cut_across(s, toggles)).map_err(|e| e.to_string())
            }
            Some(_) => model_scene(path, toggles),
            None => Err(format!("{}: kage view opens {}", path.display(), InputFormat::described())),
        }
    }

    /// The folder whose files are watched for changes (the file's own).
    #[must_use]
    pub fn folder(&self) -> Option<PathBuf> {
        let path = self.path.as_ref()?;
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        Some(parent.to_path_buf())
    }

    /// Whether a change to `path` should reload the scene.
    #[must_use]
    pub fn is_watched(path: &Path) -> bool {
        InputFormat::watched_extensions().contains(&extension(path).as_str())
    }
}

/// A scene (the demo, a scene file) cut by the toggles' section plane, placed
/// across its shadow casters' box along a world axis.
fn cut_across(mut scene: Scene, toggles: &Toggles) -> Scene {
    let Some((axis, at)) = toggles.section else { return scene };
    let Some((lo, hi)) = scene.caster_bounds().or_else(|| scene.bounds()) else { return scene };
    let normal = glam::Vec3::AXES[axis];
    let point = lo.lerp(hi, f32::from(at) * SECTION_STEP);
    if let Some(plane) = kage::scene::section::SectionPlane::through(point, normal) {
        scene.section(plane);
    }
    scene
}

/// A model file framed on its ground, as `kage render FILE` sets it up,
/// with the toggles' ground and CSG geometry.
fn model_scene(path: &Path, toggles: &Toggles) -> Result<Scene, String> {
    let options = ModelOptions {
        csg: CsgOptions {
            geometry: if toggles.exact_csg { Geometry::Exact } else { Geometry::Faceted },
            skip_unsupported: true,
        },
        up: None,
        ground: toggles.ground,
        file_camera: false,
        camera: CameraOverride::default(),
        limits: Limits::default(),
        section: None,
        section_across: toggles.section.map(|(axis, at)| (glam::Vec3::AXES[axis], f32::from(at) * SECTION_STEP)),
    };
    let (w, h) = DEFAULT_SIZE;
    let scene = if InputFormat::from_path(path) == Some(InputFormat::Scad) {
        crate::scad::scene_for_scad(path, w, h, &options)
    } else {
        model::scene_for_model_with(path, w, h, &options)
    };
    scene.map_err(|e| e.to_string())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A scene file that does not parse reports its file, line and column;
    /// an unknown kind of file says what the viewer opens.
    #[test]
    fn bad_files_say_where_and_why() {
        let dir = std::env::temp_dir().join(format!("kage-view-source-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("broken.toml");
        std::fs::write(&scene, "[camera]\neye = \"up\"\n").unwrap();
        let e = Source { path: Some(scene.clone()) }.load(&Toggles::default()).unwrap_err();
        assert!(e.contains("broken.toml:2:"), "{e}");
        let e = Source { path: Some(dir.join("notes.txt")) }.load(&Toggles::default()).unwrap_err();
        assert!(e.contains("kage view opens"), "{e}");
        let scad = dir.join("part.scad");
        std::fs::write(&scad, "cube([1, 2, 3]);\n").unwrap();
        let loaded = Source { path: Some(scad) }.load(&Toggles::default());
        match loaded {
            Ok(scene) => assert!(!scene.objects.is_empty(), "OpenSCAD's cube is shown"),
            Err(e) => assert!(e.contains("`openscad` is not on the PATH"), "{e}"),
        }
        std::fs::write(dir.join("bad.scad"), "cube([1, 2, 3]\n").unwrap();
        let loaded = Source { path: Some(dir.join("bad.scad")) }.load(&Toggles::default());
        match loaded {
            Ok(_) => panic!("a .scad that does not parse loads"),
            Err(e) => assert!(e.contains("openscad failed") || e.contains("not on the PATH"), "{e}"),
        }
        assert!(Source { path: None }.load(&Toggles::default()).is_ok(), "the demo loads");
        assert!(Source::is_watched(Path::new("a/part.STL")) && !Source::is_watched(Path::new("notes.txt")));
        std::fs::remove_dir_all(&dir).ok();
    }
}
