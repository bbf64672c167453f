//! Ray tracing: the exact answers every raster technique approximates, and the
//! secondary rays of seed 002 §4 (Kawabata, Watanabe & Sakai: reflection and
//! refraction traced from the item
//! buffer).
//!
//! [`TraceScene`] puts a scene's triangles (in world space, with their item ids;
//! [`crate::triangle`] is the watertight ray/triangle test) and its CSG solids (cast by
//! [`crate::csg::CsgCaster`]) behind one [`crate::bvh`], and answers `intersect`
//! (nearest hit), `intersect_packet` (the nearest hits of up to eight coherent
//! rays walked together) and `occluded` (anything before a distance?); [`TraceCache`]
//! keeps it while the geometry stays. [`tracer`] shades what a ray sees, bounces
//! included; [`traced`] is the raster frame's traced term, [`mod@reference`] the
//! ray-traced oracle, both on top of it; [`occlusion`] is ambient occlusion,
//! by rays from the item buffer's exact hits; [`shadow_truth`] holds a shadow
//! method's decisions and antialiased terms to shadow rays.

mod cache;
pub mod occlusion;
pub mod reference;
pub mod shadow_truth;
pub mod traced;
pub mod tracer;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use wide::f32x8;

use std::sync::Arc;

use crate::scene::{Material, Mesh, Scene};

use crate::csg::{CsgCaster, CsgSolid};

use crate::bvh::{Aabb, Bvh, PACKET};
use crate::camera::Ray;
use crate::triangle::{set_bits, RayLanes, ShearedRay, TriangleColumns, LANES};
use crate::visibility::ItemId;

pub use cache::TraceCache;

/// How far off its surface a ray leaving a point starts (along the normal),
/// so it does not meet the surface it leaves: a hair of the scene's size.
#[must_use]
pub fn ray_epsilon(scene: &Scene) -> f32 {
    scene.bounds().map_or(1e-4, |(lo, hi)| (hi - lo).length() * 1e-5)
}

/// The nearest surface along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of its direction's length.
    pub t: f32,
    /// What was hit: a triangle, or a solid's primitive.
    pub item: ItemId,
    /// Barycentric weights of the triangle's second and third vertices (zero
    /// for a solid).
    pub barycentrics: Vec2,
    /// A solid's unit outward normal there (world space; zero for a triangle).
    pub normal: Vec3,
}

/// A scene's triangles and CSG solids in world space behind one BVH: a
/// triangle is a leaf, and so is a whole solid, by its bounds (its rays are
/// cast by [`crate::csg::CsgCaster`]).
#[derive(Debug, Clone)]
pub struct TraceScene {
    /// Per leaf, in leaf order; a solid's leaf holds a triangle of NaNs, which no
    /// ray hits.
    triangles: TriangleColumns,
    items: Vec<ItemId>,
    /// The solids' leaves, sorted, with their object and caster.
    solids: Vec<(u32, u32, CsgCaster)>,
    bvh: Bvh,
    /// Per object, whether it stops shadow rays ([`Object::casts_shadows`]);
    /// empty when every object does.
    ///
    /// [`Object::casts_shadows`]: crate::scene::Object::casts_shadows
    casters: Vec<bool>,
    /// Per object, its mesh and material where the material's alpha test
    /// cuts some of it away (hits there pass through, for every ray);
    /// empty when none does. Taken from the scene the BVH was built for.
    cutouts: Vec<Option<(Arc<Mesh>, Material)>>,
}

impl TraceScene {
    /// Transforms every object's triangles and solids to world space and builds
    /// the BVH.
    #[must_use]
    pub fn new(scene: &Scene) -> TraceScene {
        let casters = if scene.objects.iter().all(|o| o.casts_shadows) {
            Vec::new()
        } else {
            scene.objects.iter().map(|o| o.casts_shadows).collect()
        };
        let cut = |o: &crate::scene::Object| {
            let material = &scene.materials[o.material];
            Some((Arc::clone(o.triangles().filter(|_| material.cuts_out())?), material.clone()))
        };
        let mut cutouts: Vec<_> = scene.objects.iter().map(cut).collect();
        if cutouts.iter().all(Option::is_none) {
            cutouts = Vec::new();
        }
        TraceScene { casters, cutouts, ..Self::built(scene) }
    }

    /// Whether the alpha test (if its material has one) keeps the point of
    /// triangle `item` at barycentrics `b`.
    fn keeps(&self, item: ItemId, b: Vec2) -> bool {
        let Some(Some((mesh, material))) = self.cutouts.get(item.object as usize) else { return true };
        let Some(corners) = mesh.triangles.get(item.triangle as usize) else { return true };
        let uvs = mesh.uvs_of(material.alpha_set());
        let [a, b1, b2] = corners.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
        material.covers(a * (1.0 - b.x - b.y) + b1 * b.x + b2 * b.y)
    }

    /// [`TraceScene::new`] but for which objects cast shadows.
    fn built(scene: &Scene) -> TraceScene {
        let (triangles, items) = Self::mesh_triangles(scene);
        let solids: Vec<(u32, CsgSolid, Aabb)> = scene
            .objects
            .iter()
            .enumerate()
            .filter_map(|(o, obj)| {
                let solid = obj.solid()?.transformed(&obj.transform);
                let (lo, hi) = solid.bounds()?;
                Some((o as u32, solid, Aabb::around(&[lo, hi])))
            })
            .collect();
        if solids.is_empty() {
            return TraceScene::from_triangles(triangles, items);
        }
        // Leaves past the triangles are solids.
        let n = triangles.len();
        let mut bounds: Vec<Aabb> = triangles.par_iter().map(|t| Aabb::around(t)).collect();
        bounds.extend(solids.iter().map(|s| s.2));
        let mut bvh = Bvh::build_lanes(bounds.len(), |i| bounds[i]);
        let order = bvh.renumber();
        let mut solids: Vec<Option<(u32, CsgSolid)>> = solids.into_iter().map(|(o, s, _)| Some((o, s))).collect();
        let mut leaves = Vec::with_capacity(order.len());
        let mut trace = TraceScene {
            triangles: TriangleColumns::default(),
            items: Vec::new(),
            solids: Vec::new(),
            bvh,
            casters: Vec::new(),
            cutouts: Vec::new(),
        };
        for (leaf, &i) in order.iter().enumerate() {
            let i = i as usize;
            if i < n {
                leaves.push(triangles[i]);
                trace.items.push(items[i]);
            } else {
                let (object, solid) = solids[i - n].take().expect("each leaf once");
                leaves.push([Vec3::NAN; 3]);
                trace.items.push(ItemId::primitive_of(object, 0));
                trace.solids.push((leaf as u32, object, CsgCaster::from_solid(solid)));
            }
        }
        trace.triangles = TriangleColumns::new(&leaves);
        trace
    }

    /// The mesh objects' triangles in world space, with their ids.
    fn mesh_triangles(scene: &Scene) -> (Vec<[Vec3; 3]>, Vec<ItemId>) {
        let meshes: Vec<_> = scene
            .objects
            .iter()
            .enumerate()
            .filter_map(|(o, obj)| Some((o as u32, obj.triangles()?, obj.transform)))
            .collect();
        let total = meshes.iter().map(|m| m.1.triangles.len()).sum();
        let (mut triangles, mut items) = (Vec::with_capacity(total), Vec::with_capacity(total));
        // A large mesh's triangles in parallel; small ones (a scene of many
        // parts) one after another, where starting parallel work would cost
        // more than the work.
        for (object, mesh, m) in meshes {
            let world = |tri: &[u32; 3]| tri.map(|i| m.transform_point3(mesh.positions[i as usize]));
            let n = mesh.triangles.len() as u32;
            let id = |triangle| ItemId { object, triangle };
            if n < 1 << 14 {
                triangles.extend(mesh.triangles.iter().map(world));
                items.extend((0..n).map(id));
            } else {
                triangles.par_extend(mesh.triangles.par_iter().with_min_len(1 << 12).map(world));
                items.par_extend((0..n).into_par_iter().map(id));
            }
        }
        (triangles, items)
    }

    /// A trace scene over explicit world-space triangles and their ids.
    #[must_use]
    pub fn from_triangles(triangles: Vec<[Vec3; 3]>, items: Vec<ItemId>) -> TraceScene {
        let mut bvh = Bvh::build_lanes(triangles.len(), |i| Aabb::around(&triangles[i]));
        let order = bvh.renumber();
        let items = order.par_iter().map(|&i| items[i as usize]).collect();
        let triangles = TriangleColumns::in_order(&triangles, &order);
        TraceScene { triangles, items, solids: Vec::new(), bvh, casters: Vec::new(), cutouts: Vec::new() }
    }

    /// The nearest hit along `ray` in `(0, t_max)`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        // Prepared at the first leaf reached (many rays reach none).
        let mut sheared = None;
        let mut hit = Hit { t: 0.0, item: ItemId::NONE, barycentrics: Vec2::ZERO, normal: Vec3::ZERO };
        let (i, t) = self.bvh.intersect_leaves(ray, t_max, |leaf, mut t_max| {
            let sr = *sheared.get_or_insert_with(|| ShearedRay::new(ray));
            let leaves = Self::range(leaf);
            let mut best = None;
            // The leaf's triangles eight at a time (a solid's leaf holds a
            // triangle no ray hits), then its solids.
            for start in leaves.clone().step_by(LANES) {
                let count = (leaves.end - start).min(LANES);
                let lanes = sr.intersect_lanes(&self.triangles, start, count, 0.0, t_max);
                for k in lanes.lanes() {
                    let (t, b, item) = (lanes.t[k], Vec2::new(lanes.b1[k], lanes.b2[k]), self.items[start + k]);
                    if t < t_max && self.keeps(item, b) {
                        (hit.item, hit.barycentrics, hit.normal) = (item, b, Vec3::ZERO);
                        (t_max, best) = (t, Some(((start + k) as u32, t)));
                    }
                }
            }
            for (at, object, caster) in self.solids_in(&leaves) {
                if let Some(c) = caster.first_hit(ray, 0.0, t_max) {
                    (hit.item, hit.barycentrics, hit.normal) =
                        (ItemId::primitive_of(*object, c.primitive), Vec2::ZERO, c.normal);
                    (t_max, best) = (c.t, Some((*at, c.t)));
                }
            }
            best
        })?;
        debug_assert_eq!(hit.item.object, self.items[i as usize].object);
        Some(Hit { t, ..hit })
    }

    /// [`TraceScene::intersect`] of up to [`PACKET`] rays walked through the
    /// BVH together (coherent rays: a block of pixels' primary rays, a
    /// mirror's reflections), each leaf's triangles tested once for all the
    /// rays that reach it. Each ray's hit is the one it finds alone (on an
    /// exact tie in distance between two triangles either may be named).
    ///
    /// # Panics
    /// If `rays` is empty or longer than [`PACKET`].
    #[must_use]
    pub fn intersect_packet(&self, rays: &[Ray], t_max: f32) -> [Option<Hit>; PACKET] {
        assert!((1..=PACKET).contains(&rays.len()), "{} rays in a packet", rays.len());
        let padded: [Ray; PACKET] = std::array::from_fn(|i| rays[i.min(rays.len() - 1)]);
        let lanes = (1u32 << rays.len()) - 1;
        let sheared = RayLanes::new(&padded);
        let mut hits = [None; PACKET];
        let mut t = [t_max; PACKET];
        self.bvh.intersect_packet_leaves(&sheared, lanes, &mut t, |leaf, mask, t| {
            let leaves = Self::range(leaf);
            let mut found = |k: usize, i: usize, d: f32, b: Vec2, t: &mut [f32; PACKET]| {
                let item = self.items[i];
                if d < t[k] && self.keeps(item, b) {
                    t[k] = d;
                    hits[k] = Some(Hit { t: d, item, barycentrics: b, normal: Vec3::ZERO });
                }
            };
            if (mask.count_ones() as usize) < leaves.len() {
                // Fewer rays than triangles: each ray tests the leaf's
                // triangles eight at a time, as it would alone.
                for k in set_bits(mask) {
                    let sr = sheared.lane(k);
                    for start in leaves.clone().step_by(LANES) {
                        let count = (leaves.end - start).min(LANES);
                        let lanes = sr.intersect_lanes(&self.triangles, start, count, 0.0, t[k]);
                        for j in lanes.lanes() {
                            found(k, start + j, lanes.t[j], Vec2::new(lanes.b1[j], lanes.b2[j]), t);
                        }
                    }
                }
            } else {
                for i in leaves.clone() {
                    let lanes = sheared.intersect_triangle(&self.triangles, i, mask, 0.0, f32x8::from(*t));
                    for k in lanes.lanes() {
                        found(k, i, lanes.t[k], Vec2::new(lanes.b1[k], lanes.b2[k]), t);
                    }
                }
            }
            for (_, object, caster) in self.solids_in(&leaves) {
                for k in set_bits(mask) {
                    if let Some(c) = caster.first_hit(&padded[k], 0.0, t[k]) {
                        t[k] = c.t;
                        let item = ItemId::primitive_of(*object, c.primitive);
                        hits[k] = Some(Hit { t: c.t, item, barycentrics: Vec2::ZERO, normal: c.normal });
                    }
                }
            }
        });
        hits
    }

    /// The leaves (triangles and solids) of a BVH leaf: consecutive numbers,
    /// since the trace scene renumbers its leaves in the BVH's order.
    fn range(leaf: &[u32]) -> std::ops::Range<usize> {
        debug_assert!(leaf.windows(2).all(|w| w[1] == w[0] + 1), "renumbered leaves");
        leaf[0] as usize..leaf[0] as usize + leaf.len()
    }

    /// The solids among `leaves`.
    fn solids_in(&self, leaves: &std::ops::Range<usize>) -> &[(u32, u32, CsgCaster)] {
        if self.solids.is_empty() {
            return &[];
        }
        let from = self.solids.partition_point(|s| (s.0 as usize) < leaves.start);
        let to = from + self.solids[from..].partition_point(|s| (s.0 as usize) < leaves.end);
        &self.solids[from..to]
    }

    /// Whether anything that casts shadows lies along `ray` in `(0, t_max)`
    /// (shadow rays).
    #[must_use]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut sheared = None;
        let casts = |object: u32| self.casters.is_empty() || self.casters[object as usize];
        self.bvh.occluded_leaves(ray, t_max, |leaf, t_max| {
            let sr = *sheared.get_or_insert_with(|| ShearedRay::new(ray));
            let leaves = Self::range(leaf);
            let triangles = leaves.clone().step_by(LANES).any(|start| {
                let count = (leaves.end - start).min(LANES);
                let lanes = sr.intersect_lanes(&self.triangles, start, count, 0.0, t_max);
                lanes.lanes().any(|k| {
                    let item = self.items[start + k];
                    casts(item.object) && self.keeps(item, Vec2::new(lanes.b1[k], lanes.b2[k]))
                })
            });
            triangles
                || self
                    .solids_in(&leaves)
                    .iter()
                    .any(|(_, object, caster)| casts(*object) && caster.first_hit(ray, 0.0, t_max).is_some())
        })
    }

    /// Number of leaves (triangles and solids).
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no leaves.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// The world-space triangle of primitive `i`.
    ///
    /// # Panics
    /// If `i` is not below [`TraceScene::len`].
    #[must_use]
    pub fn triangle(&self, i: usize) -> [Vec3; 3] {
        self.triangles.get(i)
    }

    /// The BVH.
    #[must_use]
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
}
