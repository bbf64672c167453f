//! Clipping in homogeneous clip space, before the divide by w.
//!
//! A triangle is clipped against the near and far planes and against a guard band
//! far outside the image in x and y (so the edges clipping creates there are never
//! on screen, and screen coordinates stay small enough for the exact fixed-point
//! DDA). Every plane is a half-space `dot(plane, v) ≥ 0`.
//!
//! The point where an edge crosses a plane is always computed from the inside
//! vertex towards the outside one, so two triangles sharing an edge get bit-identical
//! new vertices: clipping keeps meshes watertight.
//!
//! Clipping runs in f64: a triangle that needs it is usually huge (a ground plane
//! reaching far behind the eye), and the part of it on screen is a tiny fraction of
//! its extent, so f32's 7 digits would misplace the new vertices by many pixels.

use glam::{DVec4, Vec4};

/// The clipping planes of one frame.
#[derive(Debug, Clone, Copy)]
pub struct ClipPlanes {
    planes: [DVec4; 6],
}

/// Most vertices a triangle can have after clipping by six planes.
pub const MAX_CLIPPED: usize = 9;

impl ClipPlanes {
    /// Near `z ≤ w`, far `z ≥ far_factor·w` (reversed depth), and guard bands
    /// `|x| ≤ gx·w`, `|y| ≤ gy·w`.
    #[must_use]
    pub fn new(far_factor: f64, gx: f64, gy: f64) -> Self {
        ClipPlanes {
            planes: [
                DVec4::new(0.0, 0.0, -1.0, 1.0),
                DVec4::new(0.0, 0.0, 1.0, -far_factor),
                DVec4::new(-1.0, 0.0, 0.0, gx),
                DVec4::new(1.0, 0.0, 0.0, gx),
                DVec4::new(0.0, -1.0, 0.0, gy),
                DVec4::new(0.0, 1.0, 0.0, gy),
            ],
        }
    }

    /// One bit per plane the vertex is outside of (0: inside all).
    #[must_use]
    pub fn outcode(&self, v: Vec4) -> u8 {
        let v = v.as_dvec4();
        self.planes.iter().enumerate().fold(0, |code, (i, p)| {
            let d = p.dot(v);
            code | (u8::from(d < 0.0 || d.is_nan()) << i)
        })
    }

    /// Clips the triangle against the planes named in `mask`; returns the polygon's
    /// vertex count (0 if nothing is left). The polygon is convex and keeps the
    /// triangle's winding.
    pub fn clip(&self, tri: [DVec4; 3], mask: u8, out: &mut [DVec4; MAX_CLIPPED]) -> usize {
        let mut buf = [DVec4::ZERO; MAX_CLIPPED];
        out[..3].copy_from_slice(&tri);
        let mut n = 3;
        for (i, plane) in self.planes.iter().enumerate() {
            if mask >> i & 1 == 0 {
                continue;
            }
            buf[..n].copy_from_slice(&out[..n]);
            n = clip_polygon(&buf[..n], *plane, out);
            if n < 3 {
                return 0;
            }
        }
        n
    }
}

fn clip_polygon(input: &[DVec4], plane: DVec4, out: &mut [DVec4; MAX_CLIPPED]) -> usize {
    let mut n = 0;
    for (i, &cur) in input.iter().enumerate() {
        let next = input[(i + 1) % input.len()];
        let (dc, dn) = (plane.dot(cur), plane.dot(next));
        if dc >= 0.0 {
            out[n] = cur;
            n += 1;
        }
        if (dc >= 0.0) != (dn >= 0.0) {
            let (inside, outside, di, dout) = if dc >= 0.0 { (cur, next, dc, dn) } else { (next, cur, dn, dc) };
            out[n] = inside + (outside - inside) * (di / (di - dout));
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_the_near_plane_keeps_the_front_part() {
        let planes = ClipPlanes::new(0.001, 100.0, 100.0);
        // z ≤ w is inside; the third vertex is behind the near plane.
        let tri = [DVec4::new(0.0, 0.0, 0.5, 1.0), DVec4::new(1.0, 0.0, 0.5, 1.0), DVec4::new(0.0, 1.0, 2.0, 1.0)];
        let mask = tri.iter().fold(0, |m, v| m | planes.outcode(v.as_vec4()));
        assert_eq!(mask, 1);
        let mut out = [DVec4::ZERO; MAX_CLIPPED];
        let n = planes.clip(tri, mask, &mut out);
        assert_eq!(n, 4);
        assert!(out[..n].iter().all(|v| v.z <= v.w + 1e-6));
    }

    #[test]
    fn shared_edge_clips_to_identical_points() {
        let planes = ClipPlanes::new(0.001, 100.0, 100.0);
        let (a, b) = (DVec4::new(0.3, -0.2, 0.2, 1.0), DVec4::new(-0.7, 0.9, 3.0, 1.0));
        let t1 = [a, b, DVec4::new(1.0, 1.0, 0.1, 1.0)];
        let t2 = [b, a, DVec4::new(-1.0, -1.0, 0.1, 1.0)];
        let mut o1 = [DVec4::ZERO; MAX_CLIPPED];
        let mut o2 = [DVec4::ZERO; MAX_CLIPPED];
        let n1 = planes.clip(t1, 1, &mut o1);
        let n2 = planes.clip(t2, 1, &mut o2);
        let on_plane =
            |o: &[DVec4]| o.iter().copied().filter(|v| v.z == v.w || (v.z - v.w).abs() < 1e-6).collect::<Vec<_>>();
        let (p1, p2) = (on_plane(&o1[..n1]), on_plane(&o2[..n2]));
        assert!(p1.iter().any(|p| p2.contains(p)), "{p1:?} vs {p2:?}");
    }
}
