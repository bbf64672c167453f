//! Normal maps (glTF 2.0 `normalTexture`): a texture of unit normals in the
//! surface's tangent frame, tilting the shading normal texel by texel so flat
//! triangles show the bumps and grooves a model was baked with.
//!
//! The tangent frame is the one glTF defines without a `TANGENT` attribute:
//! x along increasing texture u (∂P/∂u), y up the image (−∂P/∂v, glTF's v
//! runs down), z the interpolated normal; x and y are made perpendicular to z
//! (Gram–Schmidt), so the frame turns with the smooth normal across a
//! triangle. ∂P/∂u and ∂P/∂v are taken per triangle, as a renderer does from
//! screen-space derivatives when a file has no tangents; a map baked against
//! per-vertex (MikkTSpace) tangents differs from it only where the texture
//! coordinates shear across neighbouring triangles. Seen from behind, the
//! frame's x and y turn round with z, as the glTF sample viewer does for
//! double-sided materials.

use glam::Vec3;

use super::surface::SurfacePoint;
use crate::scene::material::Filter;
use crate::scene::{Material, NormalMap, SharedFootprint};

/// Least cosine between a tilted normal and the direction to the eye: a map
/// may tilt a normal past the silhouette, where it would shade as the
/// surface's far side; it is held just short of it.
const MIN_FACING: f32 = 1e-3;

/// Tilts `s.normal` by `m`'s normal map, if it has one.
pub fn apply(m: &Material, s: &mut SurfacePoint) {
    apply_shared(m, s, &mut SharedFootprint::default());
}

/// [`apply`], the map's footprint shared with the point's other maps
/// through `shared`.
pub fn apply_shared<'a>(m: &'a Material, s: &mut SurfacePoint, shared: &mut SharedFootprint<'a>) {
    if let Some(map) = &m.maps.normal {
        s.normal = tilted(map, m.maps.filter, s, shared);
    }
}

/// The normal at `s` tilted by `map` (sampled with `filter` over the point's
/// footprint); `s.normal` unchanged where the point has no tangent frame.
fn tilted<'a>(map: &'a NormalMap, filter: Filter, s: &SurfacePoint, shared: &mut SharedFootprint<'a>) -> Vec3 {
    let n = s.normal;
    let [dpdu, dpdv] = s.tangents;
    let t = (dpdu - n * n.dot(dpdu)).normalize_or_zero();
    // What Gram–Schmidt leaves of −∂P/∂v, perpendicular to the unit n and
    // t, lies along n × t (already of unit length): only its side is needed.
    let up = n.cross(t);
    let handedness = up.dot(-dpdv);
    if t == Vec3::ZERO || handedness == 0.0 || !handedness.is_finite() {
        return n;
    }
    let b = if handedness > 0.0 { up } else { -up };
    let (uv, duv) = s.coords(map.texture.set);
    let texel = shared.sample(&map.texture, filter, uv, duv);
    let local = texel * 2.0 - Vec3::ONE;
    // The eye on the back: `n` was turned round, and x and y turn with it.
    let side = if s.front { 1.0 } else { -1.0 };
    let tilted = (t * local.x + b * local.y) * (side * map.scale) + n * local.z;
    let tilted = tilted.normalize_or(n);
    let facing = tilted.dot(s.to_eye);
    if facing >= MIN_FACING {
        tilted
    } else {
        (tilted + s.to_eye * (MIN_FACING - facing)).normalize_or(n)
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use glam::Vec2;

    use super::*;
    use crate::scene::Texture;

    /// A square of the xz plane seen from above: u along +x, v along +z (down
    /// the image is +z), normal +y.
    fn point(tangents: [Vec3; 2]) -> SurfacePoint {
        SurfacePoint {
            position: Vec3::ZERO,
            normal: Vec3::Y,
            to_eye: Vec3::Y,
            uv: Vec2::splat(0.5),
            duv: [Vec2::ZERO; 2],
            tangents,
            material: 0,
            front: true,
            color: Vec3::ONE,
            second: glam::Affine2::IDENTITY,
        }
    }

    fn tilted_normal(map: &NormalMap, filter: Filter, s: &SurfacePoint) -> Vec3 {
        tilted(map, filter, s, &mut SharedFootprint::default())
    }

    fn flat_map(rgb: Vec3, scale: f32) -> NormalMap {
        NormalMap { texture: Arc::new(Texture::from_texels(2, 2, vec![rgb; 4])), scale }
    }

    /// A map of (0, 0, 1) leaves the normal; one tilted towards +x in tangent
    /// space tilts it along ∂P/∂u, towards +y along −∂P/∂v (up the image),
    /// by the angle the texel encodes, and `scale` 0 undoes the tilt.
    #[test]
    fn texels_tilt_the_normal_along_the_tangent_frame() {
        let frame = [Vec3::X, Vec3::Z];
        let flat = tilted_normal(&flat_map(Vec3::new(0.5, 0.5, 1.0), 1.0), Filter::Bilinear, &point(frame));
        assert!(flat.abs_diff_eq(Vec3::Y, 1e-6), "{flat}");
        // 45° towards tangent x: (sin, cos) = (0.7071, 0.7071), encoded (n + 1) / 2.
        let s = std::f32::consts::FRAC_1_SQRT_2;
        let x = tilted_normal(
            &flat_map(Vec3::new((s + 1.0) / 2.0, 0.5, (s + 1.0) / 2.0), 1.0),
            Filter::Bilinear,
            &point(frame),
        );
        assert!(x.abs_diff_eq(Vec3::new(s, s, 0.0), 1e-3), "{x}");
        let y = tilted_normal(
            &flat_map(Vec3::new(0.5, (s + 1.0) / 2.0, (s + 1.0) / 2.0), 1.0),
            Filter::Bilinear,
            &point(frame),
        );
        assert!(y.abs_diff_eq(Vec3::new(0.0, s, -s), 1e-3), "{y}");
        let none = tilted_normal(&flat_map(Vec3::new(1.0, 0.5, 0.5), 0.0), Filter::Bilinear, &point(frame));
        assert!(none.abs_diff_eq(Vec3::Y, 1e-6), "{none}");
        // Mirrored texture coordinates (u running along −x) mirror the tilt.
        let mirrored = tilted_normal(
            &flat_map(Vec3::new((s + 1.0) / 2.0, 0.5, (s + 1.0) / 2.0), 1.0),
            Filter::Bilinear,
            &point([Vec3::NEG_X, Vec3::Z]),
        );
        assert!(mirrored.abs_diff_eq(Vec3::new(-s, s, 0.0), 1e-3), "{mirrored}");
    }

    /// Without a tangent frame (no texture coordinates) the normal stays; a
    /// tilt past the silhouette is held in front of it.
    #[test]
    fn no_frame_no_tilt_and_never_past_the_silhouette() {
        let sideways = flat_map(Vec3::new(1.0, 0.5, 0.5), 1.0);
        assert_eq!(tilted_normal(&sideways, Filter::Bilinear, &point([Vec3::ZERO; 2])), Vec3::Y);
        let mut grazing = point([Vec3::X, Vec3::Z]);
        grazing.to_eye = Vec3::new(-1.0, 0.05, 0.0).normalize();
        let n = tilted_normal(&sideways, Filter::Bilinear, &grazing);
        assert!(n.dot(grazing.to_eye) > 0.0 && n.is_normalized(), "{n}");
    }
}
