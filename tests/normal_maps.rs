//! Normal maps against the geometry they stand for: a flat square whose map
//! holds one tilted normal everywhere must shade exactly as a square tilted
//! that way would under a directional light (Lambert's cosine with the tilted
//! normal, worked out here from the glTF convention: x along +u, y up the
//! image, z out of the surface) — in the raster passes, the edge pass's
//! samples and the ray-traced reference alike. And a real model's normal map
//! changes its image where its texture says.

mod common;
#[path = "common/skip.rs"]
mod skip;

use std::path::Path;
use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::raytrace::reference::{render_reference, ReferenceOptions};
use kage::scene::mesh::shapes;
use kage::scene::{Antialias, LightKind, NormalMap, ShadowSettings, Texture};
use kage::{render, RenderOptions};

/// Where the light travels: from above, right and towards the viewer.
const LIGHT_TRAVELS: Vec3 = Vec3::new(-0.5, -1.0, 0.8);

/// The unit square of the xz plane (texture u along +x, v along +z, normal
/// +y) scaled to 4 × 4, seen from straight above, lit by one directional
/// light without shadows or ambient, its normal map one texel `normal`.
fn square_with_map(normal: Option<Vec3>, antialias: Antialias) -> kage::Scene {
    let camera = Camera {
        eye: Vec3::new(0.0, 5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        near: 0.1,
        far: 20.0,
        projection: Projection::Perspective { fov_y_deg: 30.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::plane(), camera, 48, 48, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(4.0));
    scene.antialias = antialias;
    let light = &mut scene.lights[0];
    light.kind = LightKind::Directional { direction: LIGHT_TRAVELS.normalize() };
    (light.ambient, light.shadow) = (0.0, ShadowSettings::NONE);
    let m = &mut scene.materials[0];
    (m.ks, m.kd) = (Vec3::ZERO, Vec3::splat(0.8));
    m.maps.normal = normal.map(|n| NormalMap {
        texture: Arc::new(Texture::from_texels(4, 4, vec![(n.normalize() + Vec3::ONE) * 0.5; 16])),
        scale: 1.0,
    });
    scene
}

/// The diffuse a square tilted to tangent-space normal `n` receives: in the
/// world, x along +u (+x), y up the image (−v, so −z), z the normal (+y).
fn lambert(n: Vec3) -> f32 {
    let n = n.normalize();
    let world = Vec3::new(n.x, n.z, -n.y);
    0.8 * world.dot(-LIGHT_TRAVELS.normalize()).max(0.0)
}

const TILTS: [Vec3; 5] = [
    Vec3::new(0.0, 0.0, 1.0),
    Vec3::new(0.5, 0.0, 0.8),
    Vec3::new(-0.5, 0.0, 0.8),
    Vec3::new(0.0, 0.5, 0.8),
    Vec3::new(0.3, -0.4, 0.8),
];

/// Largest difference between the centre 24 × 24 pixels of `image` and `want`.
fn worst(image: &kage::image::LinearImage, want: f32) -> f32 {
    (12..36)
        .flat_map(|y| (12..36).map(move |x| (x, y)))
        .map(|(x, y)| (image.get(x, y).x - want).abs())
        .fold(0.0, f32::max)
}

#[test]
fn a_map_of_one_tilt_shades_as_the_tilted_square_would() {
    for tilt in TILTS {
        let want = lambert(tilt);
        for antialias in [Antialias::None, Antialias::default()] {
            let frame = render(&square_with_map(Some(tilt), antialias), &RenderOptions::default()).unwrap();
            let off = worst(&frame.image, want);
            assert!(off < 2e-3, "tilt {tilt} ({antialias:?}): off by {off} from {want}");
        }
        let opts = ReferenceOptions { pixel_samples: 1, shadows: false, ..ReferenceOptions::default() };
        let traced = render_reference(&square_with_map(Some(tilt), Antialias::None), &opts, &|_| {});
        let off = worst(&traced, want);
        assert!(off < 2e-3, "tilt {tilt}, reference: off by {off} from {want}");
    }
    // The tilts do change the image: the flat square is not what they give.
    let flat = lambert(Vec3::Z);
    assert!(TILTS[1..].iter().all(|&t| (lambert(t) - flat).abs() > 0.05));
}

/// The Avocado's normal map (glTF sample model): its image with the map
/// differs from the same render with the map taken away, across much of the
/// fruit, and the two are alike in overall brightness (a map tilts normals,
/// it does not darken the model).
#[test]
fn the_avocados_normal_map_moves_its_shading() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/assets/gltf/Avocado/Avocado.gltf");
    if !path.exists() {
        skip::skipped(&format!("{} is absent", path.display()));
        return;
    }
    let scene = kage::scene::model::scene_for_model(&path, 240, 240).unwrap();
    assert!(scene.materials.iter().any(|m| m.maps.normal.is_some()), "the Avocado's normal texture is read");
    let mut flat = scene.clone();
    flat.materials.iter_mut().for_each(|m| m.maps.normal = None);
    let options = RenderOptions::default();
    let (bumped, flat) = (render(&scene, &options).unwrap(), render(&flat, &options).unwrap());
    let (mut moved, mut covered, mut sums) = (0, 0, (0.0f64, 0.0f64));
    for y in 0..240 {
        for x in 0..240 {
            if bumped.visibility.item(x, y).is_none() || bumped.visibility.item(x, y).object != 0 {
                continue;
            }
            let (a, b) = (bumped.image.get(x, y), flat.image.get(x, y));
            covered += 1;
            moved += usize::from((a - b).abs().max_element() > 0.01);
            sums = (sums.0 + f64::from(a.element_sum()), sums.1 + f64::from(b.element_sum()));
        }
    }
    assert!(covered > 2000, "the fruit covers {covered} pixels");
    assert!(moved * 4 > covered, "the map moved {moved} of {covered} pixels");
    let ratio = sums.0 / sums.1;
    assert!((0.8..1.25).contains(&ratio), "brightness with the map / without: {ratio:.3}");
}
