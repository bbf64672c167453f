//! Texture filtering against a supersampled truth: on a finely checkered ground
//! running to the horizon, mipmapped trilinear filtering comes much closer to the
//! average of 64 jittered bilinear frames than bilinear sampling does. An
//! image several materials name is decoded once. An alpha-tested surface is
//! cut away for the eye and for the light alike.

mod common;

use std::sync::Arc;

use glam::{Affine3A, Vec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::compare::compare;
use kage::scene::material::Filter;
use kage::scene::mesh::shapes;
use kage::scene::{Antialias, Texture};
use kage::{render, RenderOptions};

fn checkered_ground(filter: Filter) -> kage::Scene {
    let camera = Camera {
        eye: Vec3::new(0.0, 0.6, 4.0),
        target: Vec3::new(0.0, 0.2, -4.0),
        up: Vec3::Y,
        near: 0.05,
        far: 100.0,
        projection: Projection::Perspective { fov_y_deg: 50.0 },
        shift: Vec2::ZERO,
    };
    let mut scene = common::scene_with(shapes::plane(), camera, 160, 90, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(16.0));
    scene.lights[0].shadow = kage::scene::ShadowSettings::NONE;
    let texels = (0..256 * 256).map(|i| Vec3::splat(if (i % 256 + i / 256) % 2 == 0 { 0.9 } else { 0.1 })).collect();
    let m = &mut scene.materials[0];
    m.ks = Vec3::ZERO;
    m.maps.diffuse = vec![Arc::new(Texture::from_texels(256, 256, texels))];
    m.maps.ambient = m.maps.diffuse.clone();
    m.maps.filter = filter;
    scene
}

#[test]
fn trilinear_mipmapping_approaches_the_supersampled_truth() {
    let mut truth = checkered_ground(Filter::Bilinear);
    truth.antialias = Antialias::Jitter(64);
    let truth = render(&truth, &RenderOptions::default()).unwrap();
    let error = |filter| {
        let frame = render(&checkered_ground(filter), &RenderOptions::default()).unwrap();
        compare(&frame.image, &truth.image, 0.1).unwrap()
    };
    let (bilinear, trilinear) = (error(Filter::Bilinear), error(Filter::Trilinear));
    assert!(
        trilinear.rmse < 0.6 * bilinear.rmse && trilinear.share_over < 0.25 * bilinear.share_over,
        "trilinear rmse {:.4} ({:.3} over 0.1), bilinear {:.4} ({:.3} over 0.1)",
        trilinear.rmse,
        trilinear.share_over,
        bilinear.rmse,
        bilinear.share_over
    );
}

#[test]
fn materials_naming_one_image_share_its_decoded_texture() {
    let dir = std::env::temp_dir().join(format!("kage-shared-image-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let repo = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    std::fs::copy(repo.join("tests/data/fuzz/tex.png"), dir.join("tex.png")).unwrap();
    std::fs::write(
        dir.join("two.mtl"),
        "newmtl a\nmap_Kd tex.png\nnewmtl b\nKd 1 0 0\nmap_Kd tex.png\nmap_Ks tex.png\n",
    )
    .unwrap();
    let obj = "mtllib two.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n\
               usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 2/2 4/4 3/3\n";
    std::fs::write(dir.join("two.obj"), obj).unwrap();
    let fs = kage::scene::load::FileSystem { base: dir.clone() };
    let model = kage::scene::load::model(std::path::Path::new("two.obj"), &fs).unwrap();
    let maps: Vec<_> = model
        .parts
        .iter()
        .filter_map(|p| p.material.as_ref())
        .flat_map(|m| m.maps.diffuse.iter().chain(&m.maps.specular))
        .collect();
    assert_eq!(maps.len(), 3, "three uses of the image");
    assert!(maps.iter().all(|t| std::sync::Arc::ptr_eq(t, maps[0])), "decoded once, shared by every use");
    std::fs::remove_dir_all(&dir).ok();
}

/// A green leaf whose texture's left half is transparent, alpha-tested
/// (cutoff 0.5), one unit above a red floor, seen and lit from straight
/// above: through its cut-away half the eye sees the floor, lit (the cut
/// half casts no shadow either); its kept half is green.
/// A camera 5 units above the origin looking straight down, −z up.
fn overhead() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 5.0, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        near: 0.1,
        far: 50.0,
        projection: Projection::Perspective { fov_y_deg: 40.0 },
        shift: Vec2::ZERO,
    }
}

#[test]
fn an_alpha_tested_leaf_is_cut_for_the_eye_and_the_light() {
    use kage::scene::light::LightKind;
    use kage::scene::{Material, Object};
    let camera = overhead();
    let mut scene = common::scene_with(shapes::plane(), camera, 200, 200, false);
    scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(10.0));
    scene.materials[0] =
        Material { kd: Vec3::new(0.8, 0.1, 0.1), ka: Vec3::new(0.8, 0.1, 0.1), ks: Vec3::ZERO, ..Material::default() };
    scene.lights[0].kind = LightKind::Directional { direction: Vec3::new(0.05, -1.0, 0.02).normalize() };
    let mut alpha = Texture::from_texels_8bit(2, 1, vec![[255, 255, 255, 0], [255, 255, 255, 255]], true);
    alpha.wrap = kage::scene::texture::Wrap::Clamp;
    scene.materials.push(Material {
        kd: Vec3::new(0.1, 0.8, 0.1),
        ka: Vec3::new(0.1, 0.8, 0.1),
        ks: Vec3::ZERO,
        two_sided: true,
        cutoff: Some(0.5),
        maps: kage::scene::ComponentMaps { alpha: Some(Arc::new(alpha)), ..Default::default() },
        ..Material::default()
    });
    let leaf = Affine3A::from_translation(Vec3::Y) * Affine3A::from_scale(Vec3::splat(2.0));
    scene.objects.push(Object::mesh("leaf", Arc::new(shapes::plane()), leaf, 1));
    // The raster frame, and the ray-traced reference (its rays cut alike).
    let frame = render(&scene, &RenderOptions::default()).unwrap().image;
    let options = kage::raytrace::reference::ReferenceOptions { pixel_samples: 1, ..Default::default() };
    let traced = kage::raytrace::reference::render_reference(&scene, &options, &|_| {});
    for (name, image) in [("raster", &frame), ("traced", &traced)] {
        let at = |x, y| image.get(x, y);
        let (open_floor, through_cut, kept) = (at(10, 100), at(60, 100), at(140, 100));
        assert!(through_cut.x > 4.0 * through_cut.y, "{name}: the floor shows through the cut: {through_cut}");
        let lit = (through_cut.x / open_floor.x - 1.0).abs() < 0.05;
        assert!(lit, "{name}: lit as the open floor: {through_cut} vs {open_floor}");
        assert!(kept.y > 4.0 * kept.x, "{name}: the kept half is the leaf: {kept}");
    }
}

/// OBJ's dissolve map (`map_d`) as the cut-out it draws in the files that
/// use one: a grey mask keeps the surface where it is light.
#[test]
fn an_obj_dissolve_map_cuts_where_its_grey_is_dark() {
    let dir = std::env::temp_dir().join(format!("kage-map-d-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mask = ::image::GrayImage::from_fn(2, 1, |x, _| ::image::Luma([if x == 0 { 0 } else { 255 }]));
    mask.save(dir.join("mask.png")).unwrap();
    std::fs::write(dir.join("leaf.mtl"), "newmtl leaf\nKd 0.2 0.8 0.2\nmap_d mask.png\n").unwrap();
    let obj = "mtllib leaf.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl leaf\nf 1/1 2/2 3/3\n";
    std::fs::write(dir.join("leaf.obj"), obj).unwrap();
    let fs = kage::scene::load::FileSystem { base: dir.clone() };
    let model = kage::scene::load::model(std::path::Path::new("leaf.obj"), &fs).unwrap();
    let m = model.parts[0].material.as_ref().unwrap();
    assert_eq!(m.cutoff, Some(0.5));
    assert!(m.cuts_out() && !m.translucent());
    assert!(!m.covers(Vec2::new(0.1, 0.5)) && m.covers(Vec2::new(0.9, 0.5)));
    std::fs::remove_dir_all(&dir).ok();
}

/// A roughness that varies over a texture (a glTF metallic-roughness map,
/// baked into the specular map's alpha) sets the Phong exponent texel by
/// texel: each half of a plane whose map is smooth on the left and rough
/// on the right is drawn as the same plane with that half's exponent
/// everywhere, and the two exponents' highlights differ there.
#[test]
fn a_roughness_map_sets_the_exponent_texel_by_texel() {
    use kage::scene::light::LightKind;
    use kage::scene::{phong_exponent, Material};
    let camera = overhead();
    let plane = |material: Material| {
        let mut scene = common::scene_with(shapes::plane(), camera, 200, 200, false);
        scene.objects[0].transform = Affine3A::from_scale(Vec3::splat(10.0));
        scene.lights[0].kind = LightKind::Directional { direction: Vec3::new(0.02, -1.0, 0.01).normalize() };
        scene.materials[0] = material;
        render(&scene, &RenderOptions::default()).unwrap().image
    };
    let base = Material { kd: Vec3::splat(0.3), ka: Vec3::splat(0.3), ks: Vec3::splat(0.6), ..Material::default() };
    // Roughness codes 64 (0.25) on the left half, 255 (1.0) on the right.
    let (smooth, rough) = (64u8, 255u8);
    let texels = (0..64 * 4).map(|i| [255, 255, 255, if i % 64 < 32 { smooth } else { rough }]).collect();
    let map = Arc::new(Texture::from_texels_8bit(64, 4, texels, true));
    let mapped = plane(Material {
        maps: kage::scene::ComponentMaps {
            specular: vec![Arc::clone(&map)],
            roughness: Some(map),
            ..Default::default()
        },
        ..base.clone()
    });
    let exponent = |code: u8| phong_exponent(f32::from(code) / 255.0);
    let constant = |code| plane(Material { shininess: exponent(code), ..base.clone() });
    let (smooth_plane, rough_plane) = (constant(smooth), constant(rough));
    assert!(exponent(smooth) > 100.0 && exponent(rough) == 1.0);
    // The seam lies at column 100; one texel is about 9 columns.
    let (mut left, mut right, mut apart) = (0.0f32, 0.0f32, 0.0f32);
    for y in (10..190).step_by(4) {
        for x in 10..88 {
            left = left.max((mapped.get(x, y) - smooth_plane.get(x, y)).abs().max_element());
            apart = apart.max((smooth_plane.get(x, y) - rough_plane.get(x, y)).abs().max_element());
        }
        for x in 112..190 {
            right = right.max((mapped.get(x, y) - rough_plane.get(x, y)).abs().max_element());
        }
    }
    assert!(apart > 0.05, "the two exponents' highlights differ by only {apart}");
    assert!(left < 2e-3 && right < 2e-3, "the smooth half is off by {left}, the rough half by {right}");
}

#[test]
fn a_translucent_surface_reads_its_texture_at_the_pixels_footprint_as_an_opaque_one_does() {
    // The checkered ground seen through itself at half opacity: each pixel
    // is half the background and half what the opaque ground shows there,
    // far texels filtered alike (read at the finest level, the far
    // checkers alias into noise and the two disagree).
    let alpha = 0.5;
    let mut opaque = checkered_ground(Filter::Trilinear);
    opaque.antialias = Antialias::None;
    let mut translucent = opaque.clone();
    translucent.materials[0].opacity = alpha;
    let (a, b) =
        (render(&opaque, &RenderOptions::default()).unwrap(), render(&translucent, &RenderOptions::default()).unwrap());
    let (mut worst, mut far) = (0.0f32, 0);
    for (i, (&o, &t)) in a.image.pixels().iter().zip(b.image.pixels()).enumerate() {
        if a.visibility.items()[i].is_none() {
            continue;
        }
        let expected = opaque.background * (1.0 - alpha) + o * alpha;
        worst = worst.max((t - expected).abs().max_element());
        far += usize::from(i < 55 * 160);
    }
    assert!(far > 500, "the ground runs to the horizon: {far} pixels above row 55");
    assert!(worst < 1e-3, "largest difference from the blend of the opaque image: {worst}");
}
