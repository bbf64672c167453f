//! `kage-bench ao`: ambient occlusion after the viewer's refinement passes
//! against the reference renderer's, and what it costs a frame; beside it
//! what the x-ray view and feature lines cost a frame and a section plane
//! its one cut.
//!
//! Each scene is rendered as ambient occlusion alone (every material a white
//! ambient reflector, one white ambient light, a black background), so the
//! image is the open share itself: the raster frame's jittered passes (the
//! viewer's: the sub-pixel points of `jitter:64`, new rays each pass) beside
//! the reference (n × n rays a pixel, many ambient-occlusion rays at each hit).

use std::path::PathBuf;

use glam::Vec3;
use kage::scene::{AmbientOcclusion, Antialias, FeatureLines, Light, Material, Scene, ShadowSettings};
use kage::{render_reference, ReferenceOptions, RenderOptions, Renderer};
use miette::{miette, Result};

use crate::share::median_csg;
use crate::{median, Common};

/// Options of `kage-bench ao`.
#[derive(clap::Args, Debug)]
pub struct AoArgs {
    #[command(flatten)]
    common: Common,
    /// Jittered passes (the viewer refines to 64).
    #[arg(long, default_value_t = 64)]
    passes: u32,
    /// Ambient-occlusion rays a pixel casts in each pass (the viewer's).
    #[arg(long, default_value_t = 4)]
    pass_rays: u32,
    /// The reference's rays a pixel along each axis.
    #[arg(long, default_value_t = 4)]
    reference_spp: u32,
    /// The reference's ambient-occlusion rays at each hit.
    #[arg(long, default_value_t = 128)]
    reference_rays: u32,
}

/// `scene` drawn as ambient occlusion alone: white ambient reflectors under
/// one white ambient light, nothing else.
fn occlusion_only(scene: &Scene, ao: AmbientOcclusion) -> Scene {
    let mut s = scene.clone();
    for m in &mut s.materials {
        *m = Material {
            name: m.name.clone(),
            ka: Vec3::ONE,
            kd: Vec3::ZERO,
            two_sided: m.two_sided,
            ..Material::default()
        };
    }
    s.lights = vec![Light { ambient: 1.0, intensity: 0.0, shadow: ShadowSettings::NONE, ..Light::default() }];
    (s.fog, s.environment, s.background) = (None, None, Vec3::ZERO);
    s.ambient_occlusion = Some(ao);
    s
}

/// The scenes measured: the demo, the bunny and the truck (when
/// `../shared/assets` holds them) and the corpus `.csg` model of median frame
/// time.
fn scenes(c: &Common) -> Result<Vec<(String, Scene)>> {
    let size = (c.width, c.height);
    let mut out = Vec::new();
    let mut demo = kage::scene::demo::demo_scene().map_err(|e| miette!("{e}"))?;
    (demo.width, demo.height) = size;
    out.push(("demo".to_string(), demo));
    let assets = c.assets();
    let mut files: Vec<PathBuf> = Vec::new();
    for model in ["meshes/stanford-bunny/stanford-bunny.obj", "gltf/CesiumMilkTruck/CesiumMilkTruck.glb"] {
        let path = assets.join(model);
        if path.exists() {
            files.push(path);
        } else {
            eprintln!("skipped {} (not found)", path.display());
        }
    }
    files.extend(median_csg(&assets.join("csg"), size, 1)?);
    for path in files {
        let scene = kage::scene::model::scene_for_model(&path, size.0, size.1)
            .map_err(|e| miette!("{}: {e}", path.display()))?;
        out.push((path.file_name().unwrap_or_default().to_string_lossy().into_owned(), scene));
    }
    Ok(out)
}

/// Runs the table.
///
/// # Errors
///
/// When a scene does not load or render.
pub fn run(args: &AoArgs) -> Result<()> {
    let c = &args.common;
    println!(
        "| scene | size | radius | full frame ms (no AO) | AO ms, 16 rays | AO ms a pass ({} rays) | quick frame ms | quick AO ms (screen space) | quick frame with it ms | RMSE after the full frame | RMSE after {} passes | RMSE of quick AO | reference s | x-ray frame ms | lines: frame ms, with lines ms | section ms (once) |",
        args.pass_rays, args.passes
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, scene) in scenes(c)? {
        // The radius the scene itself gets (its floor left out of the model's size).
        let with_ao = Scene { ambient_occlusion: Some(AmbientOcclusion::default()), ..scene.clone() };
        let radius = with_ao.occlusion_radius().unwrap_or_default();
        let full_ao = AmbientOcclusion { radius: Some(radius), ..AmbientOcclusion::default() };
        // What ambient occlusion costs the full frame of the scene as it is.
        let mut renderer = Renderer::new(&RenderOptions::default()).map_err(|e| miette!("{e}"))?;
        let mut timed = |s: &Scene| -> Result<(f64, f64)> {
            let mut v = (Vec::new(), Vec::new());
            for _ in 0..c.frames.max(1) {
                let t = std::time::Instant::now();
                let stats = renderer.render(s).map_err(|e| miette!("{e}"))?.stats;
                v.0.push(t.elapsed().as_secs_f64() * 1e3);
                v.1.push(stats.occlusion_ms);
            }
            Ok((median(&mut v.0), median(&mut v.1)))
        };
        let plain = timed(&scene)?.0;
        let with = timed(&with_ao)?.1;
        let mut xray = scene.clone();
        xray.xray(kage::scene::XRAY_OPACITY);
        // X-ray frames and frames of the scene as it is, one after the other
        // (each through its own renderer, so that neither evicts the other's
        // shadow maps): what the x-ray view costs beside the frame it replaces.
        let (mut xray_frames, mut beside) = (Vec::new(), Vec::new());
        let mut xray_renderer = Renderer::new(&RenderOptions::default()).map_err(|e| miette!("{e}"))?;
        for _ in 0..c.frames.max(1) {
            let t = std::time::Instant::now();
            xray_renderer.render(&xray).map_err(|e| miette!("{e}"))?;
            xray_frames.push(t.elapsed().as_secs_f64() * 1e3);
            let t = std::time::Instant::now();
            renderer.render(&scene).map_err(|e| miette!("{e}"))?;
            beside.push(t.elapsed().as_secs_f64() * 1e3);
        }
        let (xray_ms, beside) = (median(&mut xray_frames), median(&mut beside));
        let quick_scene = Scene { antialias: Antialias::None, ..scene.clone() };
        let screen_ao = AmbientOcclusion { screen_space: true, ..full_ao };
        let quick_with = Scene { ambient_occlusion: Some(screen_ao), ..quick_scene.clone() };
        // Quick frames with and without it, one after the other: its own
        // stage, and what the whole frame gains.
        let (mut quick, mut quick_with_ms, mut quick_ao) = (Vec::new(), Vec::new(), Vec::new());
        for _ in 0..c.frames.max(1) {
            let t = std::time::Instant::now();
            renderer.render(&quick_scene).map_err(|e| miette!("{e}"))?;
            quick.push(t.elapsed().as_secs_f64() * 1e3);
            let t = std::time::Instant::now();
            let stats = renderer.render(&quick_with).map_err(|e| miette!("{e}"))?.stats;
            quick_with_ms.push(t.elapsed().as_secs_f64() * 1e3);
            quick_ao.push(stats.occlusion_ms);
        }
        let (quick, quick_with_ms, quick_ao) = (median(&mut quick), median(&mut quick_with_ms), median(&mut quick_ao));
        // Feature lines: frames with and without them, one after the other.
        let lined = Scene { lines: Some(FeatureLines::default()), ..scene.clone() };
        let (mut without, mut with_lines) = (Vec::new(), Vec::new());
        for _ in 0..c.frames.max(1) {
            for (s, out) in [(&scene, &mut without), (&lined, &mut with_lines)] {
                let t = std::time::Instant::now();
                renderer.render(s).map_err(|e| miette!("{e}"))?;
                out.push(t.elapsed().as_secs_f64() * 1e3);
            }
        }
        let (without, with_lines) = (median(&mut without), median(&mut with_lines));
        // A section through the middle of the model's box, across its longest side.
        let section_ms = {
            let (lo, hi) = scene.caster_bounds().or_else(|| scene.bounds()).unwrap_or_default();
            let axis = Vec3::AXES[(hi - lo).max_position()];
            let plane = kage::scene::section::SectionPlane::through((lo + hi) * 0.5, axis).expect("a plane");
            let mut cut = scene.clone();
            let t = std::time::Instant::now();
            cut.section(plane);
            t.elapsed().as_secs_f64() * 1e3
        };
        // The open share: the full frame, then the passes, against the reference.
        let full = occlusion_only(&scene, full_ao);
        let first = kage::render(&full, &RenderOptions::default()).map_err(|e| miette!("{e}"))?.image;
        let pass_ao = AmbientOcclusion { rays: args.pass_rays, ..full_ao };
        let passes = Scene { antialias: Antialias::Jitter(args.passes), ..occlusion_only(&scene, pass_ao) };
        let refined = kage::render(&passes, &RenderOptions::default()).map_err(|e| miette!("{e}"))?;
        let pass_ms = refined.stats.occlusion_ms / f64::from(args.passes);
        let screen = Scene { antialias: Antialias::None, ..occlusion_only(&scene, screen_ao) };
        let screen = kage::render(&screen, &RenderOptions::default()).map_err(|e| miette!("{e}"))?.image;
        let opts = ReferenceOptions {
            pixel_samples: args.reference_spp,
            shadows: false,
            max_depth: 0,
            occlusion_rays: args.reference_rays,
            ..ReferenceOptions::default()
        };
        let t = std::time::Instant::now();
        let truth = render_reference(&full, &opts, &|_| {});
        let reference_s = t.elapsed().as_secs_f64();
        let rmse = |image| kage::compare::compare(image, &truth, 0.05).map(|e| e.rmse).map_err(|e| miette!("{e}"));
        println!(
            "| {name} | {}x{} | {radius:.3} | {plain:.1} | {with:.1} | {pass_ms:.1} | {quick:.1} | {quick_ao:.1} ({:.0}%) | {quick_with_ms:.1} ({:.2}x) | {:.4} | {:.4} | {:.4} | {reference_s:.1} | {xray_ms:.1} ({:.2}x) | {without:.1}, {with_lines:.1} ({:.2}x) | {section_ms:.1} |",
            c.width,
            c.height,
            100.0 * quick_ao / quick,
            quick_with_ms / quick,
            rmse(&first)?,
            rmse(&refined.image)?,
            rmse(&screen)?,
            xray_ms / beside,
            with_lines / without,
        );
    }
    println!(
        "\nOpen share alone (white ambient reflectors, one white ambient light): the full frame (edge pass, {} rays a pixel), {} jittered passes of {} rays (the viewer's refinement), the quick frame's screen-space estimate (no antialiasing, the viewer's while the camera moves), and the reference ({} x {} rays a pixel, {} AO rays at each hit); frame times of the scene as it is, median of {} frames (x-ray frames beside frames of the scene, frames with and without feature lines, and quick frames with and without the screen-space estimate: one frame of each in turn, the median of each); {} threads.",
        AmbientOcclusion::default().rays,
        args.passes,
        args.pass_rays,
        args.reference_spp,
        args.reference_spp,
        args.reference_rays,
        c.frames.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}
