//! Where rays meet a solid: a crossing of its surface ([`Crossing`], with its
//! normal), a stretch inside it ([`Span`]), and the same before normals are
//! found ([`Hit`], [`Interval`]; eight pixels' worth in [`IntervalLanes`]),
//! which is what the booleans combine.

use glam::Vec3;

/// Where a ray crosses a solid's surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Ray parameter.
    pub t: f32,
    /// Unit outward normal of the solid there (solid space).
    pub normal: Vec3,
    /// The primitive whose surface it is.
    pub primitive: u32,
    /// Whether that surface belongs to a subtracted primitive (a hole's wall).
    pub cut: bool,
}

/// A stretch of the ray inside the solid, from `enter` to `exit`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// Where the ray enters.
    pub enter: Crossing,
    /// Where it leaves.
    pub exit: Crossing,
}

/// A [`Crossing`] before its normal is found: which face of which primitive
/// the ray crosses, and where. Combining intervals along the tree reads only
/// `t`, so the booleans move these (12 bytes) and only the crossing finally
/// seen pays for its normal ([`super::CsgCaster::crossing_on_ray`],
/// [`super::CsgCaster::crossing_on_line`]), from the face and the ray.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Hit {
    /// Ray parameter.
    pub t: f32,
    /// The primitive whose surface it is.
    pub primitive: u32,
    /// The face of the primitive's unit shape (a polyhedron's plane; a
    /// frustum's side or cap), and in its top bit whether the surface
    /// belongs to a subtracted primitive (a hole's wall).
    pub(super) face: u32,
}

impl Hit {
    /// The bit of `face` that marks a hole's wall.
    pub(super) const CUT: u32 = 1 << 31;

    /// A crossing at `t` of face `face` of `primitive`.
    pub(crate) const fn new(t: f32, primitive: usize, face: u32) -> Hit {
        Hit { t, primitive: primitive as u32, face }
    }

    /// Whether the surface belongs to a subtracted primitive (a hole's wall).
    #[must_use]
    pub fn cut(&self) -> bool {
        self.face & Self::CUT != 0
    }

    /// Whether `other` lies on the same face of the same primitive, on the
    /// same side (a hole's wall or not).
    #[inline]
    #[must_use]
    pub fn same_face(&self, other: &Hit) -> bool {
        self.primitive == other.primitive && self.face == other.face
    }

    /// Whether this crossing comes before `other` along the ray: nearer, or
    /// as near and of a primitive earlier in the file (a union's coplanar
    /// faces show the first part's at every pixel, whatever order a walk
    /// met them in).
    #[inline]
    #[must_use]
    pub fn nearer_than(&self, other: &Hit) -> bool {
        self.t < other.t || (self.t == other.t && self.primitive < other.primitive)
    }

    /// This crossing with its hole-wall bit set to `cut` (what the booleans
    /// made of the same end of the same primitive at a neighbouring pixel).
    #[must_use]
    pub fn with_cut(self, cut: bool) -> Hit {
        Hit { face: (self.face & !Self::CUT) | if cut { Self::CUT } else { 0 }, ..self }
    }
}

/// A stretch of a ray inside a primitive or a part of the solid, its ends
/// not yet given normals ([`Hit`]): what the booleans combine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Interval {
    /// Where the ray enters.
    pub enter: Hit,
    /// Where it leaves.
    pub exit: Hit,
}

/// One primitive's [`Interval`]s at eight neighbouring pixels of a scanline
/// ([`super::CsgCaster::spans_on_eight`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct IntervalLanes {
    /// Entry and exit `t` per pixel.
    pub(super) t: [[f32; 8]; 2],
    /// Entry and exit faces per pixel.
    pub(super) face: [[u32; 8]; 2],
    /// Bit `j`: pixel `j` meets the primitive.
    pub(super) hit: u8,
    pub(super) primitive: u32,
}

impl IntervalLanes {
    /// Primitive `primitive`'s intervals at eight pixels, pixel `j`'s from
    /// `at(j)` (a closed mesh's layer, found from its triangles).
    #[must_use]
    pub fn from_fn(primitive: usize, mut at: impl FnMut(usize) -> Option<Interval>) -> IntervalLanes {
        let mut out = IntervalLanes { primitive: primitive as u32, ..IntervalLanes::default() };
        for j in 0..8 {
            if let Some(s) = at(j) {
                out.t[0][j] = s.enter.t;
                out.t[1][j] = s.exit.t;
                out.face[0][j] = s.enter.face;
                out.face[1][j] = s.exit.face;
                out.hit |= 1 << j;
            }
        }
        out
    }

    /// The interval at pixel `j` (0–7) of the eight, if its ray meets the
    /// primitive.
    #[inline]
    #[must_use]
    pub fn get(&self, j: usize) -> Option<Interval> {
        (self.hit >> j & 1 != 0).then(|| {
            let hit = |k: usize| Hit { t: self.t[k][j], primitive: self.primitive, face: self.face[k][j] };
            Interval { enter: hit(0), exit: hit(1) }
        })
    }

    /// Bit `j`: whether pixel `j`'s ray meets the primitive.
    #[inline]
    #[must_use]
    pub fn met(&self) -> u8 {
        self.hit
    }

    /// The `t` of end `end` (0 the entry, 1 the exit) at the eight pixels
    /// (meaningless where the ray misses).
    #[inline]
    #[must_use]
    pub fn ends(&self, end: usize) -> &[f32; 8] {
        &self.t[end]
    }

    /// The faces of end `end` (0 the entry, 1 the exit) at the eight pixels
    /// (meaningless where the ray misses).
    #[inline]
    #[must_use]
    pub fn faces(&self, end: usize) -> &[u32; 8] {
        &self.face[end]
    }

    /// End `end` (0 the entry, 1 the exit) at pixel `j` as a crossing.
    #[inline]
    #[must_use]
    pub fn end_at(&self, end: usize, j: usize) -> Hit {
        Hit { t: self.t[end][j], primitive: self.primitive, face: self.face[end][j] }
    }
}
