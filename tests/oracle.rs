//! The rasterizer against an independent brute-force ray caster: for random
//! triangle soups and random cameras, the item id of every pixel must be what the
//! ray through the pixel centre hits first, and the depth must match.

mod common;

use common::{cast, random_camera, scene_with, triangle_soup, view_distance};
use kage::visibility::{rasterize, VisibilityBuffer};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

struct Tally {
    covered: usize,
    mismatched: usize,
    excused: usize,
    worst_depth_error: f32,
}

fn compare(seed: u64, ortho: bool, tally: &mut Tally) {
    let mut rng = StdRng::seed_from_u64(seed);
    let n = rng.gen_range(5..60);
    let two_sided = rng.gen_bool(0.5);
    let scene = scene_with(triangle_soup(&mut rng, n), random_camera(&mut rng, ortho), 160, 120, two_sided);
    let mut vb = VisibilityBuffer::new(scene.width, scene.height);
    rasterize(&scene, &mut vb);
    for y in 0..scene.height {
        for x in 0..scene.width {
            let got = vb.item(x, y);
            let want = cast(&scene, x, y);
            if got.is_none() && want.is_none() {
                continue;
            }
            tally.covered += 1;
            match want {
                Some(h) if !got.is_none() && got.triangle == h.triangle => {
                    let e = (view_distance(&scene.camera, vb.depth(x, y)) - h.view_z).abs() / h.view_z;
                    tally.worst_depth_error = tally.worst_depth_error.max(e);
                }
                Some(h) if (h.second_z - h.view_z) / h.view_z < 1e-4 => tally.excused += 1,
                _ => tally.mismatched += 1,
            }
        }
    }
}

#[test]
fn item_ids_and_depths_match_a_brute_force_ray_cast() {
    let mut tally = Tally { covered: 0, mismatched: 0, excused: 0, worst_depth_error: 0.0 };
    for seed in 0..24 {
        compare(seed, seed % 3 == 2, &mut tally);
    }
    let share = tally.mismatched as f64 / tally.covered as f64;
    eprintln!(
        "covered {} mismatched {} ({:.4}%) excused {} worst relative depth error {:.2e}",
        tally.covered,
        tally.mismatched,
        100.0 * share,
        tally.excused,
        tally.worst_depth_error
    );
    assert!(tally.covered > 50_000, "the soups must cover enough pixels to mean something");
    assert!(share < 0.001, "{} of {} covered pixels disagree with the ray cast", tally.mismatched, tally.covered);
    assert!(tally.worst_depth_error < 1e-4, "depth off by {:.2e} relative", tally.worst_depth_error);
}
