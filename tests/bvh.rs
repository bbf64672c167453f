//! The BVH against brute force: on random triangle soups and random rays, the
//! nearest hit and the any-hit answer are what testing every triangle gives.

mod common;

use glam::Vec3;
use kage::raytrace::triangle::ShearedRay;
use kage::raytrace::TraceScene;
use kage::scene::Ray;
use kage::visibility::ItemId;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn soup(rng: &mut StdRng, n: usize) -> TraceScene {
    let mesh = common::triangle_soup(rng, n);
    let tris: Vec<[Vec3; 3]> = mesh.triangles.iter().map(|t| t.map(|i| mesh.positions[i as usize])).collect();
    let items = (0..tris.len() as u32).map(|t| ItemId { object: 0, triangle: t }).collect();
    TraceScene::from_triangles(tris, items)
}

fn random_ray(rng: &mut StdRng) -> Ray {
    let o = Vec3::new(rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0));
    let target = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
    Ray { origin: o, dir: (target - o).normalize() }
}

fn brute(scene: &TraceScene, ray: &Ray, t_max: f32) -> Option<(f32, usize)> {
    let sr = ShearedRay::new(ray);
    (0..scene.len())
        .filter_map(|i| sr.intersect(scene.triangle(i), 0.0, t_max).map(|(t, _)| (t, i)))
        .min_by(|a, b| a.0.total_cmp(&b.0))
}

#[test]
fn nearest_and_any_hits_match_brute_force() {
    let mut rng = StdRng::seed_from_u64(3);
    let (mut hits, mut rays) = (0, 0);
    for n in [1, 7, 100, 1000, 6000] {
        let scene = soup(&mut rng, n);
        for _ in 0..2000 {
            let ray = random_ray(&mut rng);
            let t_max = if rng.gen_bool(0.3) { rng.gen_range(0.5..4.0) } else { f32::INFINITY };
            let want = brute(&scene, &ray, t_max);
            let got = scene.intersect(&ray, t_max);
            rays += 1;
            match (want, got) {
                (None, None) => {}
                (Some((t, i)), Some(h)) => {
                    hits += 1;
                    assert_eq!(h.t, t, "n {n}: distance");
                    // Equal distances (coplanar overlaps) may pick either triangle.
                    let same = h.item.triangle as usize == i || brute(&scene, &ray, t).is_none();
                    assert!(same, "n {n}: triangle {} vs {i}", h.item.triangle);
                }
                (w, g) => panic!("n {n}: brute force {w:?}, BVH {g:?}"),
            }
            assert_eq!(scene.occluded(&ray, t_max), want.is_some(), "n {n}: occluded");
        }
    }
    assert!(hits > rays / 4, "the rays must hit something often enough to mean anything: {hits}/{rays}");
}

#[test]
fn empty_scene_hits_nothing() {
    let scene = TraceScene::from_triangles(Vec::new(), Vec::new());
    let ray = Ray { origin: Vec3::ZERO, dir: Vec3::Z };
    assert!(scene.intersect(&ray, f32::INFINITY).is_none() && !scene.occluded(&ray, f32::INFINITY));
}
