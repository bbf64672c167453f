//! CSG solids made of convex primitives (seed 003 §5–6), as data.
//!
//! A [`CsgSolid`] is a tree of booleans ([`CsgTree`]) over convex primitives
//! ([`Primitive`]): spheres and ellipsoids, cylinders, cones and frustums (exact
//! quadrics), and convex polyhedra given by their planes (boxes, prisms, any convex
//! point set). Each primitive carries an affine transform from its unit shape into
//! the solid's space, so one unit sphere and one unit frustum describe every
//! ellipsoid and elliptic cylinder. Differences are kept as written (`A − B − C`);
//! seed 003 turns them into intersections with negative primitives when it forms
//! its sum of products, which the renderer does, not the model.
//!
//! [`CsgSolid::contains`] is the point-membership oracle the renderers are tested
//! against.

use std::ops::Range;
use std::sync::Arc;

use glam::{Affine3A, Vec3, Vec4};

use super::mesh::ClosedMesh;

/// A unit shape, before its primitive's transform.
#[derive(Debug, Clone, PartialEq)]
pub enum Shape {
    /// The sphere of radius 1 about the origin.
    Sphere,
    /// A frustum about the z axis from z = 0 (radius `bottom`) to z = 1 (radius
    /// `top`); a cylinder when they are equal, a cone when one is 0. The larger
    /// radius is 1.
    Frustum {
        /// Radius at z = 0.
        bottom: f32,
        /// Radius at z = 1.
        top: f32,
    },
    /// A convex polyhedron.
    Polyhedron(ConvexPolyhedron),
    /// One layer of a closed mesh that need not be convex: the `layer`-th
    /// interval of each ray inside it (the last layer: to the last exit). A
    /// mesh stands in a tree as the union of its layers
    /// ([`CsgTree::mesh_layers`]).
    Mesh {
        /// The mesh, in the unit shape's space.
        mesh: Arc<ClosedMesh>,
        /// Which interval along a ray.
        layer: u32,
    },
}

/// A convex polyhedron: the points `p` with `n·p ≤ d` for every plane `(n, d)`
/// (n a unit outward normal), and its corners.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexPolyhedron {
    /// Outward unit normal and offset of each face plane.
    pub planes: Vec<Vec4>,
    /// The corners (for bounds and hulls).
    pub vertices: Vec<Vec3>,
}

impl ConvexPolyhedron {
    /// The box `[0, 1]³`.
    #[must_use]
    pub fn unit_cube() -> Self {
        Self::boxed(Vec3::ZERO, Vec3::ONE)
    }

    /// The axis-aligned box `lo..hi`.
    #[must_use]
    pub fn boxed(lo: Vec3, hi: Vec3) -> Self {
        let planes = [Vec3::X, Vec3::Y, Vec3::Z]
            .into_iter()
            .flat_map(|n| [n.extend(n.dot(hi)), (-n).extend(-n.dot(lo))])
            .collect();
        let vertices =
            (0..8).map(|i| Vec3::new([lo.x, hi.x][i & 1], [lo.y, hi.y][(i >> 1) & 1], [lo.z, hi.z][(i >> 2) & 1]));
        ConvexPolyhedron { planes, vertices: vertices.collect() }
    }

    /// Whether `p` lies inside or on the surface (within `eps` of a plane).
    #[must_use]
    pub fn contains(&self, p: Vec3, eps: f32) -> bool {
        self.planes.iter().all(|pl| pl.truncate().dot(p) <= pl.w + eps)
    }
}

/// One convex primitive of a solid.
#[derive(Debug, Clone, PartialEq)]
pub struct Primitive {
    /// The unit shape.
    pub shape: Shape,
    /// From the unit shape's space to the solid's.
    pub transform: Affine3A,
    /// RGBA colour from the file, if one applies (OpenSCAD: the outermost wins).
    pub color: Option<Vec4>,
    /// Bytes of the source node that made it (for messages).
    pub source: Range<usize>,
}

impl Primitive {
    /// Corners of a box around the primitive (its unit shape's box, or a
    /// polyhedron's own corners), in solid space.
    #[must_use]
    pub fn corners(&self) -> Vec<Vec3> {
        self.unit_corners().into_iter().map(|c| self.transform.transform_point3(c)).collect()
    }

    /// The corners of a box around the unit shape, in its own space (before
    /// the transform).
    #[must_use]
    pub fn unit_corners(&self) -> Vec<Vec3> {
        let unit_box = |z0: f32| -> Vec<Vec3> {
            (0..8)
                .map(|i| {
                    let pick = |bit: usize, lo: f32| if i >> bit & 1 == 0 { lo } else { 1.0 };
                    Vec3::new(pick(0, -1.0), pick(1, -1.0), pick(2, z0))
                })
                .collect()
        };
        match &self.shape {
            Shape::Sphere => unit_box(-1.0),
            Shape::Frustum { .. } => unit_box(0.0),
            Shape::Polyhedron(p) => p.vertices.clone(),
            Shape::Mesh { mesh, .. } => {
                let (lo, hi) = mesh.bounds();
                (0..8).map(|i| Vec3::select(glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0), hi, lo)).collect()
            }
        }
    }

    /// Axis-aligned bounds `(min, max)` in solid space.
    #[must_use]
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.corners().into_iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), c| (lo.min(c), hi.max(c)))
    }

    /// Whether the point `p` (solid space) lies inside the primitive or on its
    /// surface.
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        const EPS: f32 = 1e-5;
        let q = self.transform.inverse().transform_point3(p);
        match &self.shape {
            Shape::Sphere => q.length_squared() <= 1.0 + EPS,
            Shape::Frustum { bottom, top } => {
                let r = bottom + (top - bottom) * q.z;
                (-EPS..=1.0 + EPS).contains(&q.z) && q.truncate().length() <= r + EPS
            }
            Shape::Polyhedron(poly) => poly.contains(q, EPS),
            Shape::Mesh { mesh, layer } => mesh.layer_of(q) == Some(*layer),
        }
    }
}

/// Booleans over primitives (indices into [`CsgSolid::primitives`]).
#[derive(Debug, Clone, PartialEq)]
pub enum CsgTree {
    /// One primitive.
    Leaf(usize),
    /// Inside any child.
    Union(Vec<CsgTree>),
    /// Inside every child.
    Intersection(Vec<CsgTree>),
    /// Inside the first, outside all the others.
    Difference(Box<CsgTree>, Vec<CsgTree>),
}

impl CsgTree {
    /// The union of the layers of a mesh whose first layer is primitive
    /// `first` (its `layers` primitives numbered on from there).
    #[must_use]
    pub fn mesh_layers(first: usize, layers: u32) -> CsgTree {
        match layers {
            0 | 1 => CsgTree::Leaf(first),
            n => CsgTree::Union((first..first + n as usize).map(CsgTree::Leaf).collect()),
        }
    }

    /// The same solid with nested booleans of one kind merged: a union's
    /// union operands and an intersection's intersection operands are spliced
    /// into it, a difference's union cutters become its own cutters
    /// (`A − (B ∪ C) = A − B − C`), and a difference whose first operand is a
    /// difference takes over its cutters (`(A − B) − C = A − B − C`). OpenSCAD
    /// files nest a group per module call; flat, the span combiner cuts by
    /// each cutter in turn instead of sorting a union of them at every pixel.
    #[must_use]
    pub fn flattened(self) -> CsgTree {
        /// `kids` flattened, with the operands of those `open` opens spliced in.
        fn splice(kids: Vec<CsgTree>, open: fn(CsgTree) -> Result<Vec<CsgTree>, CsgTree>) -> Vec<CsgTree> {
            let mut out = Vec::with_capacity(kids.len());
            for kid in kids.into_iter().map(CsgTree::flattened) {
                match open(kid) {
                    Ok(inner) => out.extend(inner),
                    Err(kid) => out.push(kid),
                }
            }
            out
        }
        let unions = |t| match t {
            CsgTree::Union(kids) => Ok(kids),
            t => Err(t),
        };
        let intersections = |t| match t {
            CsgTree::Intersection(kids) => Ok(kids),
            t => Err(t),
        };
        match self {
            CsgTree::Leaf(_) => self,
            CsgTree::Union(kids) => CsgTree::Union(splice(kids, unions)),
            CsgTree::Intersection(kids) => CsgTree::Intersection(splice(kids, intersections)),
            CsgTree::Difference(first, cutters) => {
                let cutters = splice(cutters, unions);
                match first.flattened() {
                    CsgTree::Difference(first, mut earlier) => {
                        earlier.extend(cutters);
                        CsgTree::Difference(first, earlier)
                    }
                    first => CsgTree::Difference(Box::new(first), cutters),
                }
            }
        }
    }

    /// Whether `p` is inside, given which primitives contain it.
    #[must_use]
    pub fn contains(&self, inside: &impl Fn(usize) -> bool) -> bool {
        match self {
            CsgTree::Leaf(i) => inside(*i),
            CsgTree::Union(c) => c.iter().any(|t| t.contains(inside)),
            CsgTree::Intersection(c) => c.iter().all(|t| t.contains(inside)),
            CsgTree::Difference(a, b) => a.contains(inside) && !b.iter().any(|t| t.contains(inside)),
        }
    }

    /// What bounds the tree, given what bounds each primitive (`leaf`):
    /// unions join their operands' bounds, intersections meet them, a
    /// difference keeps its first part's.
    #[must_use]
    pub fn bound<B: Bound>(&self, leaf: &impl Fn(usize) -> B) -> B {
        match self {
            CsgTree::Leaf(i) => leaf(*i),
            CsgTree::Union(kids) => kids.iter().fold(B::nowhere(), |b, k| b.join(&k.bound(leaf))),
            CsgTree::Intersection(kids) => kids.iter().fold(B::anywhere(), |b, k| b.meet(&k.bound(leaf))),
            CsgTree::Difference(a, _) => a.bound(leaf),
        }
    }

    /// Axis-aligned bounds of the tree given each primitive's ([`CsgTree::bound`]).
    /// `None` when the bounds show the tree empty.
    #[must_use]
    pub fn bounds(&self, leaf: &impl Fn(usize) -> (Vec3, Vec3)) -> Option<(Vec3, Vec3)> {
        match self.bound(&|i| Reach::Within(Aabb(leaf(i)))) {
            Reach::Within(Aabb(b)) => Some(b),
            Reach::Anywhere | Reach::Nowhere => None,
        }
    }
}

/// What bounds a node of a [`CsgTree`] ([`CsgTree::bound`]): meets narrow it
/// (an intersection lies within all its operands), joins widen it (a union
/// within any).
pub trait Bound: Clone {
    /// No bound at all (what meets start from).
    fn anywhere() -> Self;
    /// Nothing inside (what joins start from), or the nearest bound that
    /// can say so.
    fn nowhere() -> Self;
    /// Within both.
    #[must_use]
    fn meet(&self, other: &Self) -> Self;
    /// Within one or the other.
    #[must_use]
    fn join(&self, other: &Self) -> Self;
}

/// A box (of space, of pixels) as a [`Reach`] meets and joins them.
pub trait BoxBound: Copy {
    /// What lies in both, `None` if nothing.
    fn meet(self, other: Self) -> Option<Self>;
    /// A box holding both.
    fn join(self, other: Self) -> Self;
}

/// Where a node of a tree may be non-empty: anywhere, within a box, or
/// nowhere.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reach<B> {
    /// Anywhere.
    Anywhere,
    /// Within the box.
    Within(B),
    /// Nowhere.
    Nowhere,
}

impl<B> Reach<B> {
    /// Within `b`, or nowhere for `None`.
    pub fn of(b: Option<B>) -> Reach<B> {
        b.map_or(Reach::Nowhere, Reach::Within)
    }
}

impl<B: BoxBound> Bound for Reach<B> {
    fn anywhere() -> Self {
        Reach::Anywhere
    }

    fn nowhere() -> Self {
        Reach::Nowhere
    }

    fn meet(&self, other: &Self) -> Self {
        match (*self, *other) {
            (Reach::Nowhere, _) | (_, Reach::Nowhere) => Reach::Nowhere,
            (Reach::Anywhere, r) | (r, Reach::Anywhere) => r,
            (Reach::Within(a), Reach::Within(b)) => Reach::of(a.meet(b)),
        }
    }

    fn join(&self, other: &Self) -> Self {
        match (*self, *other) {
            (Reach::Anywhere, _) | (_, Reach::Anywhere) => Reach::Anywhere,
            (Reach::Nowhere, r) | (r, Reach::Nowhere) => r,
            (Reach::Within(a), Reach::Within(b)) => Reach::Within(a.join(b)),
        }
    }
}

/// An axis-aligned box `(min, max)` of solid space.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Aabb((Vec3, Vec3));

impl BoxBound for Aabb {
    fn meet(self, Aabb(b): Aabb) -> Option<Aabb> {
        let m = (self.0 .0.max(b.0), self.0 .1.min(b.1));
        m.0.cmple(m.1).all().then_some(Aabb(m))
    }

    fn join(self, Aabb(b): Aabb) -> Aabb {
        Aabb((self.0 .0.min(b.0), self.0 .1.max(b.1)))
    }
}

/// A solid: primitives and the booleans that combine them.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CsgSolid {
    /// Every primitive, in file order.
    pub primitives: Vec<Primitive>,
    /// The booleans; `None` for a solid with no volume.
    pub tree: Option<CsgTree>,
}

impl CsgSolid {
    /// Whether the point `p` (solid space) lies inside the solid (brute force:
    /// every primitive is asked).
    #[must_use]
    pub fn contains(&self, p: Vec3) -> bool {
        self.tree.as_ref().is_some_and(|t| t.contains(&|i| self.primitives[i].contains(p)))
    }

    /// The solid moved by `m` (each primitive's transform composed after it).
    #[must_use]
    pub fn transformed(&self, m: &Affine3A) -> CsgSolid {
        let mut out = self.clone();
        out.primitives.iter_mut().for_each(|p| p.transform = *m * p.transform);
        out
    }

    /// Axis-aligned bounds `(min, max)` of the solid (`None` if it is empty).
    #[must_use]
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        let boxes: Vec<(Vec3, Vec3)> = self.primitives.iter().map(Primitive::bounds).collect();
        self.tree.as_ref()?.bounds(&|i| boxes[i])
    }
}

/// Random trees over primitives `0..n`, nested up to `depth` levels (for
/// property tests of whatever reads trees).
#[cfg(test)]
pub(crate) fn random_tree(n: usize, depth: u32) -> impl proptest::strategy::Strategy<Value = CsgTree> {
    use proptest::prelude::*;
    (0..n).prop_map(CsgTree::Leaf).prop_recursive(depth, 8 * depth, 4, |inner| {
        prop_oneof![
            prop::collection::vec(inner.clone(), 1..4).prop_map(CsgTree::Union),
            prop::collection::vec(inner.clone(), 1..4).prop_map(CsgTree::Intersection),
            (inner.clone(), prop::collection::vec(inner, 1..4))
                .prop_map(|(a, cut)| CsgTree::Difference(Box::new(a), cut)),
        ]
    })
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    /// Whether a boolean of one kind is left nested in its own kind.
    fn nested(t: &CsgTree) -> bool {
        match t {
            CsgTree::Leaf(_) => false,
            CsgTree::Union(k) => k.iter().any(|k| matches!(k, CsgTree::Union(_)) || nested(k)),
            CsgTree::Intersection(k) => k.iter().any(|k| matches!(k, CsgTree::Intersection(_)) || nested(k)),
            CsgTree::Difference(a, k) => {
                matches!(**a, CsgTree::Difference(..))
                    || nested(a)
                    || k.iter().any(|k| matches!(k, CsgTree::Union(_)) || nested(k))
            }
        }
    }

    proptest! {
        /// Flattening keeps the solid (the same inside for every set of
        /// primitives containing a point) and leaves nothing to flatten.
        #[test]
        fn flattening_keeps_the_solid(t in random_tree(8, 4), inside in prop::collection::vec(any::<bool>(), 8)) {
            let flat = t.clone().flattened();
            prop_assert!(!nested(&flat), "{flat:?}");
            prop_assert_eq!(flat.contains(&|i| inside[i]), t.contains(&|i| inside[i]));
        }
    }
}
