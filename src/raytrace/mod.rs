//! Ray tracing: the exact answers every raster technique approximates, and the
//! secondary rays of seed 002 §4 (Kawabata, Watanabe & Sakai: reflection and
//! refraction traced from the item
//! buffer).
//!
//! [`TraceScene`] puts a scene's triangles (in world space, with their item ids;
//! [`crate::triangle`] is the watertight ray/triangle test) and its CSG solids (cast by
//! [`crate::csg::CsgCaster`]) behind one [`crate::bvh`], and answers `intersect`
//! (nearest hit) and `occluded` (anything before a distance?); [`TraceCache`]
//! keeps it while the geometry stays. [`tracer`] shades what a ray sees, bounces
//! included; [`traced`] is the raster frame's traced term, [`mod@reference`] the
//! ray-traced oracle, both on top of it; [`shadow_truth`] holds a shadow
//! method's decisions and antialiased terms to shadow rays.

mod cache;
pub mod reference;
pub mod shadow_truth;
pub mod traced;
pub mod tracer;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use std::sync::Arc;

use crate::scene::{Material, Mesh, Scene};

use crate::csg::{CsgCaster, CsgSolid};

use crate::bvh::{Aabb, Bvh};
use crate::camera::Ray;
use crate::triangle::ShearedRay;
use crate::visibility::ItemId;

pub use cache::TraceCache;

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
    /// Per leaf, in leaf order; a solid's leaf holds a triangle that no ray hits.
    triangles: Vec<[Vec3; 3]>,
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
        let mut bvh = Bvh::build(&bounds);
        let order = bvh.renumber();
        let mut solids: Vec<Option<(u32, CsgSolid)>> = solids.into_iter().map(|(o, s, _)| Some((o, s))).collect();
        let mut trace = TraceScene {
            triangles: Vec::new(),
            items: Vec::new(),
            solids: Vec::new(),
            bvh,
            casters: Vec::new(),
            cutouts: Vec::new(),
        };
        for (leaf, &i) in order.iter().enumerate() {
            let i = i as usize;
            if i < n {
                trace.triangles.push(triangles[i]);
                trace.items.push(items[i]);
            } else {
                let (object, solid) = solids[i - n].take().expect("each leaf once");
                trace.triangles.push([Vec3::ZERO; 3]);
                trace.items.push(ItemId::primitive_of(object, 0));
                trace.solids.push((leaf as u32, object, CsgCaster::from_solid(solid)));
            }
        }
        trace
    }

    /// The mesh objects' triangles in world space, with their ids.
    fn mesh_triangles(scene: &Scene) -> (Vec<[Vec3; 3]>, Vec<ItemId>) {
        let (triangles, items): (Vec<[Vec3; 3]>, Vec<ItemId>) = scene
            .objects
            .par_iter()
            .enumerate()
            .filter_map(|(o, obj)| Some((o, obj.triangles()?, obj.transform)))
            .flat_map_iter(|(o, mesh, m)| {
                mesh.triangles.iter().enumerate().map(move |(t, tri)| {
                    let p = tri.map(|i| m.transform_point3(mesh.positions[i as usize]));
                    (p, ItemId { object: o as u32, triangle: t as u32 })
                })
            })
            .unzip();
        (triangles, items)
    }

    /// A trace scene over explicit world-space triangles and their ids.
    #[must_use]
    pub fn from_triangles(triangles: Vec<[Vec3; 3]>, items: Vec<ItemId>) -> TraceScene {
        let bounds: Vec<Aabb> = triangles.par_iter().map(|t| Aabb::around(t)).collect();
        let mut bvh = Bvh::build(&bounds);
        let order = bvh.renumber();
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        let items = order.iter().map(|&i| items[i as usize]).collect();
        TraceScene { triangles, items, solids: Vec::new(), bvh, casters: Vec::new(), cutouts: Vec::new() }
    }

    /// The solid at leaf `i`, if that leaf is one.
    fn solid_at(&self, i: u32) -> Option<&(u32, u32, CsgCaster)> {
        if self.solids.is_empty() {
            return None;
        }
        self.solids.binary_search_by_key(&i, |s| s.0).ok().map(|k| &self.solids[k])
    }

    /// The nearest hit along `ray` in `(0, t_max)`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let sr = ShearedRay::new(ray);
        let mut hit = Hit { t: 0.0, item: ItemId::NONE, barycentrics: Vec2::ZERO, normal: Vec3::ZERO };
        let (i, t) = self.bvh.intersect(ray, t_max, |i, t_max| {
            if let Some((_, object, caster)) = self.solid_at(i) {
                let c = caster.first_hit(ray, 0.0, t_max)?;
                hit.item = ItemId::primitive_of(*object, c.primitive);
                hit.normal = c.normal;
                return Some(c.t);
            }
            let (t, b) = sr.intersect(&self.triangles[i as usize], 0.0, t_max)?;
            if !self.keeps(self.items[i as usize], b) {
                return None;
            }
            (hit.item, hit.barycentrics, hit.normal) = (self.items[i as usize], b, Vec3::ZERO);
            Some(t)
        })?;
        debug_assert_eq!(hit.item.object, self.items[i as usize].object);
        Some(Hit { t, ..hit })
    }

    /// Whether anything that casts shadows lies along `ray` in `(0, t_max)`
    /// (shadow rays).
    #[must_use]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let sr = ShearedRay::new(ray);
        self.bvh.occluded(ray, t_max, |i, t_max| match self.solid_at(i) {
            _ if !self.casters.is_empty() && !self.casters[self.items[i as usize].object as usize] => None,
            Some((_, _, caster)) => caster.first_hit(ray, 0.0, t_max).map(|c| c.t),
            None => sr
                .intersect(&self.triangles[i as usize], 0.0, t_max)
                .filter(|&(_, b)| self.keeps(self.items[i as usize], b))
                .map(|h| h.0),
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
    #[must_use]
    pub fn triangle(&self, i: usize) -> &[Vec3; 3] {
        &self.triangles[i]
    }

    /// The BVH.
    #[must_use]
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }
}
