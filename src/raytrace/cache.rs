//! A [`TraceScene`] kept from frame to frame. An interactive preview re-renders the
//! same geometry from new viewpoints, under new lights and materials; only a change
//! of geometry (a mesh, an object's transform, or whether it casts shadows:
//! [`GeometryKey`]) needs a new BVH. Jittered passes of one frame (seed 002 §4)
//! share it too.

use super::TraceScene;
use crate::scene::{GeometryKey, Scene};

/// The BVH of the last scene traced, and what it was built from.
#[derive(Debug, Default)]
pub struct TraceCache {
    key: GeometryKey,
    trace: Option<TraceScene>,
    builds: usize,
}

impl TraceCache {
    /// The trace scene of `scene`'s geometry, built only if the geometry differs
    /// from the last call's.
    pub fn get(&mut self, scene: &Scene) -> &TraceScene {
        if !self.key.matches(scene) || self.trace.is_none() {
            self.key = GeometryKey::of(scene);
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
        scene.objects[0].transform = glam::Affine3A::from_translation(glam::Vec3::X) * scene.objects[0].transform;
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
