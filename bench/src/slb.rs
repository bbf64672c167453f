//! `kage-bench slb`: the silhouette-line buffer (seed 000) beside shadow maps
//! from 512² to 16K² and 3 × 3 PCF, on the same scenes, against shadow rays:
//! misclassified visible points, the RMSE of the term along shadow
//! boundaries against 16 × 16 shadow rays per pixel, the bytes the method
//! holds (and the SLB's lines, as the paper's Table 8), and the light pass,
//! eye pass and whole frame at the timing size. Every frame renders its maps
//! again, as a one-shot render does.

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::raytrace::shadow_truth::{self, ShadowRays};
use kage::scene::mesh::shapes;
use kage::scene::{Light, LightKind, Material, Object, ShadowSettings};
use kage::shadows::{ShadowTerm, SlbTerm};
use kage::{RenderOptions, Scene};
use miette::{miette, Result};

use crate::{frame_times, repository, Common};

/// Options of `kage-bench slb`.
#[derive(clap::Args, Debug)]
pub struct SlbArgs {
    #[command(flatten)]
    common: Common,
    /// Width of the image the errors are measured on (the timing size is
    /// `--width` × `--height`).
    #[arg(long, default_value_t = 640)]
    check_width: u32,
    /// Height of the image the errors are measured on.
    #[arg(long, default_value_t = 360)]
    check_height: u32,
    /// Only the scenes whose name contains this.
    #[arg(long)]
    only: Option<String>,
    /// Only these methods, by their names in the table (repeatable; e.g.
    /// `--method "map 2048²" --method "SLB 1024², k = 8"`).
    #[arg(long = "method")]
    methods: Vec<String>,
}

/// One column of the comparison: a method and its settings.
struct Method {
    name: String,
    settings: ShadowSettings,
}

/// Maps 512² … 16K², 3 × 3 PCF on 2K², the SLB 1K² at k = 4 / 8 / 16 and, at
/// k = 8, scales 4 / 16 / 64 / 256 / 1024 (the paper's Fig. 8 and 9 go to 1024).
fn methods() -> Vec<Method> {
    let map = |resolution: u32, pcf: u32| ShadowSettings { resolution, by_need: false, pcf, ..ShadowSettings::MAP };
    let mut out: Vec<Method> = [512, 1024, 2048, 4096, 8192, 16384]
        .into_iter()
        .map(|r| Method { name: format!("map {r}²"), settings: map(r, 1) })
        .collect();
    out.push(Method { name: "map 2048², PCF 3×3".into(), settings: map(2048, 3) });
    for bits in [4, 8, 16] {
        out.push(Method {
            name: format!("SLB 1024², k = {bits}"),
            settings: ShadowSettings { bits, ..ShadowSettings::SLB },
        });
    }
    for scale in [4.0, 16.0, 64.0, 256.0, 1024.0] {
        let settings = ShadowSettings { scale, ..ShadowSettings::SLB };
        out.push(Method { name: format!("SLB 1024², k = 8, scale {scale}"), settings });
    }
    out
}

/// A `side`-wide floor seen from `eye` looking at `target` (45°, far plane
/// `far`), its material the default.
fn over_a_floor(eye: Vec3, target: Vec3, far: f32, side: f32) -> Scene {
    let projection = Projection::Perspective { fov_y_deg: 45.0 };
    let camera = Camera { eye, target, up: Vec3::Y, near: 0.1, far, projection, shift: Vec2::ZERO };
    let mut scene = Scene::new(640, 360, camera);
    scene.materials.push(Material::default());
    let plane = Arc::new(shapes::plane());
    scene.objects.push(Object::mesh("floor", plane, Affine3A::from_scale(Vec3::splat(side)), 0));
    scene
}

/// Cubes on a floor in a 7 × 7 grid under a sun 12° above the horizon.
fn grid_of_boxes() -> Scene {
    let mut scene = over_a_floor(Vec3::new(0.0, 9.0, 13.0), Vec3::new(0.0, 0.0, 0.5), 80.0, 40.0);
    let cube = Arc::new(shapes::cube());
    for i in 0..7 {
        for j in 0..7 {
            let at = Vec3::new(-6.0 + 2.0 * i as f32, 0.4, -6.0 + 2.0 * j as f32);
            let turn = glam::Quat::from_rotation_y(0.3 * (i * 7 + j) as f32);
            let transform = Affine3A::from_scale_rotation_translation(Vec3::splat(0.8), turn, at);
            scene.objects.push(Object::mesh(format!("box {i},{j}"), cube.clone(), transform, 0));
        }
    }
    let elevation = 12f32.to_radians();
    let direction = -Vec3::new(elevation.cos() * 0.8, elevation.sin(), elevation.cos() * 0.6).normalize();
    scene.lights.push(Light { kind: LightKind::Directional { direction }, ambient: 0.2, ..Light::default() });
    scene
}

/// A tilted torus over a floor under a spot light: its hole lets light through
/// and its ring shadows itself.
fn torus_scene() -> Scene {
    let mut scene = over_a_floor(Vec3::new(0.0, 3.5, 4.5), Vec3::new(0.0, 0.5, 0.0), 50.0, 20.0);
    let turn = glam::Quat::from_rotation_x(0.6) * glam::Quat::from_rotation_z(0.3);
    let transform = Affine3A::from_rotation_translation(turn, Vec3::new(0.0, 1.1, 0.0));
    scene.objects.push(Object::mesh("torus", Arc::new(shapes::torus(96, 48, 0.35)), transform, 0));
    let position = Vec3::new(-2.5, 5.0, 1.5);
    let kind = LightKind::Spot {
        position,
        direction: (Vec3::new(0.0, 0.5, 0.0) - position).normalize(),
        inner: 0.5,
        outer: 0.6,
    };
    scene.lights.push(Light { kind, ambient: 0.2, ..Light::default() });
    scene
}

/// Scanned and CAD meshes side by side on a wide floor under a sun 15° above
/// the horizon: the Stanford bunny, dragon and armadillo and OpenSCAD's
/// printer part, each scaled to stand 1.5 units tall (`None` when one is not
/// among the assets).
fn scanned_and_cad(assets: &std::path::Path) -> Result<Option<Scene>> {
    let models = [
        "meshes/stanford-bunny/stanford-bunny.obj",
        "meshes/dragon/dragon.obj",
        "meshes/armadillo/armadillo.obj",
        "csg/mk3_x_end.csg",
    ];
    let mut scene = over_a_floor(Vec3::new(0.0, 5.0, 10.0), Vec3::new(0.0, 0.5, 0.0), 80.0, 40.0);
    for (k, model) in models.iter().enumerate() {
        let path = assets.join(model);
        if !path.exists() {
            eprintln!("skipped the scanned and CAD scene: {} not found", path.display());
            return Ok(None);
        }
        let one = kage::scene::model::scene_for_model(&path, 640, 360).map_err(|e| miette!("{e}"))?;
        let objects: Vec<Object> = one.objects.into_iter().filter(|o| o.name != "ground").collect();
        let bounds = objects.iter().filter_map(Object::world_bounds).reduce(|(a, b), (c, d)| (a.min(c), b.max(d)));
        let Some((lo, hi)) = bounds else { continue };
        let scale = 1.5 / (hi.y - lo.y).max(1e-6);
        let at = Vec3::new(-4.5 + 3.0 * k as f32, 0.0, 0.0);
        let centre = Vec3::new((lo.x + hi.x) * 0.5, lo.y, (lo.z + hi.z) * 0.5);
        let place = Affine3A::from_translation(at)
            * Affine3A::from_scale(Vec3::splat(scale))
            * Affine3A::from_translation(-centre);
        let offset = scene.materials.len();
        scene.materials.extend(one.materials);
        scene.objects.extend(objects.into_iter().map(|o| Object {
            transform: place * o.transform,
            material: o.material + offset,
            ..o
        }));
    }
    let elevation = 15f32.to_radians();
    let direction = -Vec3::new(elevation.cos() * 0.6, elevation.sin(), elevation.cos() * 0.8).normalize();
    scene.lights.push(Light { kind: LightKind::Directional { direction }, ambient: 0.2, ..Light::default() });
    Ok(Some(scene))
}

/// The scenes: the demo, the heat sink, atrium and CSG examples, a torus, a grid of boxes under
/// grazing light, and the Stanford bunny and dragon and a CAD part from OpenSCAD, and all
/// three with the armadillo on one floor under a low sun, when the shared assets are there.
fn scenes(c: &Common) -> Result<Vec<(String, Scene)>> {
    let mut out = Vec::new();
    let demo = kage::scene::demo::demo_scene().map_err(|e| miette!("{e}"))?;
    out.push(("demo".to_string(), demo));
    let dir = repository().join("examples/scenes");
    for name in ["heatsink", "atrium", "csg"] {
        let scene = kage::scene::file::load_scene(&dir.join(format!("{name}.toml"))).map_err(|e| miette!("{e}"))?;
        out.push((format!("{name}.toml"), scene));
    }
    out.push(("torus over a floor".to_string(), torus_scene()));
    out.push(("grid of boxes, sun at 12°".to_string(), grid_of_boxes()));
    for model in ["meshes/stanford-bunny/stanford-bunny.obj", "meshes/dragon/dragon.obj", "csg/mk3_x_end.csg"] {
        let path = c.assets().join(model);
        if path.exists() {
            let scene = kage::scene::model::scene_for_model(&path, 640, 360).map_err(|e| miette!("{e}"))?;
            let name = path.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
            out.push((name, scene));
        } else {
            eprintln!("skipped {} (not found)", path.display());
        }
    }
    if let Some(scene) = scanned_and_cad(&c.assets())? {
        out.push(("scanned and CAD, sun at 15°".to_string(), scene));
    }
    Ok(out)
}

/// `scene` at `size` with every light a point (no `size`: the truth is hard
/// shadows) and every shadowed light's shadows as `settings` say.
fn with(scene: &Scene, settings: &ShadowSettings, (w, h): (u32, u32)) -> Scene {
    let mut s = scene.clone();
    (s.width, s.height) = (w, h);
    s.lights.iter_mut().for_each(|l| l.size = 0.0);
    s.lights.iter_mut().filter(|l| l.casts_shadows()).for_each(|l| l.shadow = *settings);
    s
}

/// What the errors are measured against, for one scene at the check size:
/// its shadow rays, and per light the boundary pixels and their 16 × 16-ray
/// coverage.
struct Truth<'a> {
    rays: ShadowRays<'a>,
    boundaries: Vec<Boundary>,
}

/// One light's boundary pixels (x, y, object) and their rays' coverage.
struct Boundary {
    pixels: Vec<(u32, u32, u32)>,
    covered: Vec<Option<f32>>,
}

/// The truth of `scene`: boundary pixels where shadow rays through the pixel
/// centres change within a 3 × 3 neighbourhood.
fn truth(scene: &Scene) -> Result<Truth<'_>> {
    let frame = kage::render(scene, &RenderOptions::default()).map_err(|e| miette!("{e}"))?;
    let rays = ShadowRays::new(scene);
    let vb = &frame.visibility;
    let w = scene.width;
    let mut boundaries = Vec::new();
    for light in 0..scene.lights.len() {
        let mut image = vec![Vec3::ONE; (w * scene.height) as usize];
        let lit = std::sync::Mutex::new(&mut image);
        rays.misclassified(vb, |l, q| {
            if l == light {
                let v = if rays.reaches(q.surface, &scene.lights[light]) { 1.0 } else { 0.0 };
                lit.lock().expect("one writer at a time")[(q.pixel.1 * w + q.pixel.0) as usize] = Vec3::splat(v);
            }
            None
        });
        let pixels = shadow_truth::boundary_pixels(vb, &image);
        let covered = rays.covered_share(light, &pixels, 16);
        boundaries.push(Boundary { pixels, covered });
    }
    Ok(Truth { rays, boundaries })
}

/// Misclassified share of visible points, and the boundary RMSE over the
/// shadowed lights, of `scene` (shadows as its lights say) against `truth`.
fn errors(scene: &Scene, truth: &Truth) -> Result<(f64, f64)> {
    let options = RenderOptions { shadow_images: true, ..RenderOptions::default() };
    let frame = kage::render(scene, &options).map_err(|e| miette!("{e}"))?;
    let terms = ShadowTerm::build_all(scene);
    let (wrong, total) = truth.rays.misclassified(&frame.visibility, |light, q| {
        let receiver = q.receiver();
        terms[light].casts().then(|| terms[light].lit(q.surface.position, q.cos_theta, &receiver))
    });
    let (mut sum, mut n) = (0.0, 0);
    let shadowed = scene.lights.iter().map(kage::scene::Light::casts_shadows);
    let measured = frame.shadows.iter().zip(&truth.boundaries).zip(shadowed).filter(|(_, s)| *s);
    for ((image, boundary), _) in measured {
        let (rmse, k) = shadow_truth::rmse_at(image.pixels(), scene.width, &boundary.pixels, &boundary.covered);
        (sum, n) = (sum + rmse * rmse * k as f64, n + k);
    }
    Ok((wrong as f64 / total.max(1) as f64, (sum / n.max(1) as f64).sqrt()))
}

/// Bytes of `scene`'s shadow terms and the SLB lines they hold.
fn footprint(scene: &Scene) -> (usize, usize) {
    let terms = ShadowTerm::build_all(scene);
    let lines = terms
        .iter()
        .filter_map(|t| t.downcast_ref::<SlbTerm>())
        .flat_map(|t| t.maps().iter().map(|m| m.buffer().line_count()))
        .sum();
    (terms.iter().map(ShadowTerm::memory_bytes).sum(), lines)
}

/// Prints the table.
///
/// # Errors
///
/// When a scene does not load or render.
pub fn run(args: &SlbArgs) -> Result<()> {
    let c = &args.common;
    let check = (args.check_width, args.check_height);
    println!(
        "| scene | method | misclassified | boundary RMSE | bytes | SLB lines | light ms | eye ms | frame ms | shadows serial |"
    );
    println!("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");
    for (name, scene) in scenes(c)? {
        if args.only.as_ref().is_some_and(|o| !name.contains(o.as_str())) {
            continue;
        }
        let base = with(&scene, &ShadowSettings::MAP, check);
        let truth = truth(&base)?;
        let chosen = methods().into_iter().filter(|m| args.methods.is_empty() || args.methods.contains(&m.name));
        for method in chosen {
            let checked = with(&scene, &method.settings, check);
            let (wrong, rmse) = errors(&checked, &truth)?;
            let full = with(&scene, &method.settings, (c.width, c.height));
            let (bytes, lines) = footprint(&full);
            let t = frame_times(&full, c.frames)?;
            let (light, eye, frame) = (t.shadows, t.shading, t.frame);
            println!(
                "| {name} | {} | {:.3}% | {rmse:.4} | {:.1} M | {} | {light:.1} | {eye:.1} | {frame:.1} | {:.0}% |",
                method.name,
                100.0 * wrong,
                bytes as f64 / 1e6,
                if lines > 0 { lines.to_string() } else { "–".into() },
                100.0 * t.shadow_serial,
            );
        }
    }
    println!(
        "\nEvery light made a point (no size): the truth is hard shadows. Errors at {}×{} against shadow rays through the BVH (misclassified: visible points facing a light, N·L > \
         0.05, decided lit or not unlike a shadow ray; boundary RMSE: the term against 16 × 16 shadow rays per pixel \
         on the pixels where the rays' own decisions change within 3 × 3); times at {}×{}, median of {} frames after \
         a warm-up, every map rendered again each frame; the eye pass is the shading (the light pass not in it); \
         shadows serial: the share of the light pass's wall time during which a worker had no work (`kage::idle`); 2 \
         threads.",
        check.0, check.1, c.width, c.height, c.frames
    );
    Ok(())
}
