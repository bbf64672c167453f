//! The casters' triangles as a light sees them: each mesh triangle of a
//! shadow-casting object through the light's camera, clipped in homogeneous
//! space (near and far planes, a band just outside the map), as texel
//! coordinates and the reversed depth the shadow map stores.

use glam::{DMat4, DVec3, DVec4, Mat4};
use rayon::prelude::*;

use super::line::Facing;
use crate::camera::Camera;
use crate::scene::Scene;
use crate::visibility::{ClipPlanes, MAX_CLIPPED};

/// One caster triangle as the light sees it: texel coordinates (x right, y
/// down) and reversed depth (larger nearer the light) per vertex.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LightTriangle {
    /// The corners: x, y in texels, z reversed depth.
    pub points: [DVec3; 3],
    /// The object it belongs to.
    pub object: u32,
    /// Its index among its object's triangles (the Polygon ID).
    pub polygon: u32,
    /// Bit `i`: edge `i` (corner `i` to corner `i + 1`) is no silhouette
    /// and is not walked (a side of a solid's outline band lying inside the
    /// solid; 0 for a mesh's triangles).
    pub open: u8,
    /// Which way it faces the light (a mesh's triangle by its winding; a
    /// solid's outline band: not known).
    pub facing: Facing,
}

/// How a mesh triangle with corners `points` (texel coordinates, y down)
/// faces the light: one wound counter-clockwise about its normal runs
/// clockwise on the map (y down) when the normal points at the light.
fn facing(points: &[DVec3; 3]) -> Facing {
    let [a, b, c] = points;
    let turn = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if turn < 0.0 {
        Facing::Light
    } else if turn > 0.0 {
        Facing::Away
    } else {
        Facing::Unknown
    }
}

/// Texels of band beyond the map's sides that clipping keeps.
const BAND_TEXELS: f64 = 4.0;

/// Triangles of one mesh one task takes.
const TRIANGLES_A_TASK: usize = 8192;

/// The mesh triangles of the objects `casters` marks, seen by `camera` in a
/// `resolution` × `resolution` map.
#[must_use]
pub fn light_triangles(scene: &Scene, camera: &Camera, resolution: u32, casters: &[bool]) -> Vec<LightTriangle> {
    let view_proj = camera.view_projection(1.0).as_dmat4();
    let band = 1.0 + 2.0 * BAND_TEXELS / f64::from(resolution.max(1));
    let planes = ClipPlanes::new(f64::from(camera.far_plane_factor()), band, band);
    let n = f64::from(resolution);
    let to_texels = |c: DVec4| {
        let inv_w = 1.0 / c.w;
        DVec3::new((c.x * inv_w * 0.5 + 0.5) * n, (0.5 - c.y * inv_w * 0.5) * n, c.z * inv_w)
    };
    scene
        .objects
        .par_iter()
        .enumerate()
        .filter(|(i, _)| casters.get(*i).copied().unwrap_or(false))
        .flat_map_iter(|(i, object)| {
            let Some(mesh) = object.triangles().cloned() else { return Vec::new().into_iter() };
            let m: DMat4 = view_proj * Mat4::from(object.transform).as_dmat4();
            // A large mesh (a scanned model is one object) is cut among the
            // workers too, not left to the one that took the object.
            let clip: Vec<DVec4> =
                mesh.positions.par_iter().with_min_len(4096).map(|p| m * p.as_dvec3().extend(1.0)).collect();
            let codes: Vec<u8> = clip.par_iter().with_min_len(4096).map(|c| planes.outcode(c.as_vec4())).collect();
            let pieces = mesh.triangles.par_chunks(TRIANGLES_A_TASK).enumerate();
            let triangles = pieces.flat_map_iter(|(piece, tris)| {
                let mut out = Vec::new();
                for (k, tri) in tris.iter().enumerate() {
                    let [a, b, c] = tri.map(|k| k as usize);
                    let (ca, cb, cc) = (codes[a], codes[b], codes[c]);
                    if ca & cb & cc != 0 {
                        continue; // wholly outside one plane
                    }
                    let corners = [clip[a], clip[b], clip[c]];
                    let (object, polygon) = (i as u32, (piece * TRIANGLES_A_TASK + k) as u32);
                    if ca | cb | cc == 0 {
                        let points = corners.map(to_texels);
                        out.push(LightTriangle { points, object, polygon, open: 0, facing: facing(&points) });
                        continue;
                    }
                    let mut poly = [DVec4::ZERO; MAX_CLIPPED];
                    let n = planes.clip(corners, ca | cb | cc, &mut poly);
                    for j in 1..n.saturating_sub(1) {
                        let points = [poly[0], poly[j], poly[j + 1]].map(to_texels);
                        out.push(LightTriangle { points, object, polygon, open: 0, facing: facing(&points) });
                    }
                }
                out
            });
            triangles.collect::<Vec<_>>().into_iter()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::{Affine3A, Vec2, Vec3};

    use super::*;
    use crate::camera::Projection;
    use crate::scene::mesh::shapes;
    use crate::scene::{Material, Object};

    /// A light at `eye` looking at the origin.
    fn light_at(eye: Vec3, projection: Projection) -> Camera {
        Camera { eye, target: Vec3::ZERO, up: Vec3::Z, near: 0.1, far: 20.0, projection, shift: Vec2::ZERO }
    }

    /// A triangle whose winding normal points at the light faces it, one
    /// seen from its back faces away, for perspective and orthographic
    /// lights alike (the receiver's side of the same test is [`Facing::of`]).
    #[test]
    fn a_triangle_wound_towards_the_light_faces_it() {
        let mut scene = Scene::new(8, 8, light_at(Vec3::Y, Projection::Perspective { fov_y_deg: 40.0 }));
        scene.materials.push(Material::default());
        scene.objects.push(Object::mesh("plane", Arc::new(shapes::plane()), Affine3A::IDENTITY, 0));
        for projection in [Projection::Perspective { fov_y_deg: 60.0 }, Projection::Orthographic { height: 3.0 }] {
            for (eye, want) in [(Vec3::Y * 4.0, Facing::Light), (-Vec3::Y * 4.0, Facing::Away)] {
                let camera = light_at(eye + Vec3::X * 0.3, projection);
                let triangles = light_triangles(&scene, &camera, 64, &[true]);
                assert_eq!(triangles.len(), 2);
                assert!(triangles.iter().all(|t| t.facing == want), "from {eye}: {triangles:?}");
                assert_eq!(Facing::of(Vec3::Y, eye), want);
            }
        }
    }
}
