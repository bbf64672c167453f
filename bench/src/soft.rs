//! `kage-bench soft`: soft shadows — seed 001's two maps (the paper's search
//! every N pixels, the exact distance transform, depth-aware, on shadow maps
//! or silhouette-line buffers), PCSS, and seed 002's jittered light — against
//! the ray-traced area-light truth (32 × 32 stratified rays over the light's
//! disc at every pixel): RMSE and largest error of the key light's shadow
//! term over the penumbra (where the truth is strictly between 0 and 1) and
//! over the image, and ms per frame at two sizes.

use std::path::{Path, PathBuf};

use kage::image::LinearImage;
use kage::raytrace::shadow_truth::ShadowRays;
use kage::scene::file::SceneFile;
use kage::scene::load::FileSystem;
use kage::scene::{HardShadows, LightKind, PenumbraFalloff, PenumbraPoints, Scene, ShadowMethod, ShadowSettings};
use kage::RenderOptions;
use miette::{miette, Result};

use crate::{frame_times, Common};

/// Options of `kage-bench soft`.
#[derive(clap::Args, Debug)]
pub struct SoftArgs {
    #[command(flatten)]
    common: Common,
    /// Size the errors are measured at (square).
    #[arg(long, default_value_t = 512)]
    check: u32,
    /// Rays over the light's disc along each axis for the truth.
    #[arg(long, default_value_t = 32)]
    truth_rays: u32,
    /// Only scenes whose name contains this.
    #[arg(long)]
    only: Option<String>,
    /// Only methods whose name contains this.
    #[arg(long)]
    method: Option<String>,
    /// Also write crops of each method beside the truth here.
    #[arg(long)]
    crops: Option<PathBuf>,
    /// Instead: the two-map method's defects (double shadows of thin
    /// occluders, false umbra where different occluders' shadows overlap)
    /// on scenes made to show them.
    #[arg(long)]
    defects: bool,
}

/// A row of the table: a name and the key light's shadow settings.
struct Method {
    name: &'static str,
    settings: ShadowSettings,
}

/// The rows of the defects' table.
fn defect_methods() -> Vec<Method> {
    let soft = ShadowSettings { method: ShadowMethod::Soft, ..ShadowSettings::MAP };
    vec![
        Method { name: "two maps (default)", settings: soft },
        Method { name: "ring of four", settings: ShadowSettings { points: PenumbraPoints::Ring, ..soft } },
        Method {
            name: "the paper (N = 1, linear)",
            settings: ShadowSettings {
                search: 1,
                penumbra: PenumbraFalloff::Linear,
                depth_aware: false,
                points: PenumbraPoints::Paper,
                ..soft
            },
        },
        Method {
            name: "PCSS 32/64",
            settings: ShadowSettings { method: ShadowMethod::Pcss, blockers: 32, filter: 64, ..ShadowSettings::MAP },
        },
        Method { name: "jittered light, 16", settings: ShadowSettings { samples: 16, ..ShadowSettings::MAP } },
    ]
}

fn methods() -> Vec<Method> {
    let soft = ShadowSettings { method: ShadowMethod::Soft, ..ShadowSettings::MAP };
    let paper = |search| ShadowSettings {
        search,
        penumbra: PenumbraFalloff::Linear,
        depth_aware: false,
        points: PenumbraPoints::Paper,
        ..soft
    };
    let pcss =
        |blockers, filter| ShadowSettings { method: ShadowMethod::Pcss, blockers, filter, ..ShadowSettings::MAP };
    let jittered = |samples| ShadowSettings { samples, ..ShadowSettings::MAP };
    vec![
        Method { name: "paper, N = 1", settings: paper(1) },
        Method { name: "paper, N = 3", settings: paper(3) },
        Method { name: "paper, N = 5", settings: paper(5) },
        Method { name: "paper, N = 10", settings: paper(10) },
        Method { name: "EDT", settings: paper(0) },
        Method { name: "EDT + depth-aware", settings: ShadowSettings { depth_aware: true, ..paper(0) } },
        Method {
            name: "EDT + depth-aware, matched points",
            settings: ShadowSettings { penumbra: PenumbraFalloff::Linear, ..soft },
        },
        Method { name: "same + disc falloff (default)", settings: soft },
        Method { name: "same at half resolution", settings: ShadowSettings { half: true, ..soft } },
        Method { name: "same, on SLB hard shadows", settings: ShadowSettings { hard: HardShadows::Slb, ..soft } },
        Method { name: "ring of four points", settings: ShadowSettings { points: PenumbraPoints::Ring, ..soft } },
        Method { name: "PCSS 16/16", settings: pcss(16, 16) },
        Method { name: "PCSS 32/64", settings: pcss(32, 64) },
        Method { name: "jittered light, 16", settings: jittered(16) },
        Method { name: "jittered light, 64", settings: jittered(64) },
    ]
}

/// A sphere of radius 0.5 centred `height` over a floor, under a light of
/// radius 0.3 five units up.
fn sphere_over_plane(height: f32) -> Result<Scene> {
    parse(&format!(
        r#"
[camera]
eye = [0.0, 4.5, 6.0]
target = [0.0, 0.6, 0.0]
fov = 40
[[light]]
type = "point"
position = [0.8, 5.0, 0.4]
intensity = 0.9
ambient = 0.1
size = 0.3
[[object]]
shape = "plane"
scale = 20.0
[[object]]
shape = "sphere"
translate = [0.0, {height}, 0.0]
scale = 0.5
"#
    ))
}

/// Scenes that show the two-map method's defects, under a light of radius
/// 0.3 five units up: a rod thinner than its penumbra is wide (its two hard
/// shadows do not overlap: a double shadow), and two crossed grilles of
/// slats at two heights (one slat's shadow from one point overlaps another
/// slat's from the other: false umbra).
fn defect_scenes() -> Result<Vec<(String, Scene)>> {
    let head = r#"
[camera]
eye = [0.0, 5.0, 4.0]
target = [0.0, 0.0, 0.0]
fov = 40
[[light]]
type = "point"
position = [0.3, 5.0, 0.2]
intensity = 0.9
ambient = 0.1
size = 0.3
[[object]]
shape = "plane"
scale = 20.0
"#;
    let cube = |scale: [f32; 3], at: [f32; 3], turn: f32| {
        format!("[[object]]\nshape = \"cube\"\nscale = {scale:?}\ntranslate = {at:?}\nrotate = [0.0, {turn}, 0.0]\n")
    };
    let rod = format!("{head}{}", cube([3.0, 0.04, 0.04], [0.0, 1.5, 0.0], 30.0));
    let mut grilles = head.to_string();
    for k in -3..=3 {
        let x = k as f32 * 0.3;
        grilles += &cube([0.1, 0.05, 2.4], [x, 1.0, 0.0], 0.0);
        grilles += &cube([2.4, 0.05, 0.1], [0.0, 2.0, x + 0.12], 0.0);
    }
    Ok(vec![("thin rod".to_string(), parse(&rod)?), ("two grilles".to_string(), parse(&grilles)?)])
}

/// The Cornell box of the shared assets, a light of radius 0.2 under its
/// ceiling lamp (far enough below the ceiling that its disc, turned to face
/// each point, stays in the room), seen through its open side.
fn cornell_box(assets: &Path) -> Result<Scene> {
    let mesh = assets.join("scenes/cornell-box/CornellBox-Original.obj");
    parse(&format!(
        r#"
[camera]
eye = [0.0, 1.0, 3.4]
target = [0.0, 1.0, 0.0]
fov = 40
[[light]]
type = "point"
position = [0.0, 1.7, -0.03]
intensity = 0.8
ambient = 0.15
size = 0.2
[[object]]
mesh = "{}"
"#,
        mesh.display()
    ))
}

fn parse(text: &str) -> Result<Scene> {
    let file = SceneFile::parse(text, Path::new("bench.toml")).map_err(|e| miette!("{e}"))?;
    file.build(&FileSystem { base: ".".into() }).map_err(|e| miette!("{e}"))
}

/// The scenes, each with one shadowed light with a size (its key light;
/// the other lights unshadowed).
fn scenes(c: &Common) -> Result<Vec<(String, Scene)>> {
    let mut out = Vec::new();
    for height in [0.6, 1.5, 3.0] {
        out.push((format!("sphere over a plane, h = {height}"), sphere_over_plane(height)?));
    }
    let assets = c.assets();
    for model in ["meshes/stanford-bunny/stanford-bunny.obj", "csg/mk3_x_end.csg"] {
        let path = assets.join(model);
        if path.exists() {
            let scene = kage::scene::model::scene_for_model(&path, 512, 512).map_err(|e| miette!("{e}"))?;
            let name = path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            out.push((name, scene));
        } else {
            eprintln!("skipped {} (not found)", path.display());
        }
    }
    if assets.join("scenes/cornell-box").exists() {
        out.push(("Cornell box".to_string(), cornell_box(&assets)?));
    }
    out.push(("demo".to_string(), kage::scene::demo::demo_scene().map_err(|e| miette!("{e}"))?));
    for (_, scene) in &mut out {
        let key = key_light(scene).ok_or_else(|| miette!("a scene without a point or spot light"))?;
        for (i, light) in scene.lights.iter_mut().enumerate() {
            if i != key {
                light.shadow.method = ShadowMethod::None;
            }
        }
    }
    Ok(out)
}

/// The first shadowed point or spot light with a size.
fn key_light(scene: &Scene) -> Option<usize> {
    scene.lights.iter().position(|l| {
        matches!(l.kind, LightKind::Point { .. } | LightKind::Spot { .. })
            && l.size > 0.0
            && l.shadow.method != ShadowMethod::None
    })
}

/// `scene` at `size` with its key light's shadows by `settings`.
fn with(scene: &Scene, settings: &ShadowSettings, (w, h): (u32, u32)) -> Scene {
    let mut s = scene.clone();
    (s.width, s.height) = (w, h);
    let key = key_light(scene).expect("scenes have a key light");
    s.lights[key].shadow = *settings;
    s
}

/// The key light's shadow term per pixel (`None` where no object is seen).
fn term(scene: &Scene) -> Result<(Vec<Option<f32>>, LinearImage)> {
    let options = RenderOptions { shadow_images: true, ..RenderOptions::default() };
    let frame = kage::render(scene, &options).map_err(|e| miette!("{e}"))?;
    let key = key_light(scene).expect("scenes have a key light");
    let items = frame.visibility.items();
    let term = frame.shadows[key].pixels().iter().zip(items).map(|(p, i)| (!i.is_none()).then_some(p.x)).collect();
    Ok((term, frame.shadows[key].clone()))
}

/// RMSE and largest error of `term` against `truth` over the pixels both
/// have where `keep` holds.
fn errors(term: &[Option<f32>], truth: &[Option<f32>], keep: impl Fn(f32) -> bool) -> (f64, f64) {
    let (mut sum, mut most, mut n) = (0.0f64, 0.0f64, 0usize);
    for (t, r) in term.iter().zip(truth) {
        if let (Some(t), Some(r)) = (t, r) {
            if keep(*r) {
                let d = f64::from(t - r).abs();
                (sum, most, n) = (sum + d * d, most.max(d), n + 1);
            }
        }
    }
    ((sum / n.max(1) as f64).sqrt(), most)
}

/// Prints the table (or, with `--defects`, the defects' table).
///
/// # Errors
///
/// When a scene does not load or render.
pub fn run(args: &SoftArgs) -> Result<()> {
    let c = &args.common;
    let check = (args.check, args.check);
    let extra = if args.defects { " false umbra | false lit |" } else { "" };
    println!(
        "| scene | method | penumbra RMSE | penumbra max | image RMSE | image max |{extra} ms {0}² | ms {1}×{2} | of \
         which shadows | shadows serial |",
        args.check, c.width, c.height
    );
    println!("|---|---|---:|---:|---:|---:|{}---:|---:|---:|---:|", if args.defects { "---:|---:|" } else { "" });
    let (scenes, methods) = if args.defects { (defect_scenes()?, defect_methods()) } else { (scenes(c)?, methods()) };
    for (name, scene) in scenes {
        if args.only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let truth = truth(&scene, check.0, args.truth_rays)?;
        let mut crops = vec![("truth".to_string(), truth_image(&truth, args.check))];
        for method in &methods {
            if args.method.as_ref().is_some_and(|m| !method.name.contains(m.as_str())) {
                continue;
            }
            let (term, image) = term(&with(&scene, &method.settings, check))?;
            let (p_rmse, p_max) = errors(&term, &truth, |t| t > 0.0 && t < 1.0);
            let (i_rmse, i_max) = errors(&term, &truth, |_| true);
            let defects = if args.defects {
                let share = |wrong: &dyn Fn(f32, f32) -> bool| {
                    let seen = term.iter().zip(&truth).filter_map(|(t, r)| t.zip(*r));
                    let (bad, all) = seen.fold((0, 0), |(b, a), (t, r)| (b + usize::from(wrong(t, r)), a + 1));
                    100.0 * bad as f64 / all.max(1) as f64
                };
                let umbra = share(&|t, r| t <= 0.05 && r >= 0.25);
                let lit = share(&|t, r| t >= 0.95 && r <= 0.75);
                format!(" {umbra:.2}% | {lit:.2}% |")
            } else {
                String::new()
            };
            let small = frame_times(&with(&scene, &method.settings, check), c.frames)?.frame;
            let large = frame_times(&with(&scene, &method.settings, (c.width, c.height)), c.frames)?;
            println!(
                "| {name} | {} | {p_rmse:.4} | {p_max:.3} | {i_rmse:.4} | {i_max:.3} |{defects} {small:.1} | \
                 {:.1} | {:.1} | {:.0}% |",
                method.name,
                large.frame,
                large.shadows,
                100.0 * large.shadow_serial
            );
            crops.push((method.name.to_string(), image));
        }
        if let Some(dir) = &args.crops {
            write_crops(dir, &name, &crops, &truth, check.0)?;
        }
    }
    println!(
        "\nThe key light's shadow term (the scene's first point light with a size; the other lights unshadowed) \
         against {0} × {0} stratified, jittered shadow rays over its disc at each pixel centre, at {1}²: RMSE and \
         largest error over the penumbra (truth strictly between 0 and 1) and over every pixel showing an object, \
         surfaces the light grazes (N·L ≤ 0.1) left out.{5} \
         Frame times (every map rendered again each frame; the default edge pass) at {1}² and {2}×{3}, and the \
         shadow stage's share (maps and the per-pixel soft term), median of {4} frames after a warm-up; 2 threads. \
         Shadows serial: the share of the shadow stage's wall time at {2}×{3} during which a worker had no work \
         (`kage::idle`).",
        args.truth_rays,
        args.check,
        c.width,
        c.height,
        c.frames,
        if args.defects {
            " False umbra: the share of those pixels a method calls dark (≤ 0.05) where the truth is at least a \
             quarter lit; false lit: called lit (≥ 0.95) where the truth is at most three quarters lit."
        } else {
            ""
        }
    );
    Ok(())
}

/// The key light's visibility by rays over its disc at every pixel of
/// `scene` at `side`², `None` where no object is seen or the light grazes
/// the surface.
fn truth(scene: &Scene, side: u32, rays: u32) -> Result<Vec<Option<f32>>> {
    let base = with(scene, &ShadowSettings::MAP, (side, side));
    let frame = kage::render(&base, &RenderOptions::default()).map_err(|e| miette!("{e}"))?;
    let key = key_light(&base).expect("scenes have a key light");
    let mut truth = ShadowRays::new(&base).area_visibility(&frame.visibility, key, rays);
    // Surfaces the light grazes (N·L ≤ 0.1 at the centre) are left out:
    // there a mesh's shading normal and its facets disagree on what the
    // light reaches, for every method alike.
    let surfaces = kage::shading::screen_surfaces(&base, &frame.visibility);
    for (t, s) in truth.iter_mut().zip(&surfaces.all()) {
        if s.is_some_and(|s| s.normal.dot(base.lights[key].incident(s.position).to_light) <= 0.1) {
            *t = None;
        }
    }
    Ok(truth)
}

/// The truth as a grey image (1 where no object is seen).
fn truth_image(truth: &[Option<f32>], side: u32) -> LinearImage {
    let mut image = LinearImage::new(side, side);
    for (p, t) in image.pixels_mut().iter_mut().zip(truth) {
        *p = glam::Vec3::splat(t.unwrap_or(1.0));
    }
    image
}

/// Writes `dir/<scene>.png`: a 128 × 128 window round the penumbra's middle
/// from each image (the truth first), side by side, twice enlarged.
fn write_crops(
    dir: &Path,
    scene: &str,
    images: &[(String, LinearImage)],
    truth: &[Option<f32>],
    side: u32,
) -> Result<()> {
    const W: u32 = 128;
    let penumbra: Vec<u32> =
        (0..truth.len() as u32).filter(|&i| truth[i as usize].is_some_and(|t| t > 0.0 && t < 1.0)).collect();
    let Some(&middle) = penumbra.get(penumbra.len() / 2) else { return Ok(()) };
    let (cx, cy) = ((middle % side).clamp(W / 2, side - W / 2), (middle / side).clamp(W / 2, side - W / 2));
    let mut out = image::RgbImage::new(2 * W * images.len() as u32, 2 * W);
    for (k, (_, img)) in images.iter().enumerate() {
        for y in 0..2 * W {
            for x in 0..2 * W {
                let v = img.pixels()[((cy - W / 2 + y / 2) * side + cx - W / 2 + x / 2) as usize].x;
                let g = (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8;
                out.put_pixel(k as u32 * 2 * W + x, y, image::Rgb([g, g, g]));
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| miette!("{}: {e}", dir.display()))?;
    let file = dir.join(format!("{}.png", scene.replace([' ', ',', '=', '.'], "_")));
    out.save(&file).map_err(|e| miette!("{}: {e}", file.display()))?;
    eprintln!("wrote {} ({})", file.display(), images.iter().map(|(n, _)| n.as_str()).collect::<Vec<_>>().join(" | "));
    Ok(())
}
