//! A [`TraceScene`] kept from frame to frame. An interactive preview re-renders the
//! same geometry from new viewpoints, under new lights and materials; only a change
//! of geometry (a mesh or an object's transform, or whether it casts shadows)
//! needs a new BVH. Jittered passes of
//! one frame (seed 002 §4) share it too.
//!
//! The key holds a clone of every object's body (its `Arc<Mesh>` or
//! `Arc<CsgSolid>`): while the cache holds it, no one can change that geometry in place (`Arc::get_mut` fails and `Arc::make_mut`
//! copies), so pointer equality is a sound test of "the same geometry".

use glam::Affine3A;

use super::TraceScene;
use crate::scene::{Body, Scene};

/// The BVH of the last scene traced, and what it was built from.
#[derive(Debug, Default)]
pub struct TraceCache {
    key: Vec<(Body, Affine3A, bool)>,
    trace: Option<TraceScene>,
    builds: usize,
}

impl TraceCache {
    /// The trace scene of `scene`'s geometry, built only if the geometry differs
    /// from the last call's.
    pub fn get(&mut self, scene: &Scene) -> &TraceScene {
        let same = self.key.len() == scene.objects.len()
            && self
                .key
                .iter()
                .zip(&scene.objects)
                .all(|((b, t, c), o)| b.same(&o.body) && *t == o.transform && *c == o.casts_shadows);
        if !same || self.trace.is_none() {
            self.key = scene.objects.iter().map(|o| (o.body.clone(), o.transform, o.casts_shadows)).collect();
            self.builds += 1;
            self.trace = None;
        }
        self.trace.get_or_insert_with(|| TraceScene::new(scene))
    }

    /// How many times a BVH has been built.
    #[must_use]
    pub fn builds(&self) -> usize {
        self.builds
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::demo::demo_scene;

    #[test]
    fn rebuilds_only_when_geometry_changes() {
        let mut scene = demo_scene().expect("the demo loads");
        assert!(scene.objects.len() >= 2);
        let mut cache = TraceCache::default();
        let n = cache.get(&scene).len();
        scene.camera.eye *= 1.5;
        scene.lights.clear();
        cache.get(&scene);
        assert_eq!(cache.builds(), 1, "a new viewpoint and lights keep the BVH");
        scene.objects[0].transform = Affine3A::from_translation(glam::Vec3::X) * scene.objects[0].transform;
        cache.get(&scene);
        assert_eq!(cache.builds(), 2, "a moved object needs a new BVH");
        let crate::scene::Body::Mesh(mesh) = &mut scene.objects[0].body else {
            panic!("the demo's objects are meshes")
        };
        let mesh = std::sync::Arc::make_mut(mesh);
        mesh.triangles.truncate(1);
        let m = cache.get(&scene).len();
        assert_eq!(cache.builds(), 3, "an edited mesh needs a new BVH");
        assert!(m < n);
        scene.objects.pop();
        cache.get(&scene);
        assert_eq!(cache.builds(), 4, "a removed object needs a new BVH");
    }
}
