//! Indexed triangle meshes: the geometry every loader produces and the rasterizer eats.
//!
//! Loaders hand their raw arrays to [`Mesh::new`], which is the one place input is
//! checked: non-finite positions are an error, triangles with out-of-range indices are
//! an error, zero-area triangles are dropped (and counted, so the caller can warn), and
//! a mesh left with no triangles is an error.

use glam::{Vec2, Vec3};

/// An indexed triangle mesh in its own (object) space.
#[derive(Debug, Clone, Default)]
pub struct Mesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit vertex normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty. Origin at the image's
    /// top-left corner (glTF convention; OBJ's v is flipped on load).
    pub uvs: Vec<Vec2>,
    /// Triangles as vertex indices, counter-clockwise seen from the front.
    pub triangles: Vec<[u32; 3]>,
    /// Linear RGB vertex colours, one per position, or empty: they multiply
    /// the material's ambient and diffuse colours (glTF's `COLOR_0`).
    pub colors: Vec<Vec3>,
    /// A second set of texture coordinates, one per position, or empty: read
    /// by the textures whose [`Texture::set`](super::Texture::set) is 1 (a
    /// glTF material's textures on a second `TEXCOORD_n`). Without it those
    /// read [`Mesh::uvs`].
    pub uvs1: Vec<Vec2>,
}

/// What [`Mesh::new`] had to drop.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MeshRepairs {
    /// Triangles of zero area (repeated or collinear vertices) that were removed.
    pub degenerate_triangles: usize,
}

/// How to make normals for a mesh that has none.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NormalMode {
    /// Area-weighted average of the faces around each shared vertex.
    Smooth,
    /// Each triangle keeps its own face normal (vertices are split).
    Flat,
}

impl Mesh {
    /// Checks and builds a mesh. `normals` and `uvs` may be empty; missing normals
    /// are computed with `mode`.
    ///
    /// # Errors
    ///
    /// A message when a vertex is not finite, a triangle refers to a vertex
    /// past the positions, or no triangle has any area.
    pub fn new(
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        uvs: Vec<Vec2>,
        triangles: Vec<[u32; 3]>,
        mode: NormalMode,
    ) -> Result<(Mesh, MeshRepairs), String> {
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(format!("vertex {i} has a non-finite coordinate {:?}", positions[i]));
        }
        let n = positions.len() as u64;
        if let Some(t) = triangles.iter().position(|t| t.iter().any(|&i| i as u64 >= n)) {
            return Err(format!("triangle {t} refers to a vertex past the {n} given"));
        }
        let before = triangles.len();
        let triangles: Vec<[u32; 3]> =
            triangles.into_iter().filter(|t| face_normal(&positions, *t).length_squared() > 0.0).collect();
        let repairs = MeshRepairs { degenerate_triangles: before - triangles.len() };
        if triangles.is_empty() {
            return Err(if before == 0 {
                "the mesh has no triangles".to_string()
            } else {
                format!("all {before} triangles have zero area")
            });
        }
        let uvs = if uvs.len() == positions.len() { uvs } else { Vec::new() };
        let normals_ok = normals.len() == positions.len() && normals.iter().all(|v| v.is_finite());
        let normals = if normals_ok { normals } else { Vec::new() };
        let mut mesh = Mesh { positions, normals, uvs, triangles, colors: Vec::new(), uvs1: Vec::new() };
        if mesh.normals.is_empty() {
            match mode {
                NormalMode::Smooth => mesh.compute_smooth_normals(),
                NormalMode::Flat => mesh.split_flat(),
            }
        }
        mesh.normals.iter_mut().for_each(|v| *v = v.normalize_or(Vec3::Y));
        Ok((mesh, repairs))
    }

    /// Gives the mesh vertex `colors` (one per position, finite and not
    /// negative).
    ///
    /// # Errors
    ///
    /// A message when there are not as many colours as positions, or one is
    /// negative or not finite (the mesh is left without colours).
    pub fn set_colors(&mut self, colors: Vec<Vec3>) -> Result<(), String> {
        if colors.len() != self.positions.len() {
            return Err(format!("{} vertex colours for {} vertices", colors.len(), self.positions.len()));
        }
        if let Some(i) = colors.iter().position(|c| !c.is_finite() || c.min_element() < 0.0) {
            return Err(format!("vertex colour {i} is {:?}", colors[i]));
        }
        self.colors = colors;
        Ok(())
    }

    /// The texture coordinates a texture of coordinate set `set` reads:
    /// [`Mesh::uvs1`] for set 1 where the mesh has them, else [`Mesh::uvs`].
    #[must_use]
    pub fn uvs_of(&self, set: u8) -> &[Vec2] {
        if set == 1 && !self.uvs1.is_empty() {
            &self.uvs1
        } else {
            &self.uvs
        }
    }

    /// Gives the mesh a second set of texture coordinates (one per position,
    /// finite).
    ///
    /// # Errors
    ///
    /// A message when there are not as many as positions, or one is not
    /// finite (the mesh is left without them).
    pub fn set_second_uvs(&mut self, uvs: Vec<Vec2>) -> Result<(), String> {
        if uvs.len() != self.positions.len() {
            return Err(format!("{} texture coordinates for {} vertices", uvs.len(), self.positions.len()));
        }
        if let Some(i) = uvs.iter().position(|c| !c.is_finite()) {
            return Err(format!("texture coordinate {i} is {:?}", uvs[i]));
        }
        self.uvs1 = uvs;
        Ok(())
    }

    fn compute_smooth_normals(&mut self) {
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        for &t in &self.triangles {
            let n = face_normal(&self.positions, t); // length = 2·area: area weighting
            for i in t {
                acc[i as usize] += n;
            }
        }
        self.normals = acc;
    }

    fn split_flat(&mut self) {
        let mut m = Mesh::default();
        for &t in &self.triangles {
            let n = face_normal(&self.positions, t);
            let base = m.positions.len() as u32;
            for i in t {
                m.positions.push(self.positions[i as usize]);
                m.normals.push(n);
                if !self.uvs.is_empty() {
                    m.uvs.push(self.uvs[i as usize]);
                }
            }
            m.triangles.push([base, base + 1, base + 2]);
        }
        *self = m;
    }

    /// Axis-aligned bounds `(min, max)` of the vertices used by triangles.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.triangles.iter().flatten().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| {
            let p = self.positions[i as usize];
            (lo.min(p), hi.max(p))
        })
    }

    /// The area of all triangles together (where triangles overlap, counted
    /// once per triangle).
    #[must_use]
    pub fn surface_area(&self) -> f32 {
        self.triangles.iter().map(|&t| face_normal(&self.positions, t).length() / 2.0).sum()
    }
}

/// Unnormalised face normal (cross product; length is twice the area).
#[must_use]
pub fn face_normal(p: &[Vec3], t: [u32; 3]) -> Vec3 {
    let [a, b, c] = t.map(|i| p[i as usize]);
    (b - a).cross(c - a)
}

/// Built-in shapes, so scenes and tests can draw without files.
pub mod shapes {
    use super::*;

    /// A square of side 1 in the XZ plane at y = 0, facing +y, uv over the unit square.
    #[must_use]
    pub fn plane() -> Mesh {
        let positions = vec![
            Vec3::new(-0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, 0.5),
            Vec3::new(0.5, 0.0, -0.5),
            Vec3::new(-0.5, 0.0, -0.5),
        ];
        let uvs = vec![Vec2::new(0.0, 1.0), Vec2::new(1.0, 1.0), Vec2::new(1.0, 0.0), Vec2::ZERO];
        Mesh {
            positions,
            normals: vec![Vec3::Y; 4],
            uvs,
            triangles: vec![[0, 1, 2], [0, 2, 3]],
            colors: Vec::new(),
            uvs1: Vec::new(),
        }
    }

    /// A cube of side 1 centred at the origin, flat-shaded.
    #[must_use]
    pub fn cube() -> Mesh {
        let mut m = Mesh::default();
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = Vec3::from_array(std::array::from_fn(|k| if k == axis { sign } else { 0.0 }));
                let u = Vec3::from_array(std::array::from_fn(|k| if k == (axis + 1) % 3 { 1.0 } else { 0.0 }));
                let v = n.cross(u);
                let base = m.positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    m.positions.push(0.5 * (n + a * u + b * v));
                    m.normals.push(n);
                    m.uvs.push(Vec2::new(0.5 + 0.5 * a, 0.5 - 0.5 * b));
                }
                m.triangles.push([base, base + 1, base + 2]);
                m.triangles.push([base, base + 2, base + 3]);
            }
        }
        m
    }

    /// A UV sphere of radius 1 at the origin with `stacks` × 2·`stacks` quads,
    /// smooth normals, counter-clockwise outward (as the peers' `gen_scene.py`).
    #[must_use]
    pub fn sphere(stacks: u32) -> Mesh {
        let stacks = stacks.max(2);
        let slices = 2 * stacks;
        let mut m = Mesh::default();
        for i in 0..=stacks {
            let theta = std::f32::consts::PI * i as f32 / stacks as f32;
            // The poles exactly on the axis and the seam's two columns at one
            // place, so the triangles meeting there share their corners exactly.
            let (sin_t, cos_t) = match i {
                0 => (0.0, 1.0),
                _ if i == stacks => (0.0, -1.0),
                _ => theta.sin_cos(),
            };
            for j in 0..=slices {
                let phi = std::f32::consts::TAU * (j % slices) as f32 / slices as f32;
                let p = Vec3::new(sin_t * phi.cos(), cos_t, -sin_t * phi.sin());
                m.positions.push(p);
                m.normals.push(p);
                m.uvs.push(Vec2::new(j as f32 / slices as f32, i as f32 / stacks as f32));
            }
        }
        let row = slices + 1;
        for i in 0..stacks {
            for j in 0..slices {
                let (a, b) = (i * row + j, (i + 1) * row + j);
                if i != 0 {
                    m.triangles.push([a, b, a + 1]);
                }
                if i != stacks - 1 {
                    m.triangles.push([a + 1, b, b + 1]);
                }
            }
        }
        m
    }

    /// A torus about the y axis at the origin: a ring of radius 1 swept by a
    /// tube of radius `tube`, as `rings` × `sides` quads (at least 3 × 3),
    /// smooth normals, counter-clockwise outward.
    #[must_use]
    pub fn torus(rings: u32, sides: u32, tube: f32) -> Mesh {
        let (rings, sides) = (rings.max(3), sides.max(3));
        let mut m = Mesh::default();
        for i in 0..rings {
            let a = std::f32::consts::TAU * i as f32 / rings as f32;
            for j in 0..sides {
                let b = std::f32::consts::TAU * j as f32 / sides as f32;
                let n = Vec3::new(b.cos() * a.cos(), b.sin(), b.cos() * a.sin());
                m.positions.push(Vec3::new(a.cos(), 0.0, a.sin()) + n * tube);
                m.normals.push(n);
                m.uvs.push(Vec2::new(i as f32 / rings as f32, j as f32 / sides as f32));
            }
        }
        let at = |i: u32, j: u32| (i % rings) * sides + j % sides;
        for i in 0..rings {
            for j in 0..sides {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                m.triangles.push([a, c, b]);
                m.triangles.push([a, d, c]);
            }
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every built-in closed shape winds its triangles counter-clockwise
    /// seen from outside: each face normal agrees with its vertices' normals.
    #[test]
    fn built_in_shapes_wind_outward() {
        for (name, m) in [("cube", shapes::cube()), ("sphere", shapes::sphere(8)), ("torus", shapes::torus(12, 8, 0.3))]
        {
            for t in &m.triangles {
                let n = face_normal(&m.positions, *t);
                let smooth: Vec3 = t.iter().map(|&i| m.normals[i as usize]).sum();
                assert!(n.dot(smooth) > 0.0, "{name}: triangle {t:?} winds inward");
            }
        }
    }

    #[test]
    fn rejects_nan_and_empty_and_drops_degenerates() {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(2.0, 0.0, 0.0)];
        let e = Mesh::new(p.clone(), vec![], vec![], vec![], NormalMode::Smooth).unwrap_err();
        assert!(e.contains("no triangles"), "{e}");
        let (m, r) = Mesh::new(p.clone(), vec![], vec![], vec![[0, 1, 2], [0, 1, 3]], NormalMode::Smooth).unwrap();
        assert_eq!((m.triangles.len(), r.degenerate_triangles), (1, 1));
        let e = Mesh::new(p.clone(), vec![], vec![], vec![[0, 1, 3]], NormalMode::Flat).unwrap_err();
        assert!(e.contains("zero area"), "{e}");
        let mut bad = p;
        bad[2].y = f32::NAN;
        let e = Mesh::new(bad, vec![], vec![], vec![[0, 1, 2]], NormalMode::Smooth).unwrap_err();
        assert!(e.contains("vertex 2") && e.contains("non-finite"), "{e}");
    }

    /// Shapes are closed and outward-facing: the divergence theorem gives a positive
    /// volume equal to the analytic one.
    #[test]
    fn shapes_enclose_their_volume() {
        let volume = |m: &Mesh| -> f32 {
            m.triangles
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| m.positions[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum()
        };
        assert!((volume(&shapes::cube()) - 1.0).abs() < 1e-5);
        let v = volume(&shapes::sphere(64));
        assert!((v - 4.0 / 3.0 * std::f32::consts::PI).abs() < 0.01, "{v}");
    }
}
