//! CSG solids: the ray caster's spans agree with point membership.
//!
//! Random solids — spheres, cones, frustums, cylinders and convex polyhedra under
//! random affine maps (rotation, shear, non-uniform scale), joined by random
//! unions, intersections and differences — and random rays: at sample points
//! along each ray, "inside a span" (interval arithmetic along the tree) must equal
//! "inside the solid" (each primitive's own point test, combined by the tree).

use glam::{Affine3A, Mat3, Vec3, Vec4};
use kage::camera::Ray;
use kage::csg::{first_hit, primitive_span, spans, ConvexPolyhedron, Crossing, CsgSolid, CsgTree, Primitive, Shape};
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};

fn random_shape(rng: &mut StdRng) -> Shape {
    match rng.gen_range(0..4) {
        0 => Shape::Sphere,
        1 => {
            // Cylinder, cone either way up, or frustum; the larger radius is 1.
            let small = [0.0, 1.0, rng.gen_range(0.1..0.9)][rng.gen_range(0..3)];
            if rng.gen_bool(0.5) {
                Shape::Frustum { bottom: 1.0, top: small }
            } else {
                Shape::Frustum { bottom: small, top: 1.0 }
            }
        }
        2 => Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
        _ => {
            // A tetrahedron: four planes through the faces of (0,0,0), x, y, z.
            let n = Vec3::ONE.normalize();
            let planes = vec![(-Vec3::X).extend(0.0), (-Vec3::Y).extend(0.0), (-Vec3::Z).extend(0.0), n.extend(n.x)];
            Shape::Polyhedron(ConvexPolyhedron { planes, vertices: vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z] })
        }
    }
}

fn random_transform(rng: &mut StdRng) -> Affine3A {
    let mut v = || Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0));
    let (axis, shear, offset) = (v().normalize_or(Vec3::Z), v() * 0.3, v() * 1.5);
    let rotation = Mat3::from_axis_angle(axis, rng.gen_range(0.0..std::f32::consts::TAU));
    let scale =
        Mat3::from_diagonal(Vec3::new(rng.gen_range(0.4..1.5), rng.gen_range(0.4..1.5), rng.gen_range(0.4..1.5)));
    let shear = Mat3::from_cols(Vec3::X, Vec3::new(shear.x, 1.0, 0.0), Vec3::new(shear.y, shear.z, 1.0));
    Affine3A::from_mat3_translation(rotation * shear * scale, offset)
}

fn random_primitive(rng: &mut StdRng) -> Primitive {
    Primitive { shape: random_shape(rng), transform: random_transform(rng), color: None, source: 0..0 }
}

fn random_tree(rng: &mut StdRng, prims: &mut Vec<Primitive>, depth: u32) -> CsgTree {
    if depth == 0 || rng.gen_bool(0.3) {
        prims.push(random_primitive(rng));
        return CsgTree::Leaf(prims.len() - 1);
    }
    let kids: Vec<CsgTree> = (0..rng.gen_range(2..4)).map(|_| random_tree(rng, prims, depth - 1)).collect();
    match rng.gen_range(0..3) {
        0 => CsgTree::Union(kids),
        1 => CsgTree::Intersection(kids),
        _ => {
            let mut kids = kids.into_iter();
            let first = kids.next().expect("two or more");
            CsgTree::Difference(Box::new(first), kids.collect())
        }
    }
}

#[test]
fn spans_agree_with_point_membership_on_random_solids() {
    let mut rng = StdRng::seed_from_u64(6);
    let (mut checked, mut hits) = (0, 0);
    for _ in 0..300 {
        let mut prims = Vec::new();
        let tree = random_tree(&mut rng, &mut prims, 3);
        let solid = CsgSolid { primitives: prims, tree: Some(tree) };
        for _ in 0..20 {
            let origin = Vec3::new(rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..6.0), rng.gen_range(-6.0..6.0));
            let target = Vec3::new(rng.gen_range(-1.5..1.5), rng.gen_range(-1.5..1.5), rng.gen_range(-1.5..1.5));
            let ray = Ray { origin, dir: (target - origin).normalize() };
            let inside_spans = spans(&solid, &ray);
            hits += usize::from(!inside_spans.is_empty());
            // Every primitive's boundary along the ray: samples near one are
            // ambiguous (and a difference widens its cutter there on purpose).
            let borders: Vec<f32> = (0..solid.primitives.len())
                .filter_map(|i| primitive_span(&solid.primitives[i], i, &ray))
                .flat_map(|s| [s.enter.t, s.exit.t])
                .collect();
            for k in 0..200 {
                let t = k as f32 * 0.1;
                if borders.iter().any(|b| (b - t).abs() < 1e-3) {
                    continue;
                }
                let by_spans = inside_spans.iter().any(|s| s.enter.t < t && t < s.exit.t);
                let by_points = solid.contains(ray.origin + ray.dir * t);
                assert_eq!(by_spans, by_points, "t = {t}, spans {inside_spans:?}, solid {solid:?}, ray {ray:?}");
                checked += 1;
            }
            // Spans are sorted, disjoint and non-empty; the first hit is the first entry.
            assert!(inside_spans.windows(2).all(|w| w[0].exit.t <= w[1].enter.t));
            assert!(inside_spans.iter().all(|s| s.enter.t < s.exit.t));
            let first = first_hit(&solid, &ray, 0.0, f32::INFINITY).map(|c| c.t);
            let expected = inside_spans.iter().flat_map(|s| [s.enter.t, s.exit.t]).find(|&t| t > 0.0);
            assert_eq!(first, expected);
        }
    }
    assert!(hits > 1000, "only {hits} rays met a solid");
    eprintln!("{checked} sample points agree");
}

#[test]
fn a_union_seen_from_inside_one_part_is_left_where_the_union_ends() {
    // Two overlapping unit balls at x = 0 and x = 1.5, and a third apart at
    // x = 6: from inside the first, the union's first surface is where the
    // second ends (x = 2.5), not where the first does; from outside, the
    // nearest entry.
    let ball = |x: f32| Primitive {
        shape: Shape::Sphere,
        transform: Affine3A::from_translation(Vec3::new(x, 0.0, 0.0)),
        color: None,
        source: 0..0,
    };
    let union = |order: [usize; 3]| CsgSolid {
        primitives: vec![ball(0.0), ball(1.5), ball(6.0)],
        tree: Some(CsgTree::Union(order.iter().map(|&i| CsgTree::Leaf(i)).collect())),
    };
    let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
    for order in [[0, 1, 2], [2, 1, 0], [1, 2, 0]] {
        let solid = union(order);
        let inside = Ray { origin: Vec3::new(0.2, 0.0, 0.0), dir: Vec3::X };
        let hit = first_hit(&solid, &inside, 0.0, f32::INFINITY).unwrap();
        assert!(near(hit.t, 2.3) && hit.primitive == 1, "{order:?}: {hit:?}");
        let outside = Ray { origin: Vec3::new(-3.0, 0.0, 0.0), dir: Vec3::X };
        let hit = first_hit(&solid, &outside, 0.0, f32::INFINITY).unwrap();
        assert!(near(hit.t, 2.0) && hit.primitive == 0, "{order:?}: {hit:?}");
        let between = Ray { origin: Vec3::new(3.0, 0.0, 0.0), dir: Vec3::X };
        let hit = first_hit(&solid, &between, 0.0, f32::INFINITY).unwrap();
        assert!(near(hit.t, 2.0) && hit.primitive == 2, "{order:?}: {hit:?}");
    }
}

#[test]
fn normals_point_out_of_the_solid_and_hole_walls_are_marked_cut() {
    // A unit ball with a cylinder bored along z: a ray along x through the centre
    // enters the ball (normal −x), leaves into the hole through its wall (normal
    // +x towards the hole, marked cut), and so on.
    let ball = Primitive { shape: Shape::Sphere, transform: Affine3A::IDENTITY, color: None, source: 0..0 };
    let bore = Primitive {
        shape: Shape::Frustum { bottom: 1.0, top: 1.0 },
        transform: Affine3A::from_scale_rotation_translation(
            Vec3::new(0.3, 0.3, 4.0),
            glam::Quat::IDENTITY,
            Vec3::new(0.0, 0.0, -2.0),
        ),
        color: None,
        source: 0..0,
    };
    let solid = CsgSolid {
        primitives: vec![ball, bore],
        tree: Some(CsgTree::Difference(Box::new(CsgTree::Leaf(0)), vec![CsgTree::Leaf(1)])),
    };
    let ray = Ray { origin: Vec3::new(-3.0, 0.0, 0.0), dir: Vec3::X };
    let s = spans(&solid, &ray);
    assert_eq!(s.len(), 2, "{s:?}");
    let near = |a: f32, b: f32| (a - b).abs() < 1e-5;
    assert!(near(s[0].enter.t, 2.0) && s[0].enter.normal.abs_diff_eq(-Vec3::X, 1e-5) && !s[0].enter.cut);
    assert!(near(s[0].exit.t, 2.7) && s[0].exit.normal.abs_diff_eq(Vec3::X, 1e-5) && s[0].exit.cut);
    assert!(near(s[1].enter.t, 3.3) && s[1].enter.normal.abs_diff_eq(-Vec3::X, 1e-5) && s[1].enter.cut);
    assert!(near(s[1].exit.t, 4.0) && s[1].exit.normal.abs_diff_eq(Vec3::X, 1e-5) && !s[1].exit.cut);
    // A cutter flush with a face removes the face: a box minus a box sharing its top.
    let cube = |lo: Vec3, size: Vec3| Primitive {
        shape: Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
        transform: Affine3A::from_scale_rotation_translation(size, glam::Quat::IDENTITY, lo),
        color: Some(Vec4::ONE),
        source: 0..0,
    };
    let solid = CsgSolid {
        primitives: vec![cube(Vec3::ZERO, Vec3::splat(2.0)), cube(Vec3::new(0.5, 0.5, 1.0), Vec3::new(1.0, 1.0, 1.0))],
        tree: Some(CsgTree::Difference(Box::new(CsgTree::Leaf(0)), vec![CsgTree::Leaf(1)])),
    };
    let down = Ray { origin: Vec3::new(1.0, 1.0, 5.0), dir: -Vec3::Z };
    let hit = first_hit(&solid, &down, 0.0, f32::INFINITY).unwrap();
    assert!(near(hit.t, 4.0) && hit.cut && hit.normal.abs_diff_eq(Vec3::Z, 1e-5), "the pocket's floor: {hit:?}");
}

/// A camera looking at the origin from a random direction: every fourth
/// round orthographic; every fifth from inside the solids' reach, so that
/// primitives straddle the eye.
fn random_camera(rng: &mut StdRng, round: usize) -> kage::camera::Camera {
    use kage::camera::{Camera, Projection};
    let dir =
        Vec3::new(rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0), rng.gen_range(-1.0..1.0)).normalize_or(Vec3::Z);
    let projection = if round % 4 == 3 {
        Projection::Orthographic { height: 6.0 }
    } else {
        Projection::Perspective { fov_y_deg: rng.gen_range(30.0..70.0) }
    };
    let distance = if round % 5 == 4 { 1.0 } else { rng.gen_range(5.0..9.0) };
    Camera {
        eye: dir * distance,
        target: Vec3::ZERO,
        up: if dir.y.abs() > 0.9 { Vec3::X } else { Vec3::Y },
        near: 0.05,
        far: 100.0,
        projection,
        shift: glam::Vec2::ZERO,
    }
}

/// A pixel's column and row, what the scanline walk shows there, and what a
/// ray cast at the whole solid first meets.
type PixelBesideRay = ((u32, u32), Option<Crossing>, Option<Crossing>);

/// Each pixel of a `w` x `h` frame of `solid` seen by `camera`, the ray
/// cast beyond the near plane.
fn walk_beside_rays(solid: &CsgSolid, camera: &kage::camera::Camera, (w, h): (u32, u32)) -> Vec<PixelBesideRay> {
    let scanned = kage::visibility::solids::scan_solid(solid, camera, w, h);
    let rays = camera.pixel_rays(glam::Vec2::new(w as f32, h as f32));
    let pixel = |(x, y): (u32, u32)| {
        let ray = rays.ray(glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5));
        let near = camera.distance_at_depth(&ray, 1.0);
        ((x, y), scanned[(y * w + x) as usize], first_hit(solid, &ray, near, f32::INFINITY))
    };
    (0..h).flat_map(|y| (0..w).map(move |x| (x, y))).map(pixel).collect()
}

#[test]
fn the_scanline_walk_finds_what_a_ray_per_pixel_finds() {
    let mut rng = StdRng::seed_from_u64(3);
    let (w, h) = (96u32, 64u32);
    let (mut pixels, mut covered) = (0, 0);
    for round in 0..40 {
        let mut prims = Vec::new();
        let tree = random_tree(&mut rng, &mut prims, 3);
        let solid = CsgSolid { primitives: prims, tree: Some(tree) };
        let camera = random_camera(&mut rng, round);
        // The paper's pattern matrix finds the same surfaces.
        let method = kage::visibility::solids::CsgMethod::PatternMatrix { limit: 100_000 };
        let expanded = kage::visibility::solids::scan_solid_with(&solid, &camera, w, h, method).unwrap();
        // (The walk clips at the near plane, as the polygon pass does.)
        for ((x, y), got, cast) in walk_beside_rays(&solid, &camera, (w, h)) {
            let paper = expanded[(y * w + x) as usize];
            assert_eq!(
                got.map(|c| c.primitive),
                paper.map(|c| c.primitive),
                "({x}, {y}) round {round}: pattern matrix"
            );
            if let (Some(a), Some(b)) = (got, paper) {
                assert!((a.t - b.t).abs() <= 1e-5 * a.t.abs().max(1.0), "({x}, {y}): {a:?} vs {b:?}");
            }
            pixels += 1;
            covered += usize::from(cast.is_some());
            match (got, cast) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!(a.primitive, b.primitive, "({x}, {y}) round {round}");
                    assert!((a.t - b.t).abs() <= 1e-4 * b.t.abs().max(1.0), "({x}, {y}): {a:?} vs {b:?}");
                }
                _ => panic!("({x}, {y}) round {round}: scanline {got:?}, ray {cast:?}"),
            }
        }
    }
    assert!(covered * 20 > pixels, "only {covered} of {pixels} pixels show a solid");
}

/// A part of a few primitives cut by many, some far from it, some through it,
/// some through two of its primitives at once: the walk (which leaves each
/// cutter out wherever the ray misses the region its box shares with a box of
/// the part's primitives) shows at every pixel what a ray cast at the whole
/// solid shows.
#[test]
fn a_cutter_left_out_where_it_cannot_meet_its_part_changes_no_pixel() {
    let mut rng = StdRng::seed_from_u64(41);
    let (w, h) = (96u32, 64u32);
    let (mut covered, mut cut) = (0, 0);
    for round in 0..40 {
        let parts = rng.gen_range(1..4);
        let cutters = rng.gen_range(4..14);
        let mut primitives: Vec<Primitive> = (0..parts + cutters).map(|_| random_primitive(&mut rng)).collect();
        for p in &mut primitives[parts..] {
            // Smaller, and spread wider than the part.
            let at = Vec3::new(rng.gen_range(-2.5..2.5), rng.gen_range(-2.5..2.5), rng.gen_range(-2.5..2.5));
            p.transform = Affine3A::from_mat3_translation(Mat3::from(p.transform.matrix3) * 0.6, at);
        }
        let body = CsgTree::Union((0..parts).map(CsgTree::Leaf).collect());
        let tree = CsgTree::Difference(
            Box::new(body),
            vec![CsgTree::Union((parts..parts + cutters).map(CsgTree::Leaf).collect())],
        );
        let solid = CsgSolid { primitives, tree: Some(tree) };
        let camera = random_camera(&mut rng, round);
        for ((x, y), got, cast) in walk_beside_rays(&solid, &camera, (w, h)) {
            match (got, cast) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!(a.primitive, b.primitive, "({x}, {y}) round {round}");
                    assert!((a.t - b.t).abs() <= 1e-4 * b.t.abs().max(1.0), "({x}, {y}): {a:?} vs {b:?}");
                    covered += 1;
                    cut += usize::from(a.cut);
                }
                _ => panic!("({x}, {y}) round {round}: scanline {got:?}, ray {cast:?}"),
            }
        }
    }
    // Enough surface, and enough of it hole walls, for the test to bite.
    assert!(covered > 20_000 && cut > 2_000, "{covered} pixels covered, {cut} of hole walls");
}

/// Cutters flush with their part, as CAD models have them (a pocket as wide
/// as the plate, a cutter the part's own size, placed by translations that
/// do not round exactly): leaving each out where it cannot meet the part
/// keeps every pixel the rays cover covered, and shows the same primitive
/// nearly everywhere (a face the cut leaves exactly on the part's may show
/// either: the order in which the difference meets its cutters decides).
#[test]
fn cutters_flush_with_their_part_are_left_out_only_where_they_cannot_meet_it() {
    let mut rng = StdRng::seed_from_u64(43);
    let (w, h) = (96u32, 64u32);
    let (mut covered, mut same, mut cut) = (0, 0, 0);
    let cube = |lo: Vec3, hi: Vec3| Primitive {
        shape: Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
        transform: Affine3A::from_scale_rotation_translation(hi - lo, glam::Quat::IDENTITY, lo),
        color: None,
        source: 0..0,
    };
    for round in 0..40 {
        // The part: a plate about the origin whose corners do not round exactly.
        let size = Vec3::new(rng.gen_range(2.1..3.9), rng.gen_range(2.1..3.9), rng.gen_range(0.3..1.7));
        let (lo, hi) = (-size * 0.5 - Vec3::splat(0.1), size * 0.5 - Vec3::splat(0.1));
        let mut primitives = vec![cube(lo, hi)];
        for _ in 0..rng.gen_range(3..9) {
            // Each side of a cutter on the part's face, or inside, or beyond it.
            let mut side = |a: f32, b: f32| match rng.gen_range(0..4) {
                0 => a,
                1 => b,
                2 => rng.gen_range(a..b),
                _ => b + rng.gen_range(0.0..1.0),
            };
            let (x0, x1, y0, y1, z0, z1) = (
                side(lo.x, hi.x),
                side(lo.x, hi.x),
                side(lo.y, hi.y),
                side(lo.y, hi.y),
                side(lo.z, hi.z),
                side(lo.z, hi.z),
            );
            let (a, b) = (Vec3::new(x0.min(x1), y0.min(y1), z0.min(z1)), Vec3::new(x0.max(x1), y0.max(y1), z0.max(z1)));
            if (b - a).min_element() > 0.05 {
                primitives.push(cube(a, b));
            }
        }
        let cutters = CsgTree::Union((1..primitives.len()).map(CsgTree::Leaf).collect());
        let solid = CsgSolid { primitives, tree: Some(CsgTree::Difference(Box::new(CsgTree::Leaf(0)), vec![cutters])) };
        let camera = random_camera(&mut rng, round);
        for ((x, y), got, cast) in walk_beside_rays(&solid, &camera, (w, h)) {
            assert_eq!(got.is_some(), cast.is_some(), "({x}, {y}) round {round}: scanline {got:?}, ray {cast:?}");
            if let (Some(a), Some(b)) = (got, cast) {
                covered += 1;
                same += usize::from(a.primitive == b.primitive);
                cut += usize::from(a.cut);
            }
        }
    }
    assert!(covered > 20_000 && cut > 2_000, "{covered} pixels covered, {cut} of hole walls");
    assert!(same * 1000 >= covered * 995, "{same} of {covered} pixels show the ray's primitive");
}

/// The BVH-culled ray caster (a primitive whose box the ray misses counts as
/// missed, a union's operands read nearest box first and left once one box
/// lies past the nearest hit) finds exactly what casting every primitive
/// finds, on random solids large enough to get a BVH, for rays from inside
/// and outside their reach.
#[test]
fn culling_primitives_by_their_boxes_changes_no_hit() {
    use kage::csg::CsgCaster;
    let mut rng = StdRng::seed_from_u64(61);
    let (mut hits, mut rays) = (0, 0);
    for _ in 0..40 {
        let mut prims = Vec::new();
        // Six operands are read in turn; from eight, nearest box first.
        let operands = rng.gen_range(6..14);
        let kids = (0..operands).map(|_| random_tree(&mut rng, &mut prims, 3)).collect();
        let mut solid = CsgSolid { primitives: prims, tree: Some(CsgTree::Union(kids)) };
        // Spread the parts out, so boxes separate them.
        for p in &mut solid.primitives {
            p.transform = Affine3A::from_translation(Vec3::new(rng.gen_range(-3.0..3.0), 0.0, 0.0)) * p.transform;
        }
        if solid.primitives.len() < CsgCaster::BVH_PRIMITIVES {
            continue;
        }
        let caster = CsgCaster::new(&solid);
        for _ in 0..2000 {
            let mut v = || Vec3::new(rng.gen_range(-5.0..5.0), rng.gen_range(-3.0..3.0), rng.gen_range(-3.0..3.0));
            let (origin, to) = (v(), v());
            let ray = kage::camera::Ray { origin, dir: (to - origin).normalize_or(Vec3::X) };
            let culled = caster.first_hit(&ray, 0.0, f32::INFINITY);
            let every = caster.first_hit_every_primitive(&ray, 0.0);
            assert_eq!(culled.map(|c| (c.primitive, c.t)), every.map(|c| (c.primitive, c.t)), "{ray:?}");
            rays += 1;
            hits += usize::from(every.is_some());
        }
    }
    assert!(rays >= 20_000 && hits * 4 > rays, "{hits} hits of {rays} rays");
}

/// Seed 003 §5.2.2's coherence both ways — a pixel's answer reused along the
/// scanline while the occupants and the order of their ends stay, and an
/// eight-pixel block's answer spread from its first pixel (the default) —
/// gives the surfaces the walk finds pixel by pixel, to the bit, on random
/// solids and cameras.
#[test]
fn reusing_the_answer_along_a_scanline_changes_no_surface() {
    use kage::visibility::solids::{scan_solid_with, CsgMethod};
    let mut rng = StdRng::seed_from_u64(11);
    let (w, h) = (96u32, 64u32);
    let (mut covered, mut blocks_rounds) = (0, 0);
    for round in 0..200 {
        let mut prims = Vec::new();
        let tree = random_tree(&mut rng, &mut prims, 3);
        let solid = CsgSolid { primitives: prims, tree: Some(tree) };
        let camera = random_camera(&mut rng, round);
        let each = scan_solid_with(&solid, &camera, w, h, CsgMethod::SegmentsEachPixel).unwrap();
        for method in [CsgMethod::SegmentsCoherent, CsgMethod::Segments] {
            let reused = scan_solid_with(&solid, &camera, w, h, method).unwrap();
            for (k, (a, b)) in each.iter().zip(&reused).enumerate() {
                assert_eq!(a, b, "{method:?}: pixel ({}, {}) round {round}", k as u32 % w, k as u32 / w);
            }
        }
        let n = each.iter().flatten().count();
        covered += n;
        blocks_rounds += usize::from(n > 256);
    }
    // Enough surface for whole blocks to be spread.
    assert!(covered > 60_000 && blocks_rounds > 40, "{covered} pixels covered, {blocks_rounds} rounds of blocks");
}

/// A union of primitives takes each pixel's nearest entry occupant by
/// occupant along the scanline (a z-buffer, nearest occupants first, a block
/// left unsolved for one wholly behind what it shows; the default walk): the same
/// surfaces, to the bit, as the booleans pixel by pixel, with twin primitives
/// (exact ties: the one first in the file shows) and cameras inside a
/// primitive (the rows where a ray starts inside go to the booleans).
#[test]
fn a_union_of_primitives_walked_as_a_z_buffer_finds_what_the_booleans_find() {
    use kage::visibility::solids::{scan_solid_with, CsgMethod};
    let mut rng = StdRng::seed_from_u64(23);
    let (w, h) = (96u32, 64u32);
    let (mut covered, mut twins_seen) = (0, 0);
    for round in 0..120 {
        let mut primitives: Vec<Primitive> = (0..rng.gen_range(2..12)).map(|_| random_primitive(&mut rng)).collect();
        // A twin of one primitive, later in the file: every face of the pair ties.
        let twin = rng.gen_range(0..primitives.len());
        primitives.push(primitives[twin].clone());
        let tree = CsgTree::Union((0..primitives.len()).map(CsgTree::Leaf).collect());
        let solid = CsgSolid { primitives, tree: Some(tree) };
        let camera = random_camera(&mut rng, round);
        let each = scan_solid_with(&solid, &camera, w, h, CsgMethod::SegmentsEachPixel).unwrap();
        let nearest = scan_solid_with(&solid, &camera, w, h, CsgMethod::Segments).unwrap();
        for (k, (a, b)) in each.iter().zip(&nearest).enumerate() {
            assert_eq!(a, b, "pixel ({}, {}) round {round}", k as u32 % w, k as u32 / w);
            let last = solid.primitives.len() as u32 - 1;
            twins_seen += usize::from(b.is_some_and(|c| c.primitive == twin as u32));
            // (From inside, the first surface is an exit the full merge finds,
            // whose ties are not ordered.)
            let outside = round % 5 != 4;
            assert!(!outside || b.is_none_or(|c| c.primitive != last), "round {round}: the later twin shows");
        }
        covered += each.iter().flatten().count();
    }
    assert!(covered > 60_000 && twins_seen > 5_000, "{covered} pixels covered, {twins_seen} of twins");
}

/// A union of a crowd of small primitives, most of them on the same rows
/// (over 64, 128 and 256 occupants to a row: the z-buffer's bits in one, two
/// and four words, and beyond that the booleans), with twins: the same
/// surfaces, to the bit, as the booleans pixel by pixel.
#[test]
fn a_crowded_union_walked_as_a_z_buffer_finds_what_the_booleans_find() {
    use kage::camera::{Camera, Projection};
    use kage::visibility::solids::{scan_solid_with, CsgMethod};
    let mut rng = StdRng::seed_from_u64(37);
    let (w, h) = (96u32, 64u32);
    let mut covered = 0;
    for (round, n) in [100, 200, 300, 160].into_iter().enumerate() {
        let mut primitives: Vec<Primitive> = (0..n)
            .map(|_| {
                let p = random_primitive(&mut rng);
                // In a flat band across the view: each row meets most of them.
                let at = Vec3::new(rng.gen_range(-2.5..2.5), rng.gen_range(-0.2..0.2), rng.gen_range(-2.0..2.0));
                Primitive { transform: Affine3A::from_mat3_translation(Mat3::from(p.transform.matrix3) * 0.3, at), ..p }
            })
            .collect();
        let twins: Vec<Primitive> = primitives.iter().step_by(7).cloned().collect();
        primitives.extend(twins);
        let tree = CsgTree::Union((0..primitives.len()).map(CsgTree::Leaf).collect());
        let solid = CsgSolid { primitives, tree: Some(tree) };
        let camera = Camera {
            eye: Vec3::new(0.4 * round as f32 - 0.6, 0.3, 8.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.05,
            far: 100.0,
            projection: Projection::Perspective { fov_y_deg: 40.0 },
            shift: glam::Vec2::ZERO,
        };
        let each = scan_solid_with(&solid, &camera, w, h, CsgMethod::SegmentsEachPixel).unwrap();
        let nearest = scan_solid_with(&solid, &camera, w, h, CsgMethod::Segments).unwrap();
        for (k, (a, b)) in each.iter().zip(&nearest).enumerate() {
            assert_eq!(a, b, "pixel ({}, {}) round {round}", k as u32 % w, k as u32 / w);
        }
        covered += each.iter().flatten().count();
    }
    assert!(covered > 2_500, "{covered} pixels covered");
}

/// A viewer's frame scanned again and again (other solids, other cameras,
/// now and then an empty solid or another size) holds, after each scan, just
/// what a fresh scan finds: what the last scan wrote and this one does not is
/// cleared. Each solid is prepared once and scanned from two cameras, as a
/// viewer keeps it while the camera moves.
#[test]
fn a_frame_scanned_again_holds_only_the_last_scan() {
    use kage::visibility::solids::SurfaceFrame;
    use kage::visibility::solids::{scan_solid_with, CsgMethod, PreparedSolid};
    let mut rng = StdRng::seed_from_u64(29);
    let mut frame = SurfaceFrame::new();
    let (mut stale, mut covered) = (0, 0);
    let mut prepared = None;
    let mut solid = CsgSolid::default();
    for round in 0..100 {
        let (w, h) = if round % 13 == 12 { (40u32, 24u32) } else { (96, 64) };
        if round % 2 == 0 {
            let mut primitives = Vec::new();
            let tree = random_tree(&mut rng, &mut primitives, 2);
            solid = CsgSolid { primitives, tree: (round % 11 != 10).then_some(tree) };
            prepared = Some(PreparedSolid::new(&solid, CsgMethod::Segments).unwrap());
        }
        let camera = random_camera(&mut rng, round);
        let before: Vec<bool> = frame.pixels().iter().map(Option::is_some).collect();
        prepared.as_ref().unwrap().scan_into(&camera, (w, h), &mut frame);
        let fresh = scan_solid_with(&solid, &camera, w, h, CsgMethod::Segments).unwrap();
        assert_eq!(frame.pixels().len(), fresh.len(), "round {round}");
        for (k, (a, b)) in frame.pixels().iter().zip(&fresh).enumerate() {
            assert_eq!(a, b, "pixel ({}, {}) round {round}", k as u32 % w, k as u32 / w);
        }
        let same_size = before.len() == fresh.len();
        stale += fresh.iter().zip(&before).filter(|(f, &b)| same_size && b && f.is_none()).count();
        covered += fresh.iter().flatten().count();
    }
    // Enough pixels held a surface before and none after for the test to bite.
    assert!(stale > 10_000 && covered > 20_000, "{stale} pixels cleared, {covered} covered");
}

/// A cutter whose face leans through a solid's face by a few [`TIE`]s: the
/// raw depths keep their order across the scanline while the cut's decision
/// (the cutter's face counts as reaching the solid's within `TIE`) changes
/// inside the run; the coherent walk must change its answer there too.
#[test]
fn reuse_follows_a_cut_decided_within_the_tie() {
    use kage::csg::TIE;
    use kage::visibility::solids::CsgMethod;
    let cube = || Shape::Polyhedron(ConvexPolyhedron::unit_cube());
    let solid_box = Affine3A::from_scale(Vec3::splat(2.0)) * Affine3A::from_translation(Vec3::splat(-0.5));
    // The cutter's front face: z = 1 + s·x, from two TIEs (of t ≈ 4) in
    // front of the solid's face z = 1 at x = 1 to two behind it at x = −1:
    // the cut takes the face from x = −½ on, the raw depths swap at x = 0.
    let lean = 2.0 * TIE * 4.0;
    let shear = Mat3::from_cols(Vec3::new(1.0, 0.0, lean), Vec3::Y, Vec3::Z);
    let cutter = Affine3A::from_mat3(shear)
        * Affine3A::from_translation(Vec3::new(-1.5, -0.5, 0.5))
        * Affine3A::from_scale(Vec3::new(3.0, 1.0, 0.5));
    let primitives = vec![
        Primitive { shape: cube(), transform: solid_box, color: None, source: 0..0 },
        Primitive { shape: cube(), transform: cutter, color: None, source: 0..0 },
    ];
    let tree = CsgTree::Difference(Box::new(CsgTree::Leaf(0)), vec![CsgTree::Leaf(1)]);
    let solid = CsgSolid { primitives, tree: Some(tree) };
    // Along the middle row: the solid's face where the cutter's lies behind
    // it by more than the tie, the hole's floor elsewhere.
    let (each, [face, floor]) = down_z(&solid, CsgMethod::SegmentsEachPixel);
    assert!(face > 10 && floor > 10, "face {face}, floor {floor} pixels of the middle row");
    assert_eq!(each, down_z(&solid, CsgMethod::SegmentsCoherent).0);
    assert_eq!(each, down_z(&solid, CsgMethod::Segments).0);
}

/// `solid` seen straight down the z axis (orthographic, 3 units high) at
/// 200x100 by `method`, and how many pixels of the middle row show
/// primitive 0 and primitive 1.
fn down_z(solid: &CsgSolid, method: kage::visibility::solids::CsgMethod) -> (Vec<Option<Crossing>>, [usize; 2]) {
    use kage::camera::{Camera, Projection};
    let camera = Camera {
        eye: Vec3::new(0.0, 0.0, 5.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        near: 0.05,
        far: 100.0,
        projection: Projection::Orthographic { height: 3.0 },
        shift: glam::Vec2::ZERO,
    };
    let (w, h) = (200u32, 100u32);
    let scan = kage::visibility::solids::scan_solid_with(solid, &camera, w, h, method).unwrap();
    let row = &scan[(h / 2 * w) as usize..((h / 2 + 1) * w) as usize];
    let shows = |p: u32| row.iter().flatten().filter(|c| c.primitive == p).count();
    let counts = [shows(0), shows(1)];
    (scan, counts)
}

/// Two boxes' faces crossing at a hair's angle, so that along the middle row
/// the nearer one changes where their depths differ in the last bits only:
/// spreading a block's answer must not take "nearly equal" for "equal".
#[test]
fn spreading_a_block_keeps_faces_that_cross_within_rounding_apart() {
    use kage::visibility::solids::CsgMethod;
    let cube = || Shape::Polyhedron(ConvexPolyhedron::unit_cube());
    let flat = Affine3A::from_translation(Vec3::new(-1.5, -0.5, 0.0));
    // The second box's top: z = 1 + s·x, s a few units of the last place of
    // t (≈ 4) across the image.
    let shear = Mat3::from_cols(Vec3::new(1.0, 0.0, 4.0 * f32::EPSILON), Vec3::Y, Vec3::Z);
    let leaning = Affine3A::from_mat3(shear) * flat;
    let primitives = [flat, leaning]
        .map(|t| Primitive {
            shape: cube(),
            transform: t * Affine3A::from_scale(Vec3::new(3.0, 1.0, 1.0)),
            color: None,
            source: 0..0,
        })
        .to_vec();
    let tree = CsgTree::Union(vec![CsgTree::Leaf(0), CsgTree::Leaf(1)]);
    let solid = CsgSolid { primitives, tree: Some(tree) };
    let (each, [firsts, seconds]) = down_z(&solid, CsgMethod::SegmentsEachPixel);
    assert!(firsts > 10 && seconds > 10, "{firsts} and {seconds} pixels of the middle row show each box");
    assert_eq!(each, down_z(&solid, CsgMethod::Segments).0);
}

/// A torus about z (major radius `big`, minor `small`) as a closed mesh of
/// `n` × `m` quads, each split into two triangles, under `at`: a solid that
/// most rays meet in two intervals.
fn torus(big: f32, small: f32, (n, m): (usize, usize), at: Affine3A) -> kage::csg::ClosedMesh {
    let point = |i: usize, j: usize| {
        let (u, v) = (std::f32::consts::TAU * i as f32 / n as f32, std::f32::consts::TAU * j as f32 / m as f32);
        at.transform_point3(Vec3::new(
            (big + small * v.cos()) * u.cos(),
            (big + small * v.cos()) * u.sin(),
            small * v.sin(),
        ))
    };
    let positions: Vec<Vec3> = (0..n).flat_map(|i| (0..m).map(move |j| point(i, j))).collect();
    let index = |i: usize, j: usize| ((i % n) * m + j % m) as u32;
    let triangles = (0..n)
        .flat_map(|i| {
            (0..m).flat_map(move |j| {
                [
                    [index(i, j), index(i + 1, j), index(i + 1, j + 1)],
                    [index(i, j), index(i + 1, j + 1), index(i, j + 1)],
                ]
            })
        })
        .collect();
    kage::csg::ClosedMesh::new(positions, triangles).expect("a torus")
}

/// Brute force: every triangle of `mesh` (placed by `at`) against `ray`,
/// crossings paired by parity (the eye outside).
fn mesh_intervals(mesh: &kage::csg::ClosedMesh, at: Affine3A, ray: &Ray) -> Vec<(f64, f64)> {
    let mut ts: Vec<f64> = (0..mesh.triangles().len())
        .filter_map(|i| {
            let corners = mesh.corners(i).map(|c| at.transform_point3(c));
            kage::triangle::intersect_f64(ray, &corners).map(|(t, _)| t)
        })
        .collect();
    ts.sort_by(f64::total_cmp);
    ts.chunks_exact(2).map(|p| (p[0], p[1])).collect()
}

/// A sphere's interval along `ray` (unit direction).
fn ball_interval(centre: Vec3, r: f32, ray: &Ray) -> Vec<(f64, f64)> {
    let (o, d) = ((ray.origin - centre).as_dvec3(), ray.dir.as_dvec3());
    let (b, c) = (o.dot(d), o.dot(o) - f64::from(r * r));
    let disc = b * b - c;
    if disc < 0.0 {
        return Vec::new();
    }
    vec![(-b - disc.sqrt(), -b + disc.sqrt())]
}

/// Two sorted lists of disjoint intervals combined by `keep(in_a, in_b)`.
fn combine_lists(a: &[(f64, f64)], b: &[(f64, f64)], keep: impl Fn(bool, bool) -> bool) -> Vec<(f64, f64)> {
    let mut cuts: Vec<f64> = a.iter().chain(b).flat_map(|&(x, y)| [x, y]).collect();
    cuts.sort_by(f64::total_cmp);
    let inside = |list: &[(f64, f64)], t: f64| list.iter().any(|&(x, y)| x < t && t < y);
    let mut out: Vec<(f64, f64)> = Vec::new();
    for w in cuts.windows(2) {
        let mid = 0.5 * (w[0] + w[1]);
        if w[1] > w[0] && keep(inside(a, mid), inside(b, mid)) {
            match out.last_mut() {
                Some(last) if last.1 == w[0] => last.1 = w[1],
                _ => out.push((w[0], w[1])),
            }
        }
    }
    out
}

/// The closed-mesh primitive against brute-force ray casting of its own
/// triangles: a torus (two intervals along most rays) in a union, a
/// difference and an intersection with a ball, under random placements, seen
/// by the scanline walk (the mesh's layers rasterized a frame at a time):
/// nearly every pixel shows the surface at the depth the brute force finds.
#[test]
fn a_mesh_primitive_in_booleans_matches_brute_force_ray_casting() {
    use kage::camera::{Camera, Projection};
    let mut rng = StdRng::seed_from_u64(52);
    let (w, h) = (96u32, 72u32);
    for case in 0..9 {
        let at = Affine3A::from_rotation_translation(
            glam::Quat::from_euler(glam::EulerRot::XYZ, rng.gen_range(-1.5..1.5), rng.gen_range(-1.5..1.5), 0.0),
            Vec3::new(rng.gen_range(-0.3..0.3), rng.gen_range(-0.3..0.3), 0.0),
        );
        let mesh = std::sync::Arc::new(torus(1.0, rng.gen_range(0.25..0.45), (48, 24), Affine3A::IDENTITY));
        // A ball on the ring, so that each boolean has something to show.
        let a: f32 = rng.gen_range(0.0..std::f32::consts::TAU);
        let centre = at.transform_point3(Vec3::new(a.cos(), a.sin(), rng.gen_range(-0.3..0.3)));
        let r = rng.gen_range(0.4..0.9);
        let op = case % 3;
        let layers = mesh.layers();
        let mut primitives: Vec<Primitive> = (0..layers)
            .map(|layer| Primitive {
                shape: Shape::Mesh { mesh: mesh.clone(), layer },
                transform: at,
                color: None,
                source: 0..0,
            })
            .collect();
        primitives.push(Primitive {
            shape: Shape::Sphere,
            transform: Affine3A::from_scale_rotation_translation(Vec3::splat(r), glam::Quat::IDENTITY, centre),
            color: None,
            source: 0..0,
        });
        let torus_tree = CsgTree::mesh_layers(0, layers);
        let ball = CsgTree::Leaf(layers as usize);
        let tree = match op {
            0 => CsgTree::Union(vec![torus_tree, ball]),
            1 => CsgTree::Difference(Box::new(torus_tree), vec![ball]),
            _ => CsgTree::Intersection(vec![torus_tree, ball]),
        };
        let solid = CsgSolid { primitives, tree: Some(tree) };
        let camera = Camera {
            eye: Vec3::new(0.3, -4.0, 2.5),
            target: Vec3::ZERO,
            up: Vec3::Z,
            near: 0.1,
            far: 50.0,
            projection: Projection::Perspective { fov_y_deg: 40.0 },
            shift: glam::Vec2::ZERO,
        };
        let scanned = kage::visibility::solids::scan_solid(&solid, &camera, w, h);
        let rays = camera.pixel_rays(glam::Vec2::new(w as f32, h as f32));
        let (mut agree, mut covered) = (0, 0);
        for (k, hit) in scanned.iter().enumerate() {
            let ray = rays.ray(glam::Vec2::new((k as u32 % w) as f32 + 0.5, (k as u32 / w) as f32 + 0.5));
            let (t_mesh, t_ball) = (mesh_intervals(&mesh, at, &ray), ball_interval(centre, r, &ray));
            let truth = combine_lists(&t_mesh, &t_ball, |a, b| match op {
                0 => a || b,
                1 => a && !b,
                _ => a && b,
            });
            let first = truth.first().map(|s| s.0);
            covered += usize::from(first.is_some() || hit.is_some());
            agree += usize::from(match (first, hit) {
                (None, None) => true,
                (Some(t), Some(c)) => (t - f64::from(c.t)).abs() < 1e-3 * t.max(1.0),
                _ => false,
            });
        }
        let misses = scanned.len() - agree;
        eprintln!(
            "case {case} ({}): {misses} of {covered} covered pixels differ",
            ["union", "difference", "intersection"][op]
        );
        assert!(covered > 200 && misses * 200 <= covered, "case {case}: {misses} of {covered} pixels differ");
    }
}
