//! Texture filtering against a supersampled truth: on a finely checkered ground
//! running to the horizon, mipmapped trilinear filtering comes much closer to the
//! average of 64 jittered bilinear frames than bilinear sampling does. An
//! image several materials name is decoded once.

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
