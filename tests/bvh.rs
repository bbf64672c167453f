//! The BVH against brute force: on random triangle soups and random rays, the
//! nearest hit and the any-hit answer are what testing every triangle gives.

mod common;

use glam::Vec3;
use kage::camera::Ray;
use kage::raytrace::TraceScene;
use kage::triangle::ShearedRay;
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
        .filter_map(|i| sr.intersect(&scene.triangle(i), 0.0, t_max).map(|(t, _)| (t, i)))
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

/// Leaves past eight triangles (many with one centre: the build cannot split
/// them) and the same triangle many times over: still the brute-force answer.
#[test]
fn crowded_leaves_match_brute_force() {
    let mut rng = StdRng::seed_from_u64(5);
    let mut tris: Vec<[Vec3; 3]> = Vec::new();
    for k in 0..300 {
        // Triangles turned about one centre, and 40 copies of one triangle.
        let a = k as f32 * 0.37;
        let (c, s) = (a.cos(), a.sin());
        tris.push([Vec3::new(c, s, 0.1 * c), Vec3::new(-c, -s, -0.1 * c), Vec3::new(-s, c, 0.2)]);
    }
    tris.extend(std::iter::repeat_n(
        [Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.5)],
        40,
    ));
    let items = (0..tris.len() as u32).map(|t| ItemId { object: 0, triangle: t }).collect();
    let scene = TraceScene::from_triangles(tris, items);
    let mut hits = 0;
    for _ in 0..3000 {
        let ray = random_ray(&mut rng);
        let want = brute(&scene, &ray, f32::INFINITY);
        let got = scene.intersect(&ray, f32::INFINITY);
        assert_eq!(want.map(|w| w.0), got.map(|h| h.t), "distance");
        if let (Some((t, i)), Some(h)) = (want, got) {
            hits += 1;
            let same = h.item.triangle as usize == i || brute(&scene, &ray, t).is_none();
            assert!(same, "triangle {} vs {i}", h.item.triangle);
        }
        assert_eq!(scene.occluded(&ray, f32::INFINITY), want.is_some());
    }
    assert!(hits > 300, "{hits}");
}

/// Packets of rays walked together find each ray's brute-force hit: coherent
/// packets (eight rays from one eye through a small patch, as a pixel
/// block's primary rays are), incoherent ones (random origins and
/// directions), and packets of one to seven rays, with and without a
/// distance limit.
#[test]
fn packets_find_each_rays_brute_force_hit() {
    let mut rng = StdRng::seed_from_u64(17);
    let (mut hits, mut rays) = (0, 0);
    for n in [1, 30, 1000, 6000] {
        let scene = soup(&mut rng, n);
        for round in 0..400 {
            let size = if round % 3 == 0 { rng.gen_range(1..=8) } else { 8 };
            let packet: Vec<Ray> = if round % 2 == 0 {
                let eye = random_ray(&mut rng).origin;
                let aim = Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
                let step = rng.gen_range(0.001..0.2);
                (0..size)
                    .map(|k| {
                        let p = aim + Vec3::new((k % 4) as f32, (k / 4) as f32, 0.0) * step;
                        Ray { origin: eye, dir: (p - eye).normalize() }
                    })
                    .collect()
            } else {
                (0..size).map(|_| random_ray(&mut rng)).collect()
            };
            let t_max = if rng.gen_bool(0.3) { rng.gen_range(0.5..4.0) } else { f32::INFINITY };
            let got = scene.intersect_packet(&packet, t_max);
            assert!(got[size..].iter().all(Option::is_none), "lanes past the packet hit nothing");
            for (ray, got) in packet.iter().zip(got) {
                rays += 1;
                match (brute(&scene, ray, t_max), got) {
                    (None, None) => {}
                    (Some((t, i)), Some(h)) => {
                        hits += 1;
                        assert_eq!(h.t.to_bits(), t.to_bits(), "n {n}: distance");
                        if let Some(one) = scene.intersect(ray, t_max).filter(|one| one.item == h.item) {
                            assert_eq!(one, h, "n {n}: the packet's hit is the ray's own");
                        }
                        let same = h.item.triangle as usize == i || brute(&scene, ray, t).is_none();
                        assert!(same, "n {n}: triangle {} vs {i}", h.item.triangle);
                    }
                    (w, g) => panic!("n {n}, round {round}: brute force {w:?}, packet {g:?}"),
                }
            }
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

/// Seed 002 §4's premise: the item buffer's primary hits are the BVH's traced
/// primary hits — same triangle, same distance — on ≥ 99.9% of covered pixels of
/// random scenes.
#[test]
fn item_buffer_primary_hits_equal_traced_primary_hits() {
    use kage::shading::ObjectFrames;
    use kage::visibility::{rasterize, VisibilityBuffer};
    let mut rng = StdRng::seed_from_u64(11);
    let (mut covered, mut same) = (0usize, 0usize);
    for seed in 0..8 {
        let mesh = common::triangle_soup(&mut rng, 40);
        let mut camera = common::random_camera(&mut rng, seed % 4 == 3);
        camera.near = 0.05; // the traced rays start at the eye and never end
        camera.far = 1000.0;
        let scene = common::scene_with(mesh, camera, 160, 120, true);
        let mut vb = VisibilityBuffer::new(scene.width, scene.height);
        rasterize(&scene, &mut vb);
        let trace = TraceScene::new(&scene);
        let frames = ObjectFrames::new(&scene);
        let rays = scene.camera.pixel_rays(glam::Vec2::new(scene.width as f32, scene.height as f32));
        for y in 0..scene.height {
            for x in 0..scene.width {
                let ray = rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
                let item = vb.item(x, y);
                let traced = trace.intersect(&ray, scene.camera.far);
                if item.is_none() && traced.is_none() {
                    continue;
                }
                covered += 1;
                let (Some(hit), false) = (traced, item.is_none()) else { continue };
                let t = frames.prepare(&scene, item).surface(&ray).position.distance(ray.origin);
                same += usize::from(hit.item == item && ((hit.t - t) / t).abs() < 1e-5);
            }
        }
    }
    assert!(covered > 20_000, "{covered}");
    assert!(same as f64 >= 0.999 * covered as f64, "{same} of {covered} pixels agree");
}
