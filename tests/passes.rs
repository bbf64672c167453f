//! Multi-pass rendering (seed 002 eq. 4/5): the component passes, written out on
//! their own, sum to the final image.

use std::path::Path;

use glam::Vec3;
use kage::scene::Antialias;
use kage::shading::{Component, ComponentSet};
use kage::{render, RenderOptions};

fn example(name: &str) -> kage::Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes").join(name);
    let mut scene = kage::scene::file::load_scene(&path).unwrap();
    (scene.width, scene.height) = (192, 108);
    scene
}

#[test]
fn component_images_sum_to_the_final_image() {
    for (name, antialias) in [
        ("reflections.toml", Antialias::None),
        ("spotlights.toml", Antialias::None),
        ("demo.toml", Antialias::Jitter(4)),
        ("showroom.toml", Antialias::Edge(kage::scene::EdgeMode::default())),
        ("environment.toml", Antialias::None),
    ] {
        let mut scene = example(name);
        scene.antialias = antialias;
        if name == "spotlights.toml" {
            let mode = kage::scene::FogMode::Exp2 { density: 0.12 };
            scene.fog = Some(kage::scene::Fog { mode, color: Vec3::new(0.3, 0.3, 0.35) });
        }
        let options = RenderOptions { aovs: ComponentSet::ALL, ..RenderOptions::default() };
        let frame = render(&scene, &options).unwrap();
        assert_eq!(frame.aovs.iter().map(|(c, _)| *c).collect::<Vec<_>>(), Component::ALL.to_vec());
        let mut nonzero = [0usize; Component::ALL.len()];
        for (i, p) in frame.image.pixels().iter().enumerate() {
            let sum: Vec3 = frame.aovs.iter().map(|(_, a)| a.pixels()[i]).sum();
            assert!(
                (sum - *p).abs().max_element() <= 1e-5 * p.max_element().max(1.0),
                "{name} pixel {i}: {sum} vs {p}"
            );
            for (k, (_, a)) in frame.aovs.iter().enumerate() {
                nonzero[k] += usize::from(a.pixels()[i].max_element() > 1e-4);
            }
        }
        // Every component shows up where the scene has it: reflections.toml and
        // environment.toml trace, only spotlights.toml (here) has fog, only
        // environment.toml a reflection map. showroom.toml is antialiased by the edge
        // pass, whose blends are applied to every component alike.
        for (k, c) in Component::ALL.iter().enumerate() {
            let expect = match c {
                Component::Traced => ["reflections.toml", "environment.toml", "showroom.toml"].contains(&name),
                Component::Fog => name == "spotlights.toml",
                Component::Reflection => name == "environment.toml",
                Component::Emission => name != "showroom.toml", // nothing glows there
                _ => true,
            };
            assert_eq!(nonzero[k] > 20, expect, "{name}: {} component has {} pixels", c.name(), nonzero[k]);
        }
        // The final image is the same with or without AOVs.
        let plain = render(&scene, &RenderOptions::default()).unwrap();
        assert_eq!(plain.image, frame.image, "{name}: AOVs change the image");
    }
}

/// A component with two maps is two passes added (§3.2): Kd·(A + B) = Kd·A + Kd·B.
#[test]
fn two_maps_on_a_component_add_like_two_passes() {
    use std::sync::Arc;
    let checker = |a: f32, b: f32| {
        let texels = (0..16).map(|i| Vec3::splat(if (i % 4 + i / 4) % 2 == 0 { a } else { b })).collect();
        Arc::new(kage::scene::Texture::from_texels(4, 4, texels))
    };
    let (a, b) = (checker(0.2, 0.7), checker(0.5, 0.1));
    let mut scene = example("demo.toml");
    scene.antialias = kage::scene::Antialias::None;
    scene.lights.iter_mut().for_each(|l| l.ambient = 0.0);
    let with = |maps: Vec<Arc<kage::scene::Texture>>| {
        let mut s = scene.clone();
        for m in &mut s.materials {
            (m.ks, m.ke, m.maps.ambient, m.maps.diffuse) = (Vec3::ZERO, Vec3::ZERO, Vec::new(), maps.clone());
        }
        render(&s, &RenderOptions::default()).unwrap()
    };
    let (both, only_a, only_b) = (with(vec![a.clone(), b.clone()]), with(vec![a]), with(vec![b]));
    for (i, item) in both.visibility.items().iter().enumerate() {
        if !item.is_none() {
            let (p, q) = (both.image.pixels()[i], only_a.image.pixels()[i] + only_b.image.pixels()[i]);
            assert!((p - q).abs().max_element() < 1e-5, "pixel {i}: {p} vs {q}");
        }
    }
}
