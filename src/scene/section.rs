//! Section planes: everything beyond a plane removed, and the cut faces of
//! closed bodies drawn (capped), as a CAD section view shows a part.
//!
//! The scene itself is cut, once, before a frame: every later stage (the
//! polygon pass, shadow maps, rays, ambient occlusion, the edge pass) sees the
//! cut scene and needs nothing of its own.
//!
//! - A mesh is clipped triangle by triangle in its own space (Sutherland and
//!   Hodgman against one plane; a point where an edge crosses the plane is
//!   made once per edge, so neighbours share it and the cut stays watertight).
//!   Where every cut edge closes into loops — a closed mesh — the loops are
//!   triangulated (Manifold's ear clipper, holes included) into a cap of the
//!   [`CAP_MATERIAL`] facing the removed side, from the very points of the
//!   cut; an open mesh keeps no cap and is drawn two-sided, so its inside shows.
//! - A CSG solid (seed 003) gets one more cutter: the part of its bounding box
//!   beyond the plane, a convex primitive. The cut face is that primitive's
//!   face, in the cap material, found by the same scanline walk as every other
//!   face. As a cutter, its face decides a solid's face lying on the plane as
//!   every difference decides coplanar faces (removed): a plane on a part's
//!   bottom face, the part kept below, leaves nothing rather than a sheet of
//!   zero-length spans. The result is also met with a box just holding the
//!   kept part, so the solid's bounds (its shadow maps' framing) shrink with
//!   the cut.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{DVec3, Vec2, Vec3};
use manifold_rust::linalg::Vec2 as MVec2;
use manifold_rust::polygon::triangulate;

use super::{Body, Material, Mesh, Object, Scene};
use crate::csg::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};

/// The name of the material section caps are drawn in (added to the scene).
pub const CAP_MATERIAL: &str = "section cap";

/// A plane that keeps the points `p` with `normal · p ≤ offset` and removes
/// the rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SectionPlane {
    /// Unit normal, pointing into the removed half.
    pub normal: Vec3,
    /// The plane's distance from the origin along the normal.
    pub offset: f32,
}

impl SectionPlane {
    /// The plane through `point` with unit `normal` (into the removed half);
    /// `None` for a zero or non-finite normal or a non-finite point.
    #[must_use]
    pub fn through(point: Vec3, normal: Vec3) -> Option<SectionPlane> {
        let normal = normal.try_normalize()?;
        point.is_finite().then(|| SectionPlane { normal, offset: normal.dot(point) })
    }

    /// The plane in the space a transform's inverse maps world points to:
    /// `(n', d')` with `n' · q ≤ d'` where `q` is kept (`n'` not of unit length).
    fn in_object(self, transform: &glam::Affine3A) -> (DVec3, f64) {
        let linear = transform.matrix3.as_dmat3();
        let n = self.normal.as_dvec3();
        (linear.transpose() * n, f64::from(self.offset) - n.dot(transform.translation.as_dvec3()))
    }
}

/// What a section did to a scene, for the user to see.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct SectionReport {
    /// Objects cut and capped.
    pub capped: usize,
    /// Objects cut whose cut edges do not close (open meshes): drawn
    /// two-sided, without a cap.
    pub open: Vec<String>,
    /// Objects wholly beyond the plane, removed.
    pub removed: usize,
}

impl Scene {
    /// Cuts the scene by `plane` (module [`self`](crate::scene::section)):
    /// what lies beyond it is removed, closed meshes and solids get a cap in
    /// the [`CAP_MATERIAL`] (added to the materials), open meshes are drawn
    /// two-sided. Open meshes that were cut are named in the scene's warnings.
    pub fn section(&mut self, plane: SectionPlane) -> SectionReport {
        let cap = self.materials.len();
        let red = Vec3::new(0.75, 0.22, 0.18);
        self.materials.push(Material { name: CAP_MATERIAL.to_string(), ka: red, kd: red, ..Material::default() });
        let mut report = SectionReport::default();
        let mut out = Vec::with_capacity(self.objects.len());
        for object in std::mem::take(&mut self.objects) {
            let (n, d) = plane.in_object(&object.transform);
            match &object.body {
                Body::Mesh(mesh) => self.cut_mesh(object.clone(), mesh, (n, d), cap, &mut out, &mut report),
                Body::Solid { solid, materials } => match cut_solid(solid, (n, d)) {
                    Sectioned::Kept => out.push(object),
                    Sectioned::Removed => report.removed += 1,
                    Sectioned::Cut(solid) => {
                        let materials = materials.iter().copied().chain([cap, cap]).collect();
                        out.push(Object { body: Body::Solid { solid: Arc::new(solid), materials }, ..object });
                        report.capped += 1;
                    }
                },
            }
        }
        if out.is_empty() && report.removed > 0 {
            self.warnings.push("section: every object lies beyond the plane: nothing is left to draw".to_string());
        }
        self.objects = out;
        if !report.open.is_empty() {
            let names = report.open.join(", ");
            self.warnings.push(format!("section: not closed, so drawn without a cut face (inside shown): {names}"));
        }
        report
    }

    /// Cuts one mesh object into `out` (and its cap, if it closes).
    fn cut_mesh(
        &mut self,
        object: Object,
        mesh: &Mesh,
        plane: (DVec3, f64),
        cap: usize,
        out: &mut Vec<Object>,
        report: &mut SectionReport,
    ) {
        match clip_mesh(mesh, plane) {
            Sectioned::Kept => out.push(object),
            Sectioned::Removed => report.removed += 1,
            Sectioned::Cut((kept, loops)) => {
                let name = object.name.clone();
                let lid = loops.and_then(|loops| cap_mesh(&kept, &loops, plane.0));
                let mut cut = Object { body: Body::Mesh(Arc::new(kept)), ..object.clone() };
                match lid {
                    Some(lid) => {
                        out.push(cut);
                        let name = format!("{name} (section)");
                        out.push(Object { name, body: Body::Mesh(Arc::new(lid)), material: cap, ..object });
                        report.capped += 1;
                    }
                    None => {
                        if !self.materials[cut.material].two_sided {
                            let inside = Material { two_sided: true, ..self.materials[cut.material].clone() };
                            cut.material = self.materials.len();
                            self.materials.push(inside);
                        }
                        out.push(cut);
                        report.open.push(name);
                    }
                }
            }
        }
    }
}

/// What cutting a body left.
enum Sectioned<T> {
    /// All of it (nothing beyond the plane).
    Kept,
    /// None of it.
    Removed,
    /// Part of it.
    Cut(T),
}

/// The cut's directed edges on the plane, as loops of vertex indices of the
/// kept mesh (`None` where they do not close).
type Loops = Option<Vec<Vec<u32>>>;

/// The part of `mesh` on the kept side of `(n, d)`, and its cut's loops.
fn clip_mesh(mesh: &Mesh, (n, d): (DVec3, f64)) -> Sectioned<(Mesh, Loops)> {
    let side: Vec<f64> = mesh.positions.iter().map(|p| n.dot(p.as_dvec3()) - d).collect();
    if side.iter().all(|&s| s <= 0.0) {
        return Sectioned::Kept;
    }
    if side.iter().all(|&s| s >= 0.0) {
        return Sectioned::Removed;
    }
    // A vertex on the plane counts as beyond it (a crossing at its very
    // point stands for it): each edge along the plane is then met once, from
    // the kept side, and the cut's loops close through such vertices.
    let kept_side = |i: u32| side[i as usize] < 0.0;
    let mut kept = Kept { mesh, side: &side, out: Mesh::default(), old: HashMap::new(), crossings: HashMap::new() };
    let mut edges: Vec<(u32, u32)> = Vec::new();
    for t in &mesh.triangles {
        // Sutherland–Hodgman against the one plane: the kept polygon, and the
        // points where its boundary leaves the kept side and comes back.
        let mut polygon = Vec::with_capacity(4);
        let (mut leaves, mut enters) = (None, None);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let (a_in, b_in) = (kept_side(a), kept_side(b));
            if a_in {
                polygon.push(kept.vertex(a));
            }
            if a_in != b_in {
                let x = kept.crossing(a, b);
                polygon.push(x);
                *(if a_in { &mut leaves } else { &mut enters }) = Some(x);
            }
        }
        // The kept polygon runs along the plane from where it leaves to where
        // it enters; the cap, facing the other way, runs back.
        if let (Some(leaves), Some(enters)) = (leaves, enters) {
            edges.push((enters, leaves));
        }
        if polygon.len() >= 3 {
            (1..polygon.len() - 1).for_each(|k| kept.out.triangles.push([polygon[0], polygon[k], polygon[k + 1]]));
        }
    }
    if kept.out.triangles.is_empty() {
        return Sectioned::Removed;
    }
    // A mesh with split vertices (hard edges, seams) meets one crossing
    // point as several vertices: loops are joined by position.
    let mut by_position: HashMap<[u32; 3], u32> = HashMap::new();
    let mut one = |v: u32| *by_position.entry(key(kept.out.positions[v as usize])).or_insert(v);
    // A vertex on the plane is met by several crossings at its very point:
    // the edges between them have no length and are left out.
    let edges: Vec<(u32, u32)> = edges.iter().map(|&(a, b)| (one(a), one(b))).filter(|(a, b)| a != b).collect();
    let loops = close_loops(&edges);
    Sectioned::Cut((kept.out, loops))
}

/// A point's bits, −0 and +0 alike: one key for one place.
fn key(p: Vec3) -> [u32; 3] {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// The kept mesh as it is built: old vertices copied once, crossing points
/// made once per edge.
struct Kept<'a> {
    mesh: &'a Mesh,
    side: &'a [f64],
    out: Mesh,
    old: HashMap<u32, u32>,
    crossings: HashMap<(u32, u32), u32>,
}

impl Kept<'_> {
    /// Old vertex `i` in the kept mesh.
    fn vertex(&mut self, i: u32) -> u32 {
        if let Some(&v) = self.old.get(&i) {
            return v;
        }
        let v = self.push(i, i, 0.0);
        self.old.insert(i, v);
        v
    }

    /// Where edge `a`–`b` crosses the plane (`a`, `b` on opposite sides),
    /// made from the end with the lower position towards the other whichever
    /// way it is met (so copies of an edge between split vertices cross at
    /// the very same point).
    fn crossing(&mut self, a: u32, b: u32) -> u32 {
        if let Some(&v) = self.crossings.get(&(a.min(b), a.max(b))) {
            return v;
        }
        let at = |i: u32| (key(self.mesh.positions[i as usize]), i);
        let (a, b) = if at(a) <= at(b) { (a, b) } else { (b, a) };
        let (sa, sb) = (self.side[a as usize], self.side[b as usize]);
        let v = self.push(a, b, (sa / (sa - sb)) as f32);
        self.crossings.insert((a.min(b), a.max(b)), v);
        v
    }

    /// A new vertex `t` of the way from old vertex `a` to `b`, every
    /// attribute the mesh has interpolated.
    fn push(&mut self, a: u32, b: u32, t: f32) -> u32 {
        let (m, o) = (self.mesh, &mut self.out);
        // At an end, that end itself (a lerp to 1 need not land on it).
        let (a, b, t) = if t >= 1.0 { (b as usize, b as usize, 0.0) } else { (a as usize, b as usize, t) };
        o.positions.push(m.positions[a].lerp(m.positions[b], t));
        if !m.normals.is_empty() {
            o.normals.push(m.normals[a].lerp(m.normals[b], t).normalize_or(m.normals[a]));
        }
        let lerp2 = |v: &[Vec2]| v[a].lerp(v[b], t);
        if !m.uvs.is_empty() {
            o.uvs.push(lerp2(&m.uvs));
        }
        if !m.uvs1.is_empty() {
            o.uvs1.push(lerp2(&m.uvs1));
        }
        if !m.colors.is_empty() {
            o.colors.push(m.colors[a].lerp(m.colors[b], t));
        }
        (o.positions.len() - 1) as u32
    }
}

/// Directed edges joined into closed loops; `None` when a vertex does not
/// have exactly one edge in and one out.
fn close_loops(edges: &[(u32, u32)]) -> Loops {
    let mut next: HashMap<u32, u32> = HashMap::with_capacity(edges.len());
    for &(a, b) in edges {
        if next.insert(a, b).is_some() {
            return None;
        }
    }
    let mut ins: HashMap<u32, u32> = HashMap::with_capacity(edges.len());
    for &(_, b) in edges {
        *ins.entry(b).or_default() += 1;
    }
    if ins.len() != next.len() || ins.values().any(|&c| c != 1) || next.keys().any(|a| !ins.contains_key(a)) {
        return None;
    }
    let mut loops = Vec::new();
    let mut starts: Vec<u32> = next.keys().copied().collect();
    starts.sort_unstable();
    let mut seen = std::collections::HashSet::new();
    for start in starts {
        if !seen.insert(start) {
            continue;
        }
        let mut ring = vec![start];
        let mut v = next[&start];
        while v != start {
            seen.insert(v);
            ring.push(v);
            v = next[&v];
        }
        loops.push(ring);
    }
    Some(loops)
}

/// The cap over `loops` (of vertices of `kept`) in the plane of normal `n`,
/// facing `n`: the loops' own points, triangulated with holes.
fn cap_mesh(kept: &Mesh, loops: &[Vec<u32>], n: DVec3) -> Option<Mesh> {
    let n = n.normalize_or_zero();
    let (u, v) = n.any_orthonormal_pair();
    let flat = |i: u32| {
        let p = kept.positions[i as usize].as_dvec3();
        MVec2::new(p.dot(u), p.dot(v))
    };
    let area = |ring: &[u32]| -> f64 {
        let pts: Vec<MVec2> = ring.iter().map(|&i| flat(i)).collect();
        (0..pts.len()).map(|k| pts[k].x * pts[(k + 1) % pts.len()].y - pts[(k + 1) % pts.len()].x * pts[k].y).sum()
    };
    // u × v = n: counter-clockwise in (u, v) faces n. The largest loop is an
    // outline; if it runs clockwise, every loop is turned.
    let largest = loops.iter().max_by(|a, b| area(a).abs().total_cmp(&area(b).abs()))?;
    let turn = area(largest) < 0.0;
    let rings: Vec<Vec<u32>> =
        loops.iter().map(|r| if turn { r.iter().rev().copied().collect() } else { r.clone() }).collect();
    let polygons: Vec<Vec<MVec2>> = rings.iter().map(|r| r.iter().map(|&i| flat(i)).collect()).collect();
    let order: Vec<u32> = rings.concat();
    let triangles = triangulate(&polygons, -1.0, true);
    if triangles.is_empty() {
        return None;
    }
    let normal = n.as_vec3();
    let positions: Vec<Vec3> = order.iter().map(|&i| kept.positions[i as usize]).collect();
    let count = positions.len();
    Some(Mesh {
        positions,
        normals: vec![normal; count],
        triangles: triangles.iter().map(|t| [t.x as u32, t.y as u32, t.z as u32]).collect(),
        ..Mesh::default()
    })
}

/// `solid` less the part of its (grown) bounding box beyond `(n, d)`.
///
/// The plane is a cutter rather than one more operand of an intersection, so
/// a face of the solid lying on the plane is decided as a difference decides
/// coplanar faces ([`crate::csg::TIE`]): the cut removes it (a plane on a
/// part's bottom face, the part kept below: nothing), instead of leaving
/// spans of no length that speckle the image and its shadows. The result is
/// also met with a box a little larger than the kept part's, whose faces
/// stay clear of the solid, so the cut solid's bounds (its shadow maps',
/// its camera's framing) are the kept part's.
fn cut_solid(solid: &CsgSolid, (n, d): (DVec3, f64)) -> Sectioned<CsgSolid> {
    let (Some((lo, hi)), Some(tree)) = (solid.bounds(), &solid.tree) else { return Sectioned::Kept };
    let grow = (hi - lo).max_element().max(1e-3) * 0.01;
    let (lo, hi) = ((lo - grow).as_dvec3(), (hi + grow).as_dvec3());
    let corners: Vec<DVec3> =
        (0..8).map(|i| DVec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][i >> 1 & 1], [lo.z, hi.z][i >> 2 & 1])).collect();
    let side: Vec<f64> = corners.iter().map(|c| n.dot(*c) - d).collect();
    if side.iter().all(|&s| s <= 0.0) {
        return Sectioned::Kept;
    }
    if side.iter().all(|&s| s > 0.0) {
        return Sectioned::Removed;
    }
    let mut crossings = Vec::new();
    for a in 0..8usize {
        for bit in [1, 2, 4] {
            let b = a | bit;
            if b != a && (side[a] <= 0.0) != (side[b] <= 0.0) {
                let t = side[a] / (side[a] - side[b]);
                crossings.push(corners[a].lerp(corners[b], t).as_vec3());
            }
        }
    }
    let on = |keep: bool| {
        let corners = corners.iter().zip(&side).filter(move |(_, &s)| (s <= 0.0) == keep || s == 0.0);
        corners.map(|(c, _)| c.as_vec3()).chain(crossings.iter().copied())
    };
    let (kept_lo, kept_hi) = on(true).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(l, h), p| (l.min(p), h.max(p)));
    // Pushed out across the plane only: its other faces are the grown box's.
    let (lo, hi) = (lo.as_vec3(), hi.as_vec3());
    let kept = ConvexPolyhedron::boxed(
        Vec3::select(kept_lo.cmpgt(lo), kept_lo - grow, kept_lo),
        Vec3::select(kept_hi.cmplt(hi), kept_hi + grow, kept_hi),
    );
    let mut beyond = ConvexPolyhedron::boxed(lo, hi);
    let length = n.length();
    beyond.planes.push((-n / length).as_vec3().extend((-d / length) as f32));
    beyond.vertices = on(false).collect();
    let mut cut = solid.clone();
    let first = cut.primitives.len();
    cut.primitives.extend([kept, beyond].map(|poly| Primitive {
        shape: Shape::Polyhedron(poly),
        transform: glam::Affine3A::IDENTITY,
        color: None,
        source: 0..0,
    }));
    let less = CsgTree::Difference(Box::new(tree.clone()), vec![CsgTree::Leaf(first + 1)]);
    cut.tree = Some(CsgTree::Intersection(vec![less, CsgTree::Leaf(first)]));
    Sectioned::Cut(cut)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::mesh::shapes;

    fn area(m: &Mesh, n: Vec3) -> f32 {
        m.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                0.5 * (b - a).cross(c - a).dot(n)
            })
            .sum()
    }

    /// Every edge of the meshes (by position) is used once each way: the
    /// surface is closed and consistently wound.
    fn closed(meshes: &[&Mesh]) -> bool {
        let key = |p: Vec3| p.to_array().map(f32::to_bits);
        let mut count: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        for m in meshes {
            for t in &m.triangles {
                for k in 0..3 {
                    let (a, b) = (key(m.positions[t[k] as usize]), key(m.positions[t[(k + 1) % 3] as usize]));
                    if a != b {
                        *count.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
                    }
                }
            }
        }
        count.values().all(|&c| c == 0)
    }

    fn cut(mesh: &Mesh, n: Vec3, d: f32) -> (Mesh, Option<Mesh>) {
        let Sectioned::Cut((kept, loops)) = clip_mesh(mesh, (n.as_dvec3(), f64::from(d))) else { panic!("not cut") };
        let lid = loops.and_then(|l| cap_mesh(&kept, &l, n.as_dvec3()));
        (kept, lid)
    }

    #[test]
    fn a_cube_cut_in_half_is_closed_by_a_unit_square_facing_the_cut() {
        for (n, d) in [(Vec3::Z, 0.0), (-Vec3::X, 0.2), (Vec3::new(1.0, 1.0, 0.0).normalize(), 0.0)] {
            let cube = shapes::cube();
            let (kept, lid) = cut(&cube, n, d);
            let lid = lid.expect("a closed mesh gets a cap");
            assert!(kept.positions.iter().all(|p| p.dot(n) <= d + 1e-6), "nothing beyond the plane");
            assert!(closed(&[&kept, &lid]), "the cut cube is closed");
            assert!(lid.triangles.iter().all(|t| {
                let [a, b, c] = t.map(|i| lid.positions[i as usize]);
                (b - a).cross(c - a).dot(n) >= 0.0
            }));
            let want = if n.z == 0.0 && n.x.abs() != 1.0 { std::f32::consts::SQRT_2 } else { 1.0 };
            assert!((area(&lid, n) - want).abs() < 1e-4, "plane {n} {d}: cap area {}", area(&lid, n));
        }
    }

    #[test]
    fn a_torus_cut_through_its_middle_gets_an_annulus_and_a_plane_gets_no_cap() {
        // The torus lies in the xz plane (ring radius 1, tube 0.3): cut at y = 0.
        let torus = shapes::torus(48, 24, 0.3);
        let (kept, lid) = cut(&torus, Vec3::Y, 0.0);
        let lid = lid.expect("a torus closes");
        assert!(closed(&[&kept, &lid]));
        let exact = std::f32::consts::PI * (1.3f32.powi(2) - 0.7f32.powi(2));
        assert!((area(&lid, Vec3::Y) - exact).abs() < 0.03 * exact, "annulus {} against {exact}", area(&lid, Vec3::Y));
        let (_, none) = cut(&shapes::plane(), Vec3::X, 0.1);
        assert!(none.is_none(), "an open mesh's cut does not close");
    }
}
