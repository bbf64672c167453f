//! Watertightness: random triangulations of a rectangle covering the image cover
//! every pixel exactly once (scan converter), and leave no hole through the whole
//! pipeline, near-plane clipping included.

mod common;

use common::{cast, scene_with};
use glam::{DVec2, Vec3};
use kage::camera::{Camera, Projection};
use kage::scene::mesh::NormalMode;
use kage::scene::Mesh;
use kage::visibility::scan::{scan_triangle, FixedPoint, ONE};
use kage::visibility::{rasterize, VisibilityBuffer};
use proptest::prelude::*;

/// Triangulates the rectangle `lo..hi` by inserting `points` one by one, each
/// splitting the triangle that contains it into three (points too close to an
/// existing edge are skipped). Triangles are counter-clockwise with y up.
fn triangulate(lo: DVec2, hi: DVec2, points: &[DVec2]) -> (Vec<DVec2>, Vec<[usize; 3]>) {
    let mut v = vec![lo, DVec2::new(hi.x, lo.y), hi, DVec2::new(lo.x, hi.y)];
    let mut tris = vec![[0, 1, 2], [0, 2, 3]];
    let cross = |a: DVec2, b: DVec2, p: DVec2| (b - a).perp_dot(p - a);
    for &p in points {
        let found = tris.iter().position(|t| (0..3).all(|k| cross(v[t[k]], v[t[(k + 1) % 3]], p) > 1e-3));
        let Some(i) = found else { continue };
        let [a, b, c] = tris[i];
        v.push(p);
        let n = v.len() - 1;
        tris[i] = [a, b, n];
        tris.push([b, c, n]);
        tris.push([c, a, n]);
    }
    (v, tris)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn every_pixel_is_covered_exactly_once(
        points in prop::collection::vec((-3.0f64..67.0, -3.0f64..51.0), 1..120),
        wiggle in (0.0f64..1.0, 0.0f64..1.0),
    ) {
        let (w, h) = (64i64, 48i64);
        let pts: Vec<DVec2> = points.iter().map(|&(x, y)| DVec2::new(x, y)).collect();
        let lo = DVec2::new(-4.0 - wiggle.0, -4.0 - wiggle.1);
        let (v, tris) = triangulate(lo, DVec2::new(w as f64 + 4.3, h as f64 + 4.7), &pts);
        let fixed: Vec<FixedPoint> = v.iter().map(|p| FixedPoint { x: (p.x * ONE as f64).round() as i64, y: (p.y * ONE as f64).round() as i64 }).collect();
        let mut count = vec![0u32; (w * h) as usize];
        for t in &tris {
            scan_triangle(&t.map(|i| fixed[i]), 0..h, &mut |y: i64, x0: i64, x1: i64| {
                for x in x0.max(0)..x1.min(w) {
                    count[(y * w + x) as usize] += 1;
                }
            });
        }
        let bad: Vec<usize> = (0..count.len()).filter(|&i| count[i] != 1).collect();
        prop_assert!(bad.is_empty(), "{} pixels not covered exactly once, first at {:?} (count {})",
            bad.len(), bad.first().map(|&i| (i as i64 % w, i as i64 / w)), bad.first().map_or(0, |&i| count[i]));
    }
}

/// A randomly triangulated square of side 40 × `scale` in the XZ plane, front face up.
fn ground(seed: u64, scale: f64) -> Mesh {
    let mut s = seed;
    let mut rnd = || {
        s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        (s >> 11) as f64 / (1u64 << 53) as f64
    };
    let pts: Vec<DVec2> = (0..300).map(|_| DVec2::new(rnd() * 40.0 - 20.0, rnd() * 40.0 - 20.0) * scale).collect();
    let (v, tris) = triangulate(DVec2::splat(-20.0 * scale), DVec2::splat(20.0 * scale), &pts);
    // (x, y) of the 2-D triangulation → (x, 0, −y): counter-clockwise seen from +y.
    let positions = v.iter().map(|p| Vec3::new(p.x as f32, 0.0, -p.y as f32)).collect();
    let triangles = tris.iter().map(|t| t.map(|i| i as u32)).collect();
    Mesh::new(positions, vec![], vec![], triangles, NormalMode::Flat).unwrap().0
}

/// The camera stands on a huge triangulated ground, so many triangles cross the
/// near plane and lie partly behind the eye. Every pixel the ray caster says sees
/// the ground must be covered by the rasterizer, by the same triangle (up to
/// pixel centres on shared edges), and no other pixel — also when the ground is a
/// hundred million times larger than the view (clipping precision).
#[test]
fn ground_through_the_near_plane_has_no_holes_and_matches_rays() {
    for (seed, projection, scale) in [
        (1, Projection::Perspective { fov_y_deg: 70.0 }, 1.0),
        (2, Projection::Perspective { fov_y_deg: 40.0 }, 1.0),
        (3, Projection::Orthographic { height: 3.0 }, 1.0),
        (4, Projection::Perspective { fov_y_deg: 60.0 }, 1e8),
    ] {
        let camera = Camera {
            eye: Vec3::new(0.3, 0.8, 2.0),
            target: Vec3::new(0.0, 0.0, -3.0),
            up: Vec3::Y,
            near: 0.5,
            far: 100.0,
            projection,
            shift: glam::Vec2::ZERO,
        };
        let scene = scene_with(ground(seed, scale), camera, 120, 90, false);
        let mut vb = VisibilityBuffer::new(scene.width, scene.height);
        let stats = rasterize(&scene, &mut vb);
        assert!(stats.clipped > 0, "the test must exercise near-plane clipping");
        let (mut holes, mut extra, mut other, mut seen) = (0, 0, 0, 0);
        for y in 0..scene.height {
            for x in 0..scene.width {
                match (cast(&scene, x, y), vb.item(x, y)) {
                    (Some(_), it) if it.is_none() => holes += 1,
                    (None, it) if !it.is_none() => extra += 1,
                    (Some(h), it) if it.triangle != h.triangle => other += 1,
                    _ => {}
                }
                seen += usize::from(!vb.item(x, y).is_none());
            }
        }
        assert!(seen > 2000, "seed {seed}: the ground must fill much of the image");
        assert_eq!((holes, extra), (0, 0), "seed {seed}: pixels missed / drawn outside the ground");
        assert!(other * 200 < seen, "seed {seed}: {other} pixels show a different triangle than the ray");
    }
}
