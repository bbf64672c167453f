//! The alpha test of cut-out materials (glTF's MASK mode, leaves and fences
//! painted on a few quads): a pixel of such a triangle is drawn only where
//! the material's alpha at the pixel centre reaches its cutoff, in the
//! eye's pass and in the lights' depth passes alike, so what is cut away
//! neither hides nor shadows what lies behind it.
//!
//! The texture coordinates at a pixel centre come from the triangle's
//! perspective-correct barycentric weights. With the vertices in clip space
//! `(xₖ, yₖ, wₖ)`, the point of the triangle that projects to (sx, sy) has
//! weights `b ∝ M⁻¹ (sx, sy, 1)` where M's columns are the vertices (Olano
//! and Greer, "Triangle scan conversion using 2D homogeneous coordinates",
//! Graphics Hardware 1997): linear in the pixel's position up to the common
//! factor, so one 3 × 3 inverse a triangle and three dot products a pixel.
//! It holds for clipped triangles (the original vertices are used) and for
//! orthographic cameras alike.

use glam::{DMat3, DMat4, DVec3, DVec4, Vec2};

use super::ItemId;
use crate::scene::{Material, Mesh, Scene};

/// Per object, what its alpha test needs (`None` where its material cuts
/// nothing away), and the map from pixels to normalized device coordinates.
pub(super) struct Cutouts<'a> {
    objects: Vec<Option<CutoutObject<'a>>>,
    /// (x, y, 1) of a pixel (integer indices; its centre) to (sx, sy, 1).
    to_ndc: DMat3,
}

struct CutoutObject<'a> {
    material: &'a Material,
    mesh: &'a Mesh,
    to_clip: DMat4,
}

impl<'a> Cutouts<'a> {
    /// The alpha tests of `scene`'s objects, seen through `to_clip` (per
    /// object: object space to clip space) on a `width × height` image.
    pub(super) fn new(scene: &'a Scene, to_clip: impl Fn(usize) -> DMat4, width: usize, height: usize) -> Self {
        let objects = scene
            .objects
            .iter()
            .enumerate()
            .map(|(i, o)| {
                let material = &scene.materials[o.material];
                let mesh = o.triangles().filter(|_| material.cuts_out())?;
                Some(CutoutObject { material, mesh, to_clip: to_clip(i) })
            })
            .collect();
        Cutouts { objects, to_ndc: Self::pixel_to_ndc(width, height) }
    }

    /// (x, y, 1) of pixel (x, y)'s centre to its device coordinates (sx, sy, 1).
    fn pixel_to_ndc(width: usize, height: usize) -> DMat3 {
        let (w, h) = (width as f64, height as f64);
        DMat3::from_cols(
            DVec3::new(2.0 / w, 0.0, 0.0),
            DVec3::new(0.0, -2.0 / h, 0.0),
            DVec3::new(1.0 / w - 1.0, 1.0 - 1.0 / h, 1.0),
        )
    }

    /// Whether no object is cut.
    pub(super) fn is_empty(&self) -> bool {
        self.objects.iter().all(Option::is_none)
    }

    /// The test of `item`'s pixels, or `None` where every pixel is kept.
    pub(super) fn triangle(&self, item: ItemId) -> Option<CutoutTriangle<'a>> {
        let o = self.objects.get(item.object as usize)?.as_ref()?;
        let corners = *o.mesh.triangles.get(item.triangle as usize)?;
        let clip = corners.map(|i| o.to_clip * o.mesh.positions[i as usize].as_dvec3().extend(1.0));
        let weights = pixel_weights(clip, self.to_ndc)?;
        let uvs = o.mesh.uvs_of(o.material.alpha_set());
        let uv = corners.map(|i| uvs.get(i as usize).copied().unwrap_or(Vec2::ZERO));
        Some(CutoutTriangle { material: o.material, weights, uv })
    }
}

/// One triangle's alpha test at pixel centres.
pub(super) struct CutoutTriangle<'a> {
    material: &'a Material,
    /// (x, y, 1) of a pixel to its barycentric weights, up to a common factor.
    weights: DMat3,
    uv: [Vec2; 3],
}

impl CutoutTriangle<'_> {
    /// Whether the material keeps the triangle's surface at pixel (x, y).
    pub(super) fn covers(&self, x: i64, y: i64) -> bool {
        let Some(b) = barycentrics(&self.weights, x as f64, y as f64) else { return true };
        let b = b.as_vec3();
        self.material.covers(self.uv[0] * b.x + self.uv[1] * b.y + self.uv[2] * b.z)
    }
}

/// The map from a pixel's (x, y, 1) to the perspective-correct barycentric
/// weights (up to a common factor) of the triangle whose clip-space vertices
/// are `clip`, given the pixel → device map `to_ndc`; `None` for a triangle
/// seen edge-on or through the eye.
fn pixel_weights(clip: [DVec4; 3], to_ndc: DMat3) -> Option<DMat3> {
    let [a, b, c] = clip.map(|c| DVec3::new(c.x, c.y, c.w));
    let m = DMat3::from_cols(a, b, c);
    (m.determinant().abs() >= f64::MIN_POSITIVE).then(|| m.inverse() * to_ndc)
}

/// The barycentric weights at pixel (x, y), summing to 1.
fn barycentrics(weights: &DMat3, x: f64, y: f64) -> Option<DVec3> {
    let b = *weights * DVec3::new(x, y, 1.0);
    let sum = b.x + b.y + b.z;
    (sum != 0.0 && sum.is_finite()).then(|| b / sum)
}

#[cfg(test)]
mod tests {
    use glam::{DVec2, Vec3};

    use super::*;
    use crate::camera::{Camera, Projection};

    /// Against the point itself: a point chosen on a random triangle in
    /// front of a perspective camera, projected to the pixel grid, gives back
    /// its own barycentric weights.
    #[test]
    fn pixel_weights_recover_the_projected_points_barycentrics() {
        let (w, h) = (640.0, 480.0);
        let to_ndc = Cutouts::pixel_to_ndc(640, 480);
        let camera = Camera {
            eye: Vec3::new(0.3, 0.5, 4.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            near: 0.1,
            far: 100.0,
            projection: Projection::Perspective { fov_y_deg: 50.0 },
            shift: Vec2::ZERO,
        };
        let proj: DMat4 = camera.view_projection((w / h) as f32).as_dmat4();
        let mut seed = 7u64;
        let mut next = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..200 {
            let corners: [DVec3; 3] = std::array::from_fn(|_| DVec3::new(next(), next(), next()) * 4.0 - 2.0);
            let (u, v) = (next(), next());
            let want =
                if u + v > 1.0 { DVec3::new(u + v - 1.0, 1.0 - u, 1.0 - v) } else { DVec3::new(1.0 - u - v, u, v) };
            let p = corners[0] * want.x + corners[1] * want.y + corners[2] * want.z;
            let c = proj * p.extend(1.0);
            // The pixel whose centre is the point (fractional indices).
            let pixel = DVec2::new((c.x / c.w * 0.5 + 0.5) * w - 0.5, (0.5 - c.y / c.w * 0.5) * h - 0.5);
            let clip = corners.map(|q| proj * q.extend(1.0));
            let Some(weights) = pixel_weights(clip, to_ndc) else { continue };
            let got = barycentrics(&weights, pixel.x, pixel.y).unwrap();
            assert!((got - want).abs().max_element() < 1e-6, "{got} vs {want}");
        }
    }
}
