//! Prints a hash of everything a render produces — the image, the visibility
//! buffer (depth, item ids, solids' normals) and every component image — for
//! each input and each way of rendering it, one line each, so two builds can be
//! compared for identical output (`scripts/frame-hashes.sh` runs it over the
//! example scenes, the demo and the shared corpus).
//!
//! `cargo run --release --example frame_hashes -- [--reference] INPUT...`
//! (`demo` names the built-in demo scene).

use std::path::Path;

use kage::csg::openscad::{CsgOptions, Geometry};
use kage::image::LinearImage;
use kage::scene::{demo::demo_scene, file, model, Antialias, EdgeMode, Scene};
use kage::shading::ComponentSet;
use kage::{render, RenderOptions};

/// FNV-1a over 64 bits: stable across builds and Rust versions.
struct Fnv(u64);

impl Fnv {
    fn new() -> Fnv {
        Fnv(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
    }

    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
}

fn image_hash(image: &LinearImage) -> u64 {
    let mut h = Fnv::new();
    h.u32(image.width());
    h.u32(image.height());
    image.pixels().iter().flat_map(|p| p.to_array()).for_each(|c| h.u32(c.to_bits()));
    h.0
}

fn load(input: &str, geometry: Geometry) -> kage::error::Result<Scene> {
    if input == "demo" {
        return demo_scene();
    }
    let path = Path::new(input);
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or_default().to_ascii_lowercase();
    if ext == "toml" {
        return file::load_scene(path);
    }
    let csg = CsgOptions { geometry, skip_unsupported: false };
    model::scene_for_model_with(path, 480, 270, &model::ModelOptions { csg, ..Default::default() })
}

/// The ways each input is rendered: as its file says, with the edge pass, and
/// with four jittered passes (each also with every component image).
fn variants(scene: &Scene) -> Vec<(&'static str, Scene)> {
    let with = |antialias| Scene { antialias, ..scene.clone() };
    vec![
        ("as-is", scene.clone()),
        ("edge", with(Antialias::Edge(EdgeMode::default()))),
        ("jitter4", with(Antialias::Jitter(4))),
    ]
}

fn print_frame(name: &str, variant: &str, scene: &Scene) {
    let options = RenderOptions { aovs: ComponentSet::ALL, ..RenderOptions::default() };
    let frame = match render(scene, &options) {
        Ok(frame) => frame,
        Err(e) => return println!("{name} {variant} error {e}"),
    };
    println!("{name} {variant} image {:016x}", image_hash(&frame.image));
    let vb = &frame.visibility;
    let mut h = Fnv::new();
    vb.depths().iter().for_each(|d| h.u32(d.to_bits()));
    vb.items().iter().for_each(|i| {
        h.u32(i.object);
        h.u32(i.triangle);
    });
    for y in 0..vb.height() {
        for x in 0..vb.width() {
            vb.normal(x, y).to_array().iter().for_each(|c| h.u32(c.to_bits()));
        }
    }
    println!("{name} {variant} visibility {:016x}", h.0);
    for (c, image) in &frame.aovs {
        println!("{name} {variant} aov-{} {:016x}", c.name(), image_hash(image));
    }
}

fn print_reference(name: &str, scene: &Scene) {
    use kage::raytrace::reference::{render_reference, ReferenceOptions};
    let small = Scene { width: scene.width.div_ceil(4), height: scene.height.div_ceil(4), ..scene.clone() };
    let options = ReferenceOptions {
        pixel_samples: 2,
        light_samples: 2,
        shadows: true,
        max_depth: 4,
        ..ReferenceOptions::default()
    };
    println!("{name} reference image {:016x}", image_hash(&render_reference(&small, &options, &|_| {})));
}

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let reference = args.first().is_some_and(|a| a == "--reference");
    if reference {
        args.remove(0);
    }
    for input in &args {
        let name = Path::new(input).file_name().and_then(|n| n.to_str()).unwrap_or(input);
        let faceted = input.ends_with(".csg");
        let geometries: &[(&str, Geometry)] = if faceted {
            &[("exact", Geometry::Exact), ("faceted", Geometry::Faceted)]
        } else {
            &[("", Geometry::Exact)]
        };
        for (label, geometry) in geometries {
            let name = if label.is_empty() { name.to_string() } else { format!("{name}:{label}") };
            let scene = match load(input, *geometry) {
                Ok(scene) => scene,
                Err(e) => {
                    println!("{name} load error {}", e.to_string().replace('\n', " "));
                    continue;
                }
            };
            for (variant, scene) in variants(&scene) {
                print_frame(&name, variant, &scene);
            }
            if reference {
                print_reference(&name, &scene);
            }
        }
    }
}
