//! `kage-bench rays`: the BVH (binned SAH) beside Embree and the obvhs crate — build time and
//! primary-ray throughput on the peers' meshes. `kage-bench hybrid`: seed 002
//! §4's item-buffer hybrid beside the same image traced entirely by rays.

use std::path::Path;
use std::process::Command;

use kage::image::LinearImage;
use kage::raytrace::tracer::{ShadowRay, Tracer};
use kage::raytrace::TraceScene;
use kage::scene::Scene;
use kage::shading::ObjectFrames;
use kage::{FrameStats, RenderOptions, Renderer};
use miette::{miette, IntoDiagnostic, Result};
use rayon::prelude::*;

use crate::raster::{peer_scene_for_rays, Meshes};
use crate::{median, repository, Common};

/// Options of `kage-bench rays`.
#[derive(clap::Args, Debug)]
pub struct RaysArgs {
    #[command(flatten)]
    common: Common,
    #[command(flatten)]
    meshes: Meshes,
    /// The Embree peer program (`scripts/build-peers.sh` builds it); its
    /// columns stay empty if it is absent.
    #[arg(long, default_value = "target/peers/embree_bench")]
    embree: std::path::PathBuf,
    /// Alternating rounds of kage and Embree; the best round of each is reported.
    #[arg(long, default_value_t = 5)]
    rounds: usize,
}

/// Options of `kage-bench hybrid`.
#[derive(clap::Args, Debug)]
pub struct HybridArgs {
    #[command(flatten)]
    common: Common,
}

/// One row of the ray benchmark: build ms and Mrays/s (one ray at a time,
/// packets of eight) for kage and Embree.
struct RayRow {
    name: String,
    triangles: usize,
    build_ms: f64,
    mrays: f64,
    packet_mrays: f64,
    peer: Option<Peer>,
    crate_bvh: CrateBvh,
}

/// The obvhs crate's compressed wide BVH (CWBVH from a PLOC tree, its
/// `medium_build` preset): build ms and Mrays/s, one ray at a time.
#[derive(Clone, Copy)]
struct CrateBvh {
    build_ms: f64,
    mrays: f64,
}

/// Embree's build ms and Mrays/s (`rtcIntersect1`, `rtcIntersect8`).
#[derive(Clone, Copy)]
struct Peer {
    build_ms: f64,
    mrays: f64,
    packet_mrays: f64,
}

/// Runs the ray table and prints it.
pub fn run(args: &RaysArgs) -> Result<()> {
    let common = &args.common;
    let mut rows = Vec::new();
    for name in args.meshes.scenes.split(',').map(str::trim) {
        let (mesh, scene) = peer_scene_for_rays(common, &args.meshes, name)?;
        let triangles = crate_triangles(&scene);
        let mut best: Option<RayRow> = None;
        for _ in 0..args.rounds.max(1) {
            let (build_ms, mrays, packet_mrays) = time_rays(&scene, common.frames);
            let crate_bvh = time_obvhs(&scene, &triangles, common.frames);
            let peer = args.embree.exists().then(|| run_embree(&args.embree, &mesh, common)).transpose()?;
            let triangles = scene.triangle_count();
            let row = RayRow { name: name.to_string(), triangles, build_ms, mrays, packet_mrays, peer, crate_bvh };
            best = Some(match best {
                None => row,
                Some(b) => RayRow {
                    build_ms: b.build_ms.min(row.build_ms),
                    mrays: b.mrays.max(row.mrays),
                    packet_mrays: b.packet_mrays.max(row.packet_mrays),
                    peer: match (b.peer, row.peer) {
                        (Some(p), Some(q)) => Some(Peer {
                            build_ms: p.build_ms.min(q.build_ms),
                            mrays: p.mrays.max(q.mrays),
                            packet_mrays: p.packet_mrays.max(q.packet_mrays),
                        }),
                        (p, q) => p.or(q),
                    },
                    crate_bvh: CrateBvh {
                        build_ms: b.crate_bvh.build_ms.min(row.crate_bvh.build_ms),
                        mrays: b.crate_bvh.mrays.max(row.crate_bvh.mrays),
                    },
                    ..row
                },
            });
        }
        rows.push(best.expect("one round"));
        eprintln!("{name}: done");
    }
    println!(
        "| scene | triangles | kage build ms | Embree build ms | build ratio | kage Mrays/s | Embree Mrays/s | rate ratio | kage packets Mrays/s | Embree packets Mrays/s | packet rate ratio |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    for r in &rows {
        let peer = |f: &dyn Fn(&Peer) -> f64, ours: Option<f64>| match (&r.peer, ours) {
            (Some(p), Some(ours)) => format!("{:.2}", ours / f(p)),
            (Some(p), None) => format!("{:.2}", f(p)),
            (None, _) => "n/a".into(),
        };
        println!(
            "| {} | {} | {:.1} | {} | {} | {:.2} | {} | {} | {:.2} | {} | {} |",
            r.name,
            r.triangles,
            r.build_ms,
            r.peer.map_or("n/a".into(), |p| format!("{:.1}", p.build_ms)),
            peer(&|p| p.build_ms, Some(r.build_ms)),
            r.mrays,
            peer(&|p| p.mrays, None),
            peer(&|p| p.mrays, Some(r.mrays)),
            r.packet_mrays,
            peer(&|p| p.packet_mrays, None),
            peer(&|p| p.packet_mrays, Some(r.packet_mrays)),
        );
    }
    println!(
        "\n| scene | obvhs build ms | kage build / obvhs | obvhs Mrays/s | kage rate / obvhs | kage packets / obvhs |"
    );
    println!("|---|---:|---:|---:|---:|---:|");
    for r in &rows {
        let c = r.crate_bvh;
        println!(
            "| {} | {:.1} | {:.2} | {:.2} | {:.2} | {:.2} |",
            r.name,
            c.build_ms,
            r.build_ms / c.build_ms,
            c.mrays,
            r.mrays / c.mrays,
            r.packet_mrays / c.mrays
        );
    }
    println!(
        "\n{}x{} primary rays (one per pixel centre, nearest hit, no shading), one at a time and in packets of 4 x 2 pixels; obvhs one at a time; median of {} frames; build median of 5; best of {} rounds; {} threads.",
        common.width,
        common.height,
        common.frames,
        args.rounds.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// Median BVH build time (ms) and primary-ray throughput (Mrays/s), one ray at
/// a time and in packets of eight.
fn time_rays(scene: &Scene, frames: usize) -> (f64, f64, f64) {
    let mut builds = Vec::new();
    let mut trace = TraceScene::new(scene);
    for _ in 0..5 {
        drop(trace); // freed outside the timing, as the peer releases its scene
        let t = std::time::Instant::now();
        trace = TraceScene::new(scene);
        builds.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let (w, h) = (scene.width, scene.height);
    let ray = |x: u32, y: u32| rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
    let single = || -> usize {
        (0..h)
            .into_par_iter()
            .map(|y| (0..w).filter(|&x| trace.intersect(&ray(x, y), f32::INFINITY).is_some()).count())
            .sum()
    };
    // Packets of 4 × 2 pixels, as Embree's peer forms its eight-ray packets.
    let packets = || -> usize {
        (0..h.div_ceil(2))
            .into_par_iter()
            .map(|row| {
                let mut found = 0;
                for x0 in (0..w).step_by(4) {
                    let mut block = [ray(x0, 2 * row); 8];
                    let mut n = 0;
                    for (x, y) in (0..8).map(|k| (x0 + k % 4, 2 * row + k / 4)).filter(|&(x, y)| x < w && y < h) {
                        (block[n], n) = (ray(x, y), n + 1);
                    }
                    found += trace.intersect_packet(&block[..n], f32::INFINITY).iter().flatten().count();
                }
                found
            })
            .sum()
    };
    let (mut times, mut packet_times) = (Vec::new(), Vec::new());
    for _ in 0..frames.max(1) + 1 {
        for (f, out) in [(&single as &(dyn Fn() -> usize + Sync), &mut times), (&packets, &mut packet_times)] {
            let t = std::time::Instant::now();
            std::hint::black_box(f());
            out.push(t.elapsed().as_secs_f64());
        }
    }
    times.remove(0); // warm-up
    packet_times.remove(0);
    let rate = |t: &mut Vec<f64>| (w * h) as f64 / median(t) / 1e6;
    (median(&mut builds), rate(&mut times), rate(&mut packet_times))
}

/// The scene's world triangles as obvhs takes them (any order: obvhs builds its own).
fn crate_triangles(scene: &Scene) -> Vec<obvhs::triangle::Triangle> {
    let trace = TraceScene::new(scene);
    (0..trace.len())
        .map(|i| {
            let [v0, v1, v2] = trace.triangle(i).map(glam::Vec3A::from);
            obvhs::triangle::Triangle { v0, v1, v2 }
        })
        .collect()
}

/// Median obvhs build time (ms: the compressed wide BVH and its triangles put in
/// leaf order, as kage's build gathers its triangle columns) and its primary-ray
/// throughput (Mrays/s), one ray at a time, on the same rays as kage's.
fn time_obvhs(scene: &Scene, triangles: &[obvhs::triangle::Triangle], frames: usize) -> CrateBvh {
    use obvhs::ray::{Ray, RayHit};
    let build = || {
        let bvh = obvhs::cwbvh::builder::build_cwbvh_from_tris(
            triangles,
            obvhs::BvhBuildParams::medium_build(),
            &mut std::time::Duration::default(),
        );
        let ordered: Vec<_> = bvh.primitive_indices.par_iter().map(|&i| triangles[i as usize]).collect();
        (bvh, ordered)
    };
    let mut builds = Vec::new();
    let mut built = build();
    for _ in 0..5 {
        drop(built);
        let t = std::time::Instant::now();
        built = build();
        builds.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let (bvh, ordered) = &built;
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let (w, h) = (scene.width, scene.height);
    let single = || -> usize {
        (0..h)
            .into_par_iter()
            .map(|y| {
                (0..w)
                    .filter(|&x| {
                        let r = rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                        let ray = Ray::new(r.origin.into(), r.dir.into(), 0.0, f32::INFINITY);
                        let mut hit = RayHit::none();
                        bvh.ray_traverse(ray, &mut hit, |ray, id| ordered[id].intersect(ray))
                    })
                    .count()
            })
            .sum()
    };
    let mut times = Vec::new();
    for _ in 0..frames.max(1) + 1 {
        let t = std::time::Instant::now();
        std::hint::black_box(single());
        times.push(t.elapsed().as_secs_f64());
    }
    times.remove(0); // warm-up
    CrateBvh { build_ms: median(&mut builds), mrays: (w * h) as f64 / median(&mut times) / 1e6 }
}

/// Runs Embree's primary-ray benchmark (no shading; `rtcIntersect1` and
/// `rtcIntersect8` on 4 × 2 pixel blocks) on the same mesh.
fn run_embree(bin: &Path, mesh: &Path, common: &Common) -> Result<Peer> {
    let out = Command::new(bin)
        .args(["-t", "2", "-n", "-m", "primary", "-a", "1,8", "-f", &common.frames.to_string()])
        .args(["-w", &common.width.to_string(), "-h", &common.height.to_string()])
        .arg(mesh)
        .output()
        .into_diagnostic()?;
    let text = String::from_utf8_lossy(&out.stdout);
    let field = |line: &str, key: &str| -> Option<f64> {
        line.split_whitespace().find_map(|w| w.strip_prefix(key)).and_then(|v| v.parse().ok())
    };
    let build = text.lines().find(|l| l.contains("what=build")).and_then(|l| field(l, "median_ms="));
    let rate = |api: &str| {
        let key = format!("api={api} ");
        text.lines().find(|l| l.contains("mode=primary") && l.contains(&key)).and_then(|l| field(l, "mrays_s="))
    };
    match (build, rate("1"), rate("8")) {
        (Some(build_ms), Some(mrays), Some(packet_mrays)) => Ok(Peer { build_ms, mrays, packet_mrays }),
        _ => Err(miette!("Embree printed no build/primary results: {text}{}", String::from_utf8_lossy(&out.stderr))),
    }
}

/// Item-buffer hybrid vs full ray tracing of the same image (two ray levels).
pub fn run_hybrid(args: &HybridArgs) -> Result<()> {
    let args = &args.common;
    let load = |name: &str| {
        let path = repository().join("examples/scenes").join(name);
        let mut scene = kage::scene::file::load_scene(&path).map_err(|e| miette!("{e}"))?;
        (scene.width, scene.height) = (args.width, args.height);
        // The full trace casts one ray per pixel: the hybrid draws aliased too.
        scene.antialias = kage::scene::Antialias::None;
        Ok::<Scene, miette::Report>(scene)
    };
    let showroom = load("showroom.toml")?;
    let mut balls = load("reflections.toml")?;
    // A matte floor leaves the curved chrome and glass balls as the only reflecting
    // and refracting pixels.
    balls.materials.iter_mut().filter(|m| m.name == "floor").for_each(|m| m.kr = glam::Vec3::ZERO);
    let mut closer = balls.clone();
    let cam = &mut closer.camera;
    cam.eye = cam.target + (cam.eye - cam.target) * 0.8; // the balls fill about a fifth
    println!(
        "| scene | triangles | pixels traced | hybrid ms/frame | of which visibility / shadow maps / shading / traced | full trace ms/frame | speed-up | BVH build ms (once) | RMSE between them | pixels over 0.01 |"
    );
    println!("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|");
    let rows = [
        ("showroom.toml (polished stage, chrome ball)", &showroom),
        ("reflections.toml, matte floor (chrome and glass balls)", &balls),
        ("the same, eye at 0.8x", &closer),
    ];
    for (label, scene) in rows {
        hybrid_row(args, scene, label)?;
    }
    println!(
        "\nTwo ray levels (primary + one bounce); primary shadows from shadow maps (hybrid) or shadow rays (full trace); \
         shadow rays at the surfaces secondary rays reach in both; one BVH, built before timing; median of {} frames; {} threads.",
        args.frames.max(1),
        rayon::current_num_threads()
    );
    Ok(())
}

/// One row of the hybrid table: the item-buffer frame and the fully traced image of
/// `scene`, timed alternately.
fn hybrid_row(args: &Common, scene: &Scene, label: &str) -> Result<()> {
    // "Traced up to the second ray" (seed 002 §4): primary + one bounce.
    let depth = 1;
    let mut renderer =
        Renderer::new(&RenderOptions { ray_depth: depth, ..RenderOptions::default() }).map_err(|e| miette!("{e}"))?;
    let (mut hybrid, mut full) = (Vec::new(), Vec::new());
    let mut parts = Vec::new();
    let mut full_image = None;
    // Both sides trace through one BVH, built once (an interactive preview keeps it
    // while only the view changes); the build is reported on its own.
    let t = std::time::Instant::now();
    let trace = TraceScene::new(scene);
    let build_ms = t.elapsed().as_secs_f64() * 1e3;
    renderer.render(scene).map_err(|e| miette!("{e}"))?; // builds the renderer's copy
    for _ in 0..args.frames.max(1) {
        let t = std::time::Instant::now();
        parts.push(renderer.render(scene).map_err(|e| miette!("{e}"))?.stats);
        hybrid.push(t.elapsed().as_secs_f64() * 1e3);
        let t = std::time::Instant::now();
        full_image = Some(trace_everything(scene, &trace, depth));
        full.push(t.elapsed().as_secs_f64() * 1e3);
    }
    let frame = renderer.into_frame();
    let c = kage::compare::compare(&frame.image, &full_image.expect("one frame"), 0.01).map_err(|e| miette!("{e}"))?;
    let (h, f) = (median(&mut hybrid), median(&mut full));
    let traced = parts.last().map_or(0, |s| s.traced_pixels);
    let share = 100.0 * traced as f64 / (scene.width as f64 * scene.height as f64);
    let part = |get: fn(&FrameStats) -> f64| median(&mut parts.iter().map(get).collect::<Vec<_>>());
    println!(
        "| {label} {}x{} | {} | {share:.1}% | {h:.1} | {:.0} / {:.0} / {:.0} / {:.0} | {f:.1} | {:.2}x | {build_ms:.1} | {:.5} | {:.3}% |",
        scene.width,
        scene.height,
        trace.len(),
        part(|s| s.visibility_ms),
        part(|s| s.shadow_ms),
        part(|s| s.shading_ms),
        part(|s| s.traced_ms),
        f / h,
        c.rmse,
        100.0 * c.share_over
    );
    Ok(())
}

/// The hybrid's image computed entirely by rays, as a plain ray tracer would:
/// primary hits from the BVH, shadow rays at them (where the hybrid reads shadow
/// maps), the same bounces.
fn trace_everything(scene: &Scene, trace: &TraceScene, depth: u32) -> LinearImage {
    let frames = ObjectFrames::new(scene);
    let tracer = Tracer::new(scene, trace, &frames, ShadowRay);
    let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
    let mut image = LinearImage::new(scene.width, scene.height);
    let w = scene.width as usize;
    // Primary rays in packets of 4 × 2 pixels, as a ray tracer casts coherent rays.
    image.pixels_mut().par_chunks_mut(2 * w).enumerate().for_each(|(pair, rows)| {
        for x0 in (0..w).step_by(4) {
            let pixels: Vec<(usize, usize)> =
                (0..8).map(|k| (x0 + k % 4, k / 4)).filter(|&(x, dy)| x < w && dy * w < rows.len()).collect();
            let packet: Vec<kage::camera::Ray> = pixels
                .iter()
                .map(|&(x, dy)| rays.ray(glam::Vec2::new(x as f32 + 0.5, (2 * pair + dy) as f32 + 0.5)))
                .collect();
            let (light, _) = tracer.radiance_packet(&packet, depth);
            pixels.iter().zip(light).for_each(|(&(x, dy), l)| rows[dy * w + x] = l);
        }
    });
    image
}
