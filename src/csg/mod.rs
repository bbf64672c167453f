//! CSG solids made of convex primitives (seed 003: Tokoi & Kitahashi 1988, §5–6;
//! `docs/papers.md`): the model, its
//! OpenSCAD reader, and ray casting by intervals — everything about a solid
//! that does not depend on the scene it stands in or the screen it is drawn on.
//!
//! A [`CsgSolid`] is a boolean tree ([`CsgTree`]) over convex primitives
//! ([`Primitive`]: spheres, frustums, convex polyhedra, each a unit shape under
//! an affine transform). [`CsgCaster`] casts rays at one: the depth interval a
//! ray spends inside each primitive, solved in closed form (seed 003's
//! procedure 3), combined along the tree into the spans the ray spends inside
//! the solid. The scanline walk (`visibility::solids`) reads the same
//! intervals a scanline at a time, and the ray tracer casts reflected and
//! shadow rays through the same caster.
//!
//! One file per concern: [`model`](CsgSolid) (the solid as data and its
//! point-membership oracle), `shapes` (each unit shape's crossings and
//! normals), `lanes` (the same, eight pixels of a scanline at once), `faces`
//! (which of a many-planed polyhedron's faces a block of pixels can cross),
//! `booleans` (intervals combined along the tree; coplanar cuts decided by
//! [`TIE`]), `occupancy.rs` (seed 003's reference counts, kept at every node of
//! the tree), `outline` (where a primitive shows on the screen: procedures 1
//! and 2), the caster, and [`openscad`] (OpenSCAD `.csg` files read into a
//! solid). A new kind of primitive is a new [`Shape`] and its arms in these
//! files, all in this folder.

mod booleans;
mod caster;
mod faces;
mod hit;
mod lanes;
mod mesh;
mod model;
pub(crate) mod occupancy;
pub mod openscad;
pub(crate) mod outline;
mod shapes;

pub use booleans::{above, below, combine, Booleans, LeafSpans, Operation, Parts, SpanScratch, TIE};
pub use caster::{first_hit, primitive_span, spans, CsgCaster};
pub use faces::{FacesOnScreen, RowFaces};
pub use hit::{Crossing, Hit, Interval, IntervalLanes, Span};
pub use mesh::{pick_layer, ClosedMesh, MeshInterval, FLIP as MESH_FLIP, MAX_TRIANGLES as MAX_MESH_TRIANGLES};
#[cfg(test)]
pub(crate) use model::random_tree;
pub use model::{Bound, BoxBound, ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Reach, Shape};
