//! The casters' triangles as a light sees them: each mesh triangle of a
//! shadow-casting object through the light's camera, clipped in homogeneous
//! space (near and far planes, a band just outside the map), as texel
//! coordinates and the reversed depth the shadow map stores.

use glam::{DMat4, DVec3, DVec4, Mat4};
use rayon::prelude::*;

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
}

/// Texels of band beyond the map's sides that clipping keeps.
const BAND_TEXELS: f64 = 4.0;

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
            let mesh = object.triangles().cloned();
            let m: DMat4 = view_proj * Mat4::from(object.transform).as_dmat4();
            let clip: Vec<DVec4> = mesh
                .as_ref()
                .map_or_else(Vec::new, |mesh| mesh.positions.iter().map(|p| m * p.as_dvec3().extend(1.0)).collect());
            let codes: Vec<u8> = clip.iter().map(|c| planes.outcode(c.as_vec4())).collect();
            let mut out = Vec::new();
            let Some(mesh) = mesh else { return out.into_iter() };
            for (t, tri) in mesh.triangles.iter().enumerate() {
                let [a, b, c] = tri.map(|k| k as usize);
                let (ca, cb, cc) = (codes[a], codes[b], codes[c]);
                if ca & cb & cc != 0 {
                    continue; // wholly outside one plane
                }
                let corners = [clip[a], clip[b], clip[c]];
                let object = i as u32;
                let polygon = t as u32;
                if ca | cb | cc == 0 {
                    out.push(LightTriangle { points: corners.map(to_texels), object, polygon, open: 0 });
                    continue;
                }
                let mut poly = [DVec4::ZERO; MAX_CLIPPED];
                let k = planes.clip(corners, ca | cb | cc, &mut poly);
                for j in 1..k.saturating_sub(1) {
                    let points = [poly[0], poly[j], poly[j + 1]].map(to_texels);
                    out.push(LightTriangle { points, object, polygon, open: 0 });
                }
            }
            out.into_iter()
        })
        .collect()
}
