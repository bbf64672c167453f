//! Tiles of a frame: a region rendered on its own equals the same pixels of
//! the whole frame, bit for bit, with every technique on (edge antialiasing
//! and jittered passes, every shadow method, a mirror, glass, translucent
//! surfaces, fog, a CSG solid, a texture; an environment, the viewer's sparse
//! rays, every component and shadow term on its own, feature lines), for random tilings on 1,
//! 5, 16 and 2 workers; and a tile's buffers cost its area.

use std::path::Path;

use kage::image::{LinearImage, PixelRect};
use kage::scene::file::load_scene;
use kage::scene::{Antialias, FeatureLines, Scene, ShadowMethod};
use kage::shading::{Component, ComponentSet};
use kage::{render, Frame, RenderOptions, Renderer};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn everything() -> Scene {
    load_scene(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/tiles.toml").as_path()).expect("test scene")
}

/// `cuts` random positions strictly inside `0..n`, sorted, with 0 and `n`.
fn cuts(rng: &mut StdRng, n: u32, count: usize) -> Vec<u32> {
    let mut c: Vec<u32> = (0..count).map(|_| rng.gen_range(1..n)).collect();
    c.extend([0, n]);
    c.sort_unstable();
    c.dedup();
    c
}

/// A random grid of tiles covering a `w` × `h` image.
fn random_tiling(rng: &mut StdRng, w: u32, h: u32) -> Vec<PixelRect> {
    let (nx, ny) = (rng.gen_range(0..4), rng.gen_range(0..4));
    let (xs, ys) = (cuts(rng, w, nx), cuts(rng, h, ny));
    let mut tiles = Vec::new();
    for y in ys.windows(2) {
        for x in xs.windows(2) {
            tiles.push(PixelRect { x0: x[0], y0: y[0], x1: x[1], y1: y[1] });
        }
    }
    tiles
}

/// Renders `scene` whole, then tile by tile for `tilings` random tilings, and
/// asserts every tile's pixels equal the whole frame's, bit for bit.
fn tiles_equal_the_frame(scene: &Scene, what: &str, seed: u64, tilings: usize) {
    tiles_equal_the_frame_with(scene, &RenderOptions::default(), what, seed, tilings);
}

/// The images of a frame: the final one, each component's and each light's
/// shadow term.
fn images(frame: &Frame) -> Vec<&LinearImage> {
    std::iter::once(&frame.image).chain(frame.aovs.iter().map(|(_, a)| a)).chain(&frame.shadows).collect()
}

/// Worker counts the tilings are rendered with, one after the other (the
/// whole frame with one per core): what is computed does not depend on how
/// it is shared out.
const THREADS: [usize; 4] = [1, 5, 16, 2];

/// As [`tiles_equal_the_frame`], rendered with `options`, every image of the
/// frame compared (components and shadow terms too), tilings rendered on
/// [`THREADS`] workers in turn.
fn tiles_equal_the_frame_with(scene: &Scene, options: &RenderOptions, what: &str, seed: u64, tilings: usize) {
    let whole = render(scene, options).expect("whole frame");
    assert_eq!(whole.rect(), PixelRect::full(scene.width, scene.height), "a whole frame holds every pixel");
    let whole: Vec<LinearImage> = images(&whole).into_iter().cloned().collect();
    let mut rng = StdRng::seed_from_u64(seed);
    for (_, threads) in (0..tilings).zip(THREADS.iter().cycle()) {
        let options = &RenderOptions { threads: Some(*threads), ..*options };
        let what = &format!("{what}, {threads} threads");
        let tiling = random_tiling(&mut rng, scene.width, scene.height);
        let mut merged = vec![LinearImage::new(scene.width, scene.height); whole.len()];
        // One renderer for every tile: what a tile leaves outside itself
        // (the tile before's pixels) must not reach the next.
        let mut renderer = Renderer::new(options).expect("renderer");
        for &tile in &tiling {
            renderer.set_options(&RenderOptions { region: Some(tile), ..*options }).expect("options");
            let frame = renderer.render(scene).expect("tile");
            assert_eq!(frame.rect(), kage::frame::region_drawn(scene, tile), "a tile holds what it draws");
            for (m, image) in merged.iter_mut().zip(images(frame)) {
                m.paste(&image.crop(tile.relative_to(frame.rect())), tile.x0, tile.y0);
            }
        }
        for (k, (whole, merged)) in whole.iter().zip(&merged).enumerate() {
            let differ = whole
                .pixels()
                .iter()
                .zip(merged.pixels())
                .position(|(a, b)| a.to_array().map(f32::to_bits) != b.to_array().map(f32::to_bits));
            if let Some(i) = differ {
                let (x, y) = (i as u32 % scene.width, i as u32 / scene.width);
                let count = whole.pixels().iter().zip(merged.pixels()).filter(|(a, b)| a != b).count();
                panic!(
                    "{what}: image {k}: tiling {tiling:?}: pixel ({x}, {y}) is {} whole and {} tiled ({count} pixels differ)",
                    whole.get(x, y),
                    merged.get(x, y)
                );
            }
        }
    }
}

/// The test scene with its two-map soft light's shadows mapped instead: no
/// light's term is computed per pixel of the frame, so a tile draws only
/// itself and a guard band.
fn without_soft_shadows(mut scene: Scene) -> Scene {
    for light in &mut scene.lights {
        if light.shadow.method == ShadowMethod::Soft {
            light.shadow = light.shadow.with_method(ShadowMethod::Map);
        }
    }
    scene
}

#[test]
fn tiles_of_an_edge_antialiased_frame_equal_the_frame() {
    tiles_equal_the_frame(&everything(), "edge", 1, 3);
}

#[test]
fn tiles_of_a_jittered_frame_equal_the_frame() {
    let scene = Scene { antialias: Antialias::Jitter(4), ..everything() };
    tiles_equal_the_frame(&scene, "jitter:4", 2, 2);
}

/// Without two-map soft shadows a tile draws only itself and a guard band:
/// the band must hold everything its pixels look at.
#[test]
fn tiles_drawn_with_a_guard_band_equal_the_frame() {
    let scene = without_soft_shadows(everything());
    let drawn = kage::frame::region_drawn(&scene, PixelRect { x0: 40, y0: 30, x1: 60, y1: 50 });
    assert_eq!(drawn, PixelRect { x0: 0, y0: 14, x1: 128, y1: 66 }, "a region grown by the guard band");
    let none = Scene { antialias: Antialias::None, ..scene.clone() };
    tiles_equal_the_frame(&none, "no antialiasing, no soft light", 3, 4);
    tiles_equal_the_frame(&scene, "edge, no soft light", 3, 4);
    let scene = Scene { antialias: Antialias::Jitter(3), ..scene };
    tiles_equal_the_frame(&scene, "jitter:3, no soft light", 4, 2);
}

/// A reflection map seen through a visible environment (each pixel's filter
/// reaches its neighbours), the viewer's sparse traced term (every other
/// pixel traced), every component on its own and each light's shadow term:
/// tiles equal the frame in every image.
#[test]
fn tiles_of_an_environment_with_sparse_rays_and_every_image_equal_the_frame() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/environment.toml");
    let scene = Scene { width: 150, height: 85, ..load_scene(&path).expect("environment.toml") };
    let scene = without_soft_shadows(Scene { antialias: Antialias::None, ..scene });
    let options =
        RenderOptions { sparse_traced: true, shadow_images: true, aovs: ComponentSet::ALL, ..RenderOptions::default() };
    tiles_equal_the_frame_with(&scene, &options, "environment, sparse", 5, 3);
    let edge = Scene { antialias: Antialias::Edge(Default::default()), ..scene };
    tiles_equal_the_frame_with(&edge, &RenderOptions { sparse_traced: false, ..options }, "environment, edge", 6, 2);
}

/// An OpenSCAD part whose solid holds closed meshes (its extrusions): a tile
/// rasterizes the meshes' layers on its own rows alone and still draws what
/// the whole frame draws there.
#[test]
fn tiles_of_an_openscad_part_with_closed_meshes_equal_the_frame() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/openscad/knob.csg");
    let scene = kage::scene::model::scene_for_model(&path, 160, 120).expect("knob.csg");
    tiles_equal_the_frame(&without_soft_shadows(scene), "knob.csg", 7, 3);
}

/// Feature lines, hidden ones dashed, over meshes and CSG solids: a mesh
/// edge's strokes are steps counted from its start and a solid's come from
/// pixel pairs, so a tile draws the strokes the frame draws there.
#[test]
fn tiles_of_a_frame_with_feature_lines_equal_the_frame() {
    let lines = Some(FeatureLines { hidden: true, ..FeatureLines::default() });
    let scene = Scene { lines, ..without_soft_shadows(everything()) };
    tiles_equal_the_frame(&scene, "lines", 8, 3);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/openscad/knob.csg");
    let knob = kage::scene::model::scene_for_model(&path, 160, 120).expect("knob.csg");
    tiles_equal_the_frame(&Scene { lines, ..without_soft_shadows(knob) }, "knob.csg, lines", 9, 2);
}

/// A tile's buffers hold its pixels and its guard band alone: the bytes of
/// its buffers of one entry a pixel are the whole frame's per pixel times the
/// pixels it draws, and a sixteenth of a frame draws well under a quarter of
/// its pixels.
#[test]
fn a_tiles_buffers_cost_its_area() {
    let scene = Scene { width: 768, height: 432, ..without_soft_shadows(everything()) };
    for antialias in [Antialias::None, Antialias::Jitter(2)] {
        let scene = Scene { antialias, ..scene.clone() };
        let options = RenderOptions { aovs: ComponentSet::only(Component::Diffuse), ..RenderOptions::default() };
        let whole = render(&scene, &options).expect("whole frame").stats.pixel_bytes;
        let area = |r: PixelRect| r.width() as usize * r.height() as usize;
        let per_pixel = whole / area(PixelRect::full(scene.width, scene.height));
        assert!(per_pixel >= 36, "{per_pixel} bytes a pixel: at least depth, item and two images");
        for index in [0, 5, 15] {
            let tile = PixelRect::tile(index, 16, scene.width, scene.height);
            let frame = render(&scene, &RenderOptions { region: Some(tile), ..options }).expect("tile");
            let drawn = frame.rect();
            assert_eq!(
                frame.stats.pixel_bytes,
                per_pixel * area(drawn),
                "{antialias:?}: tile {tile:?} drawn as {drawn:?}"
            );
            assert!(4 * area(drawn) < area(PixelRect::full(scene.width, scene.height)), "{drawn:?}");
            assert_eq!((frame.image.width(), frame.image.height()), (drawn.width(), drawn.height()));
        }
    }
}

#[test]
fn a_region_outside_the_frame_is_refused() {
    let scene = everything();
    for region in [PixelRect { x0: 0, y0: 0, x1: 193, y1: 10 }, PixelRect { x0: 5, y0: 5, x1: 5, y1: 9 }] {
        let options = RenderOptions { region: Some(region), ..RenderOptions::default() };
        let Err(e) = render(&scene, &options) else { panic!("{region:?} rendered") };
        assert!(matches!(e, kage::Error::Region { .. }), "{e}");
    }
}

#[test]
fn tiles_cover_the_image_once() {
    for (count, w, h) in [(16, 7680, 4320), (7, 100, 50), (6, 50, 100), (1, 3, 3), (12, 1920, 1080)] {
        let mut hits = vec![0u8; (w * h) as usize];
        for i in 0..count {
            let t = PixelRect::tile(i, count, w, h);
            assert!(!t.is_empty() && t.fits(w, h), "{t:?}");
            for y in t.y0..t.y1 {
                for x in t.x0..t.x1 {
                    hits[(y * w + x) as usize] += 1;
                }
            }
        }
        assert!(hits.iter().all(|&n| n == 1), "{count} tiles of {w}x{h}");
    }
    assert_eq!(PixelRect::tile(5, 16, 7680, 4320), PixelRect { x0: 1920, y0: 1080, x1: 3840, y1: 2160 });
}
