//! What textures cost a frame: each textured model of the corpus rendered as
//! `kage render FILE` sets it up, and again with every material's texture
//! maps taken away (its constant coefficients kept: a baked glTF material
//! turns white, at the cost of an untextured one), frames of the two
//! alternated on two renderers; with the time to load each model and the
//! bytes its decoded textures hold.

use std::time::Instant;

use kage::scene::model::scene_for_model;
use kage::scene::ComponentMaps;
use kage::Scene;
use miette::{miette, Result};

use crate::{median, Common};

/// `kage-bench textures`.
#[derive(clap::Args, Debug)]
pub struct TexturesArgs {
    #[command(flatten)]
    common: Common,
    /// A model to measure instead of the corpus's (repeatable): any file
    /// `kage render` reads, by its path.
    #[arg(long = "model")]
    models: Vec<std::path::PathBuf>,
}

/// The corpus's textured models, by their path under `assets/`.
const MODELS: &[&str] = &[
    "gltf/Avocado/Avocado.gltf",
    "gltf/Suzanne/Suzanne.gltf",
    "gltf/CesiumMilkTruck/CesiumMilkTruck.glb",
    "gltf/LightsPunctualLamp/LightsPunctualLamp.gltf",
    "scenes/sponza-dabrovic/sponza.obj",
];

/// `scene` with every material's texture maps taken away.
fn untextured(scene: &Scene) -> Scene {
    let mut bare = scene.clone();
    for m in &mut bare.materials {
        m.maps = ComponentMaps { filter: m.maps.filter, ..ComponentMaps::default() };
    }
    bare
}

/// Milliseconds of each frame of `a` and `b`, rendered in turn `frames`
/// times after a warm-up of each: their medians.
fn alternated(a: &Scene, b: &Scene, frames: usize) -> Result<(f64, f64)> {
    let options = kage::RenderOptions { keep_shadow_maps: false, ..Default::default() };
    let new = || kage::Renderer::new(&options).map_err(|e| miette!("{e}"));
    let (mut ra, mut rb) = (new()?, new()?);
    ra.render(a).map_err(|e| miette!("{e}"))?;
    rb.render(b).map_err(|e| miette!("{e}"))?;
    let (mut ta, mut tb) = (Vec::new(), Vec::new());
    for _ in 0..frames.max(1) {
        for (r, s, t) in [(&mut ra, a, &mut ta), (&mut rb, b, &mut tb)] {
            let start = Instant::now();
            r.render(s).map_err(|e| miette!("{e}"))?;
            t.push(start.elapsed().as_secs_f64() * 1e3);
        }
    }
    Ok((median(&mut ta), median(&mut tb)))
}

/// Prints the table.
///
/// # Errors
///
/// When a model does not load or render.
pub fn run(args: &TexturesArgs) -> Result<()> {
    let c = &args.common;
    let size = (c.width, c.height);
    println!("| model | textures (decoded MB) | load ms | textured frame ms | untextured frame ms | ratio |");
    println!("|---|---:|---:|---:|---:|---:|");
    let paths: Vec<_> = if args.models.is_empty() {
        MODELS.iter().map(|rel| c.assets().join(rel)).collect()
    } else {
        args.models.clone()
    };
    for path in paths {
        if !path.exists() {
            eprintln!("skipped: {} does not exist", path.display());
            continue;
        }
        let start = Instant::now();
        let scene = scene_for_model(&path, size.0, size.1).map_err(|e| miette!("{}: {e}", path.display()))?;
        let load = start.elapsed().as_secs_f64() * 1e3;
        let (count, bytes) = decoded(&scene);
        let (textured, bare) = alternated(&scene, &untextured(&scene), c.frames)?;
        let name = path.file_name().unwrap_or_default().to_string_lossy();
        println!(
            "| {name} | {count} ({:.0}) | {load:.0} | {textured:.1} | {bare:.1} | {:.2} |",
            bytes as f64 / 1e6,
            textured / bare
        );
    }
    println!(
        "\n{}×{}, the edge pass on, shadow maps rendered every frame; median of {} frames of each, the two \
         alternated after a warm-up of each; 2 threads. Textures: the distinct decoded textures the materials \
         hold (an image several materials name counts once), and their bytes with their mip levels.",
        size.0, size.1, c.frames
    );
    Ok(())
}

/// How many distinct decoded textures `scene`'s materials hold (copies that
/// differ in their wrap mode only counted once), and their bytes.
fn decoded(scene: &Scene) -> (usize, usize) {
    let mut seen: Vec<&kage::scene::Texture> = Vec::new();
    let mut bytes = 0;
    for m in &scene.materials {
        let maps = &m.maps;
        let all = maps.ambient.iter().chain(&maps.diffuse).chain(&maps.specular).chain(&maps.emission);
        let all = all.chain(maps.mirror.iter()).chain(maps.normal.iter().map(|n| &n.texture));
        for t in all {
            if !seen.iter().any(|s| s.shares_texels(t)) {
                seen.push(t);
                bytes += t.memory_bytes();
            }
        }
    }
    (seen.len(), bytes)
}
