//! The Khronos glTF sample models that test one feature each, judged by
//! their own markers: a card whose failing cases show red crosses shows
//! none, vertex colours draw the ticks their texture twin does, a
//! texture-transform card's arrows reach their green targets, a sparse
//! accessor's replaced vertices stand where the file puts them, a
//! quantized, meshopt- or Draco-compressed file draws as its plain original
//! does, strips and fans are drawn, a missing texture is a warning and a
//! visible placeholder, and alpha blends or cuts where the material says and
//! nowhere else.

#[path = "common/skip.rs"]
mod skip;
use std::path::{Path, PathBuf};

use glam::Vec3;
use kage::scene::framing::{CameraOverride, View};
use kage::scene::model::{scene_for_model, scene_for_model_with, ModelOptions};
use kage::{render, RenderOptions, Scene};

fn asset(rel: &str) -> Option<PathBuf> {
    skip::asset(&format!("gltf/{rel}"))
}

/// `path` seen face on (from the front), on no ground.
fn front_on(path: &Path, (w, h): (u32, u32)) -> (Scene, Shown) {
    let camera = CameraOverride { view: Some(View::FRONT), ..CameraOverride::default() };
    let options = ModelOptions { ground: false, camera, ..ModelOptions::default() };
    let scene = scene_for_model_with(path, w, h, &options).unwrap();
    let shown = Shown::of(&scene);
    (scene, shown)
}

/// A frame as `kage render` writes it: its exposure applied.
struct Shown {
    image: kage::image::LinearImage,
    scale: f32,
}

impl Shown {
    fn of(scene: &Scene) -> Shown {
        let image = render(scene, &RenderOptions::default()).unwrap().image;
        Shown { scale: scene.exposure.scale(&image), image }
    }

    fn get(&self, x: u32, y: u32) -> Vec3 {
        self.image.get(x, y) * self.scale
    }
}

/// Pixels of `frame` whose linear colour (exposed) `is` picks.
fn pixels(frame: &Shown, is: impl Fn(Vec3) -> bool) -> Vec<(u32, u32)> {
    let (w, h) = (frame.image.width(), frame.image.height());
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).filter(|&(x, y)| is(frame.get(x, y))).collect()
}

/// Whether `c` is of the hue whose strong channels `strong` marks (red,
/// green, blue): each of them over 0.02 and four times each weak one.
fn hue(c: Vec3, strong: [bool; 3]) -> bool {
    let c = c.to_array();
    let (mut least_strong, mut most_weak) = (f32::MAX, 0f32);
    for (v, s) in c.iter().zip(strong) {
        if s {
            least_strong = least_strong.min(*v);
        } else {
            most_weak = most_weak.max(*v);
        }
    }
    least_strong > 0.02 && least_strong > 4.0 * most_weak
}

/// The cards' marks: red crosses, green ticks and targets, yellow.
fn red(c: Vec3) -> bool {
    hue(c, [true, false, false])
}

fn green(c: Vec3) -> bool {
    hue(c, [false, true, false])
}

fn yellow(c: Vec3) -> bool {
    hue(c, [true, true, false]) && (c.x - c.y).abs() < 0.3 * c.x
}

fn magenta(c: Vec3) -> bool {
    hue(c, [true, false, true]) && (c.x - c.z).abs() < 0.3 * c.x
}

#[test]
fn the_negative_scale_and_texture_settings_cards_show_no_red_cross() {
    // Before mirrored nodes were turned round and samplers' wrap modes read,
    // 62 and 250 pixels of these cards were red at this size.
    for model in ["NegativeScaleTest/NegativeScaleTest.glb", "TextureSettingsTest/TextureSettingsTest.glb"] {
        let Some(path) = asset(model) else { continue };
        let (_, frame) = front_on(&path, (480, 360));
        let green = pixels(&frame, green).len();
        assert!(green > 100, "{model}: its green ticks show ({green} pixels)");
        let red = pixels(&frame, red).len();
        assert!(red < 10, "{model}: {red} pixels of red crosses");
    }
}

#[test]
fn the_vertex_colour_cards_top_row_matches_its_textured_row() {
    let Some(path) = asset("VertexColorTest/VertexColorTest.glb") else { return };
    let (_, frame) = front_on(&path, (480, 360));
    // The top row's ticks are vertex colours, the bottom row's a texture:
    // the same red and green ticks above and below the middle (without
    // vertex colours the top row shows crosses: 385 red pixels against 752).
    for (name, is) in [("red", red as fn(Vec3) -> bool), ("green", green)] {
        let shown = pixels(&frame, is);
        let above = shown.iter().filter(|&&(_, y)| y < 180).count() as f32;
        let below = shown.len() as f32 - above;
        assert!(below > 300.0 && (above / below - 1.0).abs() < 0.15, "{name}: {above} above, {below} below");
    }
}

#[test]
fn the_texture_transform_cards_arrows_reach_their_green_targets() {
    let Some(path) = asset("TextureTransformTest/TextureTransformTest.gltf") else { return };
    let (_, frame) = front_on(&path, (480, 360));
    // The top row's offsets show a tick on green, blue and teal, not the
    // yellow of an offset not applied.
    let yellow = pixels(&frame, yellow).len();
    let arrows = pixels(&frame, |c| c.max_element() < 0.01);
    // The nearest any arrow pixel comes to a mark.
    let nearest = |marks: &[(u32, u32)]| {
        let d = |(mx, my): (u32, u32), (ax, ay): (u32, u32)| f64::from(mx.abs_diff(ax).pow(2) + my.abs_diff(ay).pow(2));
        marks.iter().flat_map(|&m| arrows.iter().map(move |&a| d(m, a))).fold(f64::MAX, f64::min).sqrt()
    };
    // The bottom row's marks (below the middle of the frame).
    let below = |marks: Vec<(u32, u32)>| marks.into_iter().filter(|&(_, y)| y > 180).collect::<Vec<_>>();
    let green = below(pixels(&frame, green));
    // The rotation quad's red mark is where an arrow turned the wrong way
    // ends (8 pixels from an arrow then, 21 turned right).
    let red = below(pixels(&frame, red));
    assert!(!green.is_empty() && !red.is_empty() && !arrows.is_empty(), "the markers and arrows show");
    let (to_green, to_red) = (nearest(&green), nearest(&red));
    assert!(to_green < 8.0, "an arrow reaches a green target ({to_green} pixels off)");
    assert!(to_red > 12.0, "an arrow ends {to_red} pixels from the red mark of a rotation turned the wrong way");
    assert!(yellow < 500, "{yellow} yellow pixels: an offset is not applied");
}

#[test]
fn a_sparse_accessor_raises_the_vertices_it_replaces() {
    let Some(path) = asset("SimpleSparseAccessor/SimpleSparseAccessor.gltf") else { return };
    let loaded = kage::scene::load::model(
        Path::new(path.file_name().unwrap()),
        &kage::scene::load::FileSystem { base: path.parent().unwrap().to_path_buf() },
    )
    .unwrap();
    // The base grid lies at y = 0 (0 to 6 across, 0 to 4 up); the sparse
    // values lift vertices 8, 10 and 12 to 4 units.
    let highest = loaded.parts.iter().flat_map(|p| p.mesh.positions.iter()).map(|p| p.y).fold(f32::MIN, f32::max);
    assert!((highest - 4.0).abs() < 1e-4, "the highest vertex at y = {highest}");
}

#[test]
fn quantized_and_compressed_ducks_are_drawn_where_the_float_duck_is() {
    let Some(float) = asset("Duck/Duck.glb") else { return };
    for other in ["DuckQuantized/Duck.gltf", "DuckMeshopt/Duck.gltf", "DuckDraco/Duck.gltf"] {
        let Some(other) = asset(other) else { continue };
        same_duck(&float, &other);
    }
}

/// Whether the ducks at `a` and `b` have the same bounds and yellow area.
fn same_duck(a: &Path, b: &Path) {
    let sizes: Vec<(Vec3, Vec3, f32)> = [a, b]
        .iter()
        .map(|path| {
            let scene = scene_for_model(path, 160, 120).unwrap();
            let (lo, hi) = scene.caster_bounds().unwrap();
            let frame = Shown::of(&scene);
            let yellow = pixels(&frame, yellow).len() as f32;
            (lo, hi, yellow)
        })
        .collect();
    let ((lo_a, hi_a, yellow_a), (lo_b, hi_b, yellow_b)) = (sizes[0], sizes[1]);
    let size = (hi_a - lo_a).length();
    assert!(
        (lo_a - lo_b).length() < 0.01 * size && (hi_a - hi_b).length() < 0.01 * size,
        "{lo_a}..{hi_a} vs {lo_b}..{hi_b}"
    );
    assert!(yellow_a > 500.0 && (yellow_b / yellow_a - 1.0).abs() < 0.1, "{b:?}: yellow {yellow_a} vs {yellow_b}");
}

#[test]
fn strips_and_fans_are_drawn_and_points_and_lines_said_to_be_skipped() {
    let Some(path) = asset("MeshPrimitiveModes/MeshPrimitiveModes.gltf") else { return };
    let scene = scene_for_model(&path, 160, 120).unwrap();
    let drawn: Vec<&str> = scene.objects.iter().map(|o| o.name.as_str()).collect();
    for mode in ["TRIANGLES", "TRIANGLE_STRIP", "TRIANGLE_FAN"] {
        assert!(drawn.iter().any(|n| n.ends_with(mode)), "{mode} drawn: {drawn:?}");
    }
    for mode in ["Points", "Lines", "LineLoop", "LineStrip"] {
        assert!(scene.warnings.iter().any(|w| w.contains(&format!("uses {mode},"))), "{mode}: {:?}", scene.warnings);
    }
}

#[test]
fn a_draco_box_is_drawn_where_the_plain_box_is() {
    let (Some(plain), Some(draco)) = (asset("Box/Box.glb"), asset("BoxDraco/Box.gltf")) else { return };
    let bounds = |path: &Path| scene_for_model(path, 160, 120).unwrap().caster_bounds().unwrap();
    let ((lo_a, hi_a), (lo_b, hi_b)) = (bounds(&plain), bounds(&draco));
    assert!((lo_a - lo_b).length() < 1e-3 && (hi_a - hi_b).length() < 1e-3, "{lo_a}..{hi_a} vs {lo_b}..{hi_b}");
    let triangles = |path: &Path| {
        scene_for_model(path, 160, 120)
            .unwrap()
            .objects
            .iter()
            .filter_map(|o| o.triangles().map(|m| m.triangles.len()))
            .sum::<usize>()
    };
    assert_eq!(triangles(&plain), triangles(&draco));
}

#[test]
fn an_unlit_material_shows_its_base_colour_unshaded() {
    let Some(path) = asset("UnlitTest/UnlitTest.glb") else { return };
    let (_, frame) = front_on(&path, (320, 240));
    // Two unlit spheres, orange and blue: each one flat colour, however
    // the light falls on it.
    for (name, is) in
        [("orange", (|c: Vec3| c.x > 0.5 && c.z < 0.1) as fn(Vec3) -> bool), ("blue", |c: Vec3| c.z > 0.5 && c.x < 0.1)]
    {
        let shown = pixels(&frame, is);
        assert!(shown.len() > 1000, "{name}: {} pixels", shown.len());
        let colours: Vec<Vec3> = shown.iter().map(|&(x, y)| frame.get(x, y)).collect();
        let (lo, hi) = colours.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &c| (lo.min(c), hi.max(c)));
        // Edge pixels blend with the background: the middle 90% is flat.
        let mut lum: Vec<f32> = colours.iter().map(|c| c.max_element()).collect();
        lum.sort_by(f32::total_cmp);
        let (p5, p95) = (lum[lum.len() / 20], lum[lum.len() * 19 / 20]);
        assert!(p95 - p5 < 0.02, "{name}: shaded from {p5} to {p95} ({lo}..{hi})");
    }
}

#[test]
fn a_missing_texture_is_a_warning_and_a_magenta_checker() {
    let Some(source) = asset("TextureTransformTest/TextureTransformTest.gltf") else { return };
    let dir = std::env::temp_dir().join(format!("kage-missing-texture-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for file in ["TextureTransformTest.gltf", "TextureTransformTest.bin", "Arrow.png", "Correct.png", "Error.png"] {
        std::fs::copy(source.with_file_name(file), dir.join(file)).unwrap();
    }
    // UV.png and NotSupported.png are not copied.
    let path = dir.join("TextureTransformTest.gltf");
    let (scene, frame) = front_on(&path, (320, 240));
    let missing: Vec<&String> = scene.warnings.iter().filter(|w| w.contains("not found")).collect();
    assert!(missing.iter().any(|w| w.contains("UV.png")), "{:?}", scene.warnings);
    let magenta = pixels(&frame, magenta).len();
    assert!(magenta > 200, "{magenta} magenta pixels");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn the_alpha_mode_card_blends_and_cuts_where_its_materials_say() {
    let Some(path) = asset("AlphaBlendModeTest/AlphaBlendModeTest.gltf") else { return };
    let (w, h) = (1200, 600);
    let (_, frame) = front_on(&path, (w, h));
    // OPAQUE ignoring the texture's alpha and BLEND blending it each show a
    // green tick; a renderer that blends the opaque box, or does not blend
    // the blended one, shows a red cross there instead (0 red pixels here;
    // 23 with the blended box drawn by its factor's alpha only).
    let red = pixels(&frame, red).len();
    assert!(red < 10, "{red} pixels of red crosses");
    // Each of the three MASK boxes (cutoffs 0.25, default 0.5, 0.75) is
    // filled up to the green triangle beside it: the texture's alpha is a
    // ramp, cut where it falls below the cutoff.
    let marks = pixels(&frame, green);
    let mut triangles: Vec<Vec<(u32, u32)>> = Vec::new();
    for &(x, y) in marks.iter().filter(|&&(x, _)| x > w / 2) {
        match triangles.iter_mut().find(|t| t.iter().any(|&(a, b)| a.abs_diff(x) + b.abs_diff(y) < 4)) {
            Some(t) => t.push((x, y)),
            None => triangles.push(vec![(x, y)]),
        }
    }
    triangles.retain(|t| t.len() > 8);
    triangles.sort_by_key(|t| t[0].0);
    assert_eq!(triangles.len(), 3, "three cutoff marks: {:?}", triangles.iter().map(|t| t[0]).collect::<Vec<_>>());
    let mut tops = Vec::new();
    for t in &triangles {
        let left = t.iter().map(|p| p.0).min().unwrap();
        let tip = t.iter().map(|p| p.1).sum::<u32>() as f32 / t.len() as f32;
        // The striped fill: the first of eight rows with yellow stripes
        // across the columns left of the mark (not the box's thin border,
        // where the stripes' colour bleeds into its few texels).
        let striped = |y: u32| (left - 40..left - 4).filter(|&x| yellow(frame.get(x, y))).count() >= 5;
        let top = (0..h - 8).find(|&y| (y..y + 8).all(striped)).expect("a striped fill");
        assert!((top as f32 - tip).abs() <= 5.0, "the fill begins at row {top}, its mark at {tip}");
        tops.push(top);
    }
    assert!(tops[0] + 20 < tops[1] && tops[1] + 20 < tops[2], "three cutoffs, three levels: {tops:?}");
}

#[test]
fn a_texture_on_the_second_coordinate_set_reads_it() {
    let Some(path) = asset("MultiUVTest/MultiUVTest.gltf") else { return };
    let (scene, frame) = front_on(&path, (320, 240));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    // The emissive texture is read at TEXCOORD_1, where the cube's face
    // shows the green glTF logo; read at TEXCOORD_0 it shows "Multiple UVs
    // not supported in this viewer" in white, and no green (2098 pixels
    // here; 0 when it was).
    let logo = pixels(&frame, |c| c.y - c.x.max(c.z) > 0.15).len();
    assert!(logo > 500, "{logo} pixels of the green logo");
}
