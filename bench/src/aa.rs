//! `kage bench --aa`: seed 004's edge pass and jittered passes against a 16 × 16
//! supersampled truth (256 jittered passes), on the example scenes and two real
//! models: RMSE on edge pixels (those an object's outline crosses) and over the
//! image, and ms per frame. A second table puts the same scenes under point
//! lights with silhouette-line-buffer shadows (seed 000), 0/1 and antialiased,
//! beside the edge pass: what the shadow term's own antialiasing adds where
//! the edge pass cannot reach (shadow boundaries).

use std::path::Path;

use glam::Vec2;
use kage::image::LinearImage;
use kage::raytrace::shadow_truth;
use kage::scene::{Antialias, EdgeFilter, EdgeMode, EdgeSelection, ShadowSettings};
use kage::visibility::VisibilityBuffer;
use kage::{RenderOptions, Renderer, Scene};
use miette::{miette, Result};

use crate::{repository, Common};

/// Options of `kage-bench aa`.
#[derive(clap::Args, Debug)]
pub struct AaArgs {
    #[command(flatten)]
    common: Common,
    /// Also write side-by-side crops (aliased | edge pass | truth) here.
    #[arg(long)]
    crops: Option<std::path::PathBuf>,
}

fn edge(selection: EdgeSelection, filter: EdgeFilter) -> Antialias {
    Antialias::Edge(EdgeMode { selection, filter })
}

/// Passes of the truth: 16 × 16 samples per pixel.
const TRUTH_PASSES: u32 = 256;

/// The scenes measured: every example scene that has silhouettes to speak of, and
/// two models from `../shared/assets` when that folder is there.
fn scenes(args: &Common) -> Result<Vec<(String, Scene)>> {
    let dir = repository().join("examples/scenes");
    let mut out = Vec::new();
    for name in ["demo", "spotlights", "cad-ortho", "showroom", "reflections"] {
        let scene = kage::scene::file::load_scene(&dir.join(format!("{name}.toml"))).map_err(|e| miette!("{e}"))?;
        out.push((format!("{name}.toml"), scene));
    }
    let assets = args.assets();
    for model in ["meshes/stanford-bunny/stanford-bunny.obj", "gltf/CesiumMilkTruck/CesiumMilkTruck.glb"] {
        let path = assets.join(model);
        if path.exists() {
            let scene =
                kage::scene::model::scene_for_model(&path, args.width, args.height).map_err(|e| miette!("{e}"))?;
            out.push((model.rsplit('/').next().unwrap_or(model).to_string(), scene));
        } else {
            eprintln!("skipped {} (not found)", path.display());
        }
    }
    for (_, s) in &mut out {
        (s.width, s.height) = (args.width, args.height);
    }
    Ok(out)
}

/// Runs the table.
pub fn run(aa: &AaArgs) -> Result<()> {
    let args = &aa.common;
    println!(
        "| scene | method | ms/frame | of which edge pass | x aliased | edge-pixel RMSE | share of aliased removed | \
         same, 3 x 3 mask | image RMSE |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|");
    for (label, scene) in scenes(args)? {
        let truth = frame(&scene, Antialias::Jitter(TRUTH_PASSES), 1)?.0;
        let (aliased, (aliased_ms, _, _), vb) = frame(&scene, Antialias::None, args.frames)?;
        let (mask, near) = (crossed(&scene), silhouettes(&vb));
        let (base, base_near) = (rmse(&aliased, &truth, Some(&mask)), rmse(&aliased, &truth, Some(&near)));
        let methods = [
            ("aliased", Antialias::None),
            ("edge pass, the paper (all edges, Wu weights)", edge(EdgeSelection::All, EdgeFilter::Paper)),
            ("edge pass, all edges, coverage", edge(EdgeSelection::All, EdgeFilter::Coverage)),
            ("edge pass, outline, coverage (default)", edge(EdgeSelection::Outline, EdgeFilter::Coverage)),
            ("jitter 4", Antialias::Jitter(4)),
            ("jitter 16", Antialias::Jitter(16)),
        ];
        let mut edged = None;
        for (name, aa) in methods {
            let (image, (ms, edge_ms, ratio), _) = if aa == Antialias::None {
                (aliased.clone(), (aliased_ms, 0.0, 1.0), vb.clone())
            } else {
                frame(&scene, aa, args.frames.min(if matches!(aa, Antialias::Jitter(_)) { 3 } else { args.frames }))?
            };
            let e = rmse(&image, &truth, Some(&mask));
            println!(
                "| {label} | {name} | {ms:.1} | {edge_ms:.1} | {ratio:.2} | {e:.4} | {:.0}% | {:.0}% | {:.4} |",
                100.0 * (1.0 - e / base),
                100.0 * (1.0 - rmse(&image, &truth, Some(&near)) / base_near),
                rmse(&image, &truth, None)
            );
            if aa == Antialias::Edge(EdgeMode::default()) {
                edged = Some(image);
            }
        }
        if let (Some(dir), Some(edged)) = (&aa.crops, edged) {
            write_crop(dir, &label, [&aliased, &edged, &truth], &mask, scene.width)?;
        }
    }
    print_footnote(args);
    slb_boundaries(args)
}

/// The first table's footnote.
fn print_footnote(args: &Common) {
    println!(
        "\n{}x{}, truth = {TRUTH_PASSES} jittered passes (16 x 16 per pixel); edge pixels = pixels an object's \
         outline crosses (their truth samples see more than one object, or an object and the background); 3 x 3 \
         mask = pixels whose 3 x 3 neighbourhood in the aliased visibility buffer holds more than one object, which \
         adds the pixels beside an outline (their error is shading: shadows, reflections); median of {} frames \
         (jittered rows: 3); x aliased = median over those frames of each frame's time over an aliased frame's \
         rendered just before it; 2 threads.",
        args.width, args.height, args.frames
    );
}

/// `scene` with every light a point (no size) and every shadowed light's
/// shadows by the silhouette-line buffer, its boundary antialiased or not.
fn with_slb(scene: &Scene, antialias: bool) -> Scene {
    let mut s = scene.clone();
    s.lights.iter_mut().for_each(|l| l.size = 0.0);
    let slb = ShadowSettings { antialias, ..ShadowSettings::SLB };
    s.lights.iter_mut().filter(|l| l.casts_shadows()).for_each(|l| l.shadow = slb);
    s
}

/// Pixels along a shadow boundary of any light in `scene`'s frame (its 0/1
/// terms change within the pixel's 3 × 3 neighbourhood, on one object).
fn shadow_boundaries(scene: &Scene) -> Result<Vec<bool>> {
    let options = RenderOptions { shadow_images: true, ..RenderOptions::default() };
    let f = kage::render(scene, &options).map_err(|e| miette!("{e}"))?;
    let mut mask = vec![false; (scene.width * scene.height) as usize];
    for term in &f.shadows {
        for (x, y, _) in shadow_truth::boundary_pixels(&f.visibility, term.pixels()) {
            mask[(y * scene.width + x) as usize] = true;
        }
    }
    Ok(mask)
}

/// The second table: the scenes under point lights with SLB shadows, the
/// default edge pass with the 0/1 and the antialiased term, against 256
/// jittered passes of the 0/1 term (exact hard shadows at every sample).
fn slb_boundaries(args: &Common) -> Result<()> {
    println!(
        "\n| scene | SLB shadows | ms/frame | edge-pixel RMSE | 3 x 3 mask RMSE | shadow-boundary RMSE | image RMSE |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|");
    for (label, scene) in scenes(args)? {
        let hard = with_slb(&scene, false);
        let truth = frame(&hard, Antialias::Jitter(TRUTH_PASSES), 1)?.0;
        let (_, _, vb) = frame(&hard, Antialias::None, 1)?;
        let masks = [crossed(&hard), silhouettes(&vb), shadow_boundaries(&hard)?];
        for (name, antialias) in [("0/1", false), ("antialiased", true)] {
            let (image, (ms, _, _), _) = frame(&with_slb(&scene, antialias), Antialias::default(), args.frames)?;
            let [edge, near, boundary] = masks.each_ref().map(|m| rmse(&image, &truth, Some(m)));
            println!(
                "| {label} | {name} | {ms:.1} | {edge:.4} | {near:.4} | {boundary:.4} | {:.4} |",
                rmse(&image, &truth, None)
            );
        }
    }
    println!(
        "\n{}x{}, every light a point with SLB shadows (1024², k = 8), the default edge pass; truth = \
         {TRUTH_PASSES} jittered passes with the 0/1 SLB term (hard shadows decided at every sample); shadow-boundary \
         pixels = pixels whose 3 x 3 neighbourhood's 0/1 terms differ, on one object; median of {} frames; 2 threads.",
        args.width, args.height, args.frames
    );
    Ok(())
}

/// The frame of `scene` antialiased by `aa`: image, median ms per frame and of its
/// edge pass over `frames` renders (after one warm-up, which builds the meshes'
/// edge lists), the median ratio of each render's time to an aliased render's
/// just before it (interleaved, so both meet the same load on a shared
/// machine), and the visibility buffer.
fn frame(scene: &Scene, aa: Antialias, frames: usize) -> Result<(LinearImage, (f64, f64, f64), VisibilityBuffer)> {
    let (scene, aliased) =
        (Scene { antialias: aa, ..scene.clone() }, Scene { antialias: Antialias::None, ..scene.clone() });
    let new = || Renderer::new(&RenderOptions::default()).map_err(|e| miette!("{e}"));
    let (mut renderer, mut reference) = (new()?, new()?);
    renderer.render(&scene).map_err(|e| miette!("{e}"))?;
    reference.render(&aliased).map_err(|e| miette!("{e}"))?;
    let (mut times, mut edge, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..frames.max(1) {
        let t = std::time::Instant::now();
        reference.render(&aliased).map_err(|e| miette!("{e}"))?;
        let aliased_ms = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        edge.push(renderer.render(&scene).map_err(|e| miette!("{e}"))?.stats.edge_ms);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        ratios.push(times[times.len() - 1] / aliased_ms);
    }
    let median = |mut v: Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let f = renderer.into_frame();
    Ok((f.image, (median(times), median(edge), median(ratios)), f.visibility))
}

/// Pixels an object's outline crosses: at the truth's sample positions the pixel
/// sees more than one object, or an object and the background.
fn crossed(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.width, scene.height);
    let pixel = 2.0 / Vec2::new(w as f32, h as f32);
    let (mut vb, mut shifted) = (VisibilityBuffer::new(w, h), scene.clone());
    let mut first: Option<Vec<u32>> = None;
    let mut crossed = vec![false; w as usize * h as usize];
    for o in Antialias::Jitter(TRUTH_PASSES).offsets() {
        // As the jittered passes shift the camera (pixel offsets y down, NDC y up).
        shifted.camera.shift = scene.camera.shift + Vec2::new(o.x, -o.y) * pixel;
        kage::visibility::rasterize(&shifted, &mut vb);
        let objects = vb.items().iter().map(|i| i.object);
        match &first {
            None => first = Some(objects.collect()),
            Some(f) => crossed.iter_mut().zip(objects.zip(f)).for_each(|(c, (o, f))| *c |= o != *f),
        }
    }
    crossed
}

/// Pixels whose 3 × 3 neighbourhood sees more than one object (or the background).
fn silhouettes(vb: &VisibilityBuffer) -> Vec<bool> {
    let (w, h) = (vb.width() as i64, vb.height() as i64);
    let object = |x: i64, y: i64| vb.item(x.clamp(0, w - 1) as u32, y.clamp(0, h - 1) as u32).object;
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| {
            let o = object(x, y);
            !(-1..=1).all(|dy| (-1..=1).all(|dx| object(x + dx, y + dy) == o))
        })
        .collect()
}

/// RMSE between `a` and `b` (linear RGB), over the pixels `mask` keeps (all if none).
fn rmse(a: &LinearImage, b: &LinearImage, mask: Option<&[bool]>) -> f64 {
    let (mut sum, mut n) = (0.0f64, 0usize);
    for (i, (p, q)) in a.pixels().iter().zip(b.pixels()).enumerate() {
        if mask.is_none_or(|m| m[i]) {
            sum += f64::from((*p - *q).length_squared()) / 3.0;
            n += 1;
        }
    }
    (sum / n.max(1) as f64).sqrt()
}

/// Writes `dir/<label>.png`: the same window of the aliased frame, the edge pass
/// and the truth side by side, four times enlarged, around the middle of the
/// silhouettes.
fn write_crop(dir: &Path, label: &str, images: [&LinearImage; 3], mask: &[bool], width: u32) -> Result<()> {
    const W: u32 = 80;
    const H: u32 = 60;
    const ZOOM: u32 = 4;
    let (w, h) = (images[0].width(), images[0].height());
    let on: Vec<(u32, u32)> =
        mask.iter().enumerate().filter(|(_, &m)| m).map(|(i, _)| (i as u32 % width, i as u32 / width)).collect();
    let Some(&(cx, cy)) = on.get(on.len() / 2) else { return Ok(()) };
    let (x0, y0) =
        (cx.saturating_sub(W / 2).min(w.saturating_sub(W)), cy.saturating_sub(H / 2).min(h.saturating_sub(H)));
    let gap = 4;
    let mut out = image::RgbImage::from_pixel(3 * W * ZOOM + 2 * gap, H * ZOOM, image::Rgb([255, 255, 255]));
    for (k, img) in images.iter().enumerate() {
        let srgb = img.to_srgb8(1.0);
        for y in 0..(H * ZOOM).min(h * ZOOM) {
            for x in 0..(W * ZOOM).min(w * ZOOM) {
                let (sx, sy) = (x0 + x / ZOOM, y0 + y / ZOOM);
                let i = 3 * (sy * w + sx) as usize;
                out.put_pixel(k as u32 * (W * ZOOM + gap) + x, y, image::Rgb([srgb[i], srgb[i + 1], srgb[i + 2]]));
            }
        }
    }
    std::fs::create_dir_all(dir).map_err(|e| miette!("{}: {e}", dir.display()))?;
    let path = dir.join(format!("aa-{}.png", label.trim_end_matches(".toml").replace(['.', ' '], "-")));
    out.save(&path).map_err(|e| miette!("{}: {e}", path.display()))?;
    eprintln!("wrote {} (aliased | edge pass | {TRUTH_PASSES}-pass truth)", path.display());
    Ok(())
}
