//! Ray tracing: the exact answers every raster technique approximates, and the
//! secondary rays of seed 002 §4 (reflection and refraction traced from the item
//! buffer).
//!
//! [`bvh`] is the acceleration structure (binned SAH), [`triangle`] the watertight
//! ray/triangle test; [`TraceScene`] puts a scene's triangles, in world space and
//! with their item ids, behind one BVH and answers `intersect` (nearest hit) and
//! `occluded` (anything before a distance?). [`csg`] casts rays at CSG solids.

pub mod bvh;
pub mod cache;
pub mod csg;
pub mod item_buffer;
pub mod reference;
pub mod triangle;

use glam::{Vec2, Vec3};
use rayon::prelude::*;

use crate::scene::{Ray, Scene};
use crate::visibility::ItemId;
use bvh::{Aabb, Bvh};
use triangle::ShearedRay;

pub use cache::TraceCache;

/// The nearest surface along a ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Distance along the ray, in units of its direction's length.
    pub t: f32,
    /// What was hit.
    pub item: ItemId,
    /// Barycentric weights of the triangle's second and third vertices.
    pub barycentrics: Vec2,
}

/// A scene's triangles in world space behind a BVH.
#[derive(Debug, Clone)]
pub struct TraceScene {
    triangles: Vec<[Vec3; 3]>,
    items: Vec<ItemId>,
    bvh: Bvh,
}

impl TraceScene {
    /// Transforms every object's triangles to world space and builds the BVH.
    #[must_use]
    pub fn new(scene: &Scene) -> TraceScene {
        let (triangles, items): (Vec<[Vec3; 3]>, Vec<ItemId>) = scene
            .objects
            .par_iter()
            .enumerate()
            .flat_map_iter(|(o, obj)| {
                let m = obj.transform;
                obj.mesh.triangles.iter().enumerate().map(move |(t, tri)| {
                    let p = tri.map(|i| m.transform_point3(obj.mesh.positions[i as usize]));
                    (p, ItemId { object: o as u32, triangle: t as u32 })
                })
            })
            .unzip();
        TraceScene::from_triangles(triangles, items)
    }

    /// A trace scene over explicit world-space triangles and their ids.
    #[must_use]
    pub fn from_triangles(triangles: Vec<[Vec3; 3]>, items: Vec<ItemId>) -> TraceScene {
        let bounds: Vec<Aabb> = triangles.par_iter().map(|t| Aabb::around(t)).collect();
        let mut bvh = Bvh::build(&bounds);
        let order = bvh.renumber();
        let triangles = order.iter().map(|&i| triangles[i as usize]).collect();
        let items = order.iter().map(|&i| items[i as usize]).collect();
        TraceScene { triangles, items, bvh }
    }

    /// The nearest hit along `ray` in `(0, t_max)`.
    #[must_use]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        let sr = ShearedRay::new(ray);
        let mut bary = Vec2::ZERO;
        let (i, t) = self.bvh.intersect(ray, t_max, |i, t_max| {
            let (t, b) = sr.intersect(&self.triangles[i as usize], 0.0, t_max)?;
            bary = b;
            Some(t)
        })?;
        Some(Hit { t, item: self.items[i as usize], barycentrics: bary })
    }

    /// Whether anything lies along `ray` in `(0, t_max)` (shadow rays).
    #[must_use]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let sr = ShearedRay::new(ray);
        self.bvh.occluded(ray, t_max, |i, t_max| sr.intersect(&self.triangles[i as usize], 0.0, t_max).map(|h| h.0))
    }

    /// Number of triangles.
    #[must_use]
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
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
