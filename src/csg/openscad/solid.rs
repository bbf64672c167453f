//! 3-D nodes: booleans, transforms and colours over the tree of convex
//! primitives, and the nodes that make primitives — OpenSCAD's own, hulls,
//! Minkowski sums of convex parts, resized parts, extrusions of 2-D shapes,
//! and 2-D shapes standing alone (plates, as OpenSCAD's preview draws them).

use glam::{Affine3A, DVec2, Vec3, Vec4};

use super::extrude::{revolution, revolved, slab, wedge, Cone, Layers};
use super::flat::Region;
use super::hull::convex_hull;
use super::meshed::{minkowski_of_meshes, surface_bounds, surface_points};
use super::partition::convex_pieces;
use super::pieces::convex_summands;
use super::primitives::Made;
use super::syntax::{CsgNode, CsgValue};
use super::{combine, is_flat, kind, Builder, Built, GhostKind, Kind, Tinted};
use crate::csg::{ConvexPolyhedron, CsgTree, Primitive, Shape};
use crate::error::Result;
use crate::limits::Limit;

/// Convex pieces past which a straight extrusion is drawn as one closed
/// mesh (OpenSCAD's, as exact as its prisms) rather than a prism per piece:
/// a shape with curved outlines cut into hundreds of pieces costs every ray
/// and every scanline a box per piece, where the mesh costs its few layers.
const MESHED_PIECES: usize = 24;

/// The most convex pieces a cut or intersected child of a `minkowski()` is
/// split into before it is summed by Manifold as a mesh instead.
const MINKOWSKI_PIECES: usize = 512;

/// Half the thickness of a plate: OpenSCAD's preview draws a 2-D shape from
/// z = −½ to ½, and a subtracted one a tenth thicker.
const PLATE: (f64, f64) = (0.5, 0.55);

impl Builder<'_> {
    /// What `node` makes, placed by `m`, coloured `color` unless it or a
    /// node below it says otherwise.
    pub(super) fn node(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        if node.background {
            if self.ghostly {
                self.ghost(node, GhostKind::Background, m)?;
            }
            return Ok(Built::Skipped);
        }
        if node.highlight && self.ghostly {
            self.ghost(node, GhostKind::Highlight, m)?;
        }
        let Some(kind) = kind(node) else {
            let message = format!("`{}()` is not a node kage knows", node.name);
            self.unsupported(node, message)?;
            return Ok(Built::Skipped);
        };
        if is_flat(node) {
            return self.plate(node, m, color);
        }
        let open = self.open;
        self.open &= matches!(kind, Kind::Union | Kind::Transform | Kind::Color);
        let built = self.made(node, kind, m, color);
        self.open = open;
        built
    }

    /// What a node of 3-D `kind` makes, as [`Builder::node`].
    fn made(&mut self, node: &CsgNode, kind: Kind, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let kids = &node.children;
        match kind {
            Kind::Union => self.union(kids, m, color),
            Kind::Intersection => self.intersection(kids, m, color),
            Kind::Difference => self.difference(kids, m, color),
            Kind::Transform => {
                let matrix = self.matrix(node)?;
                if matrix.determinant().abs() < 1e-12 {
                    self.warn(&node.span, "a singular multmatrix flattens its children to nothing");
                    return Ok(Built::Empty);
                }
                self.union(kids, m * Affine3A::from_mat4(matrix), color)
            }
            Kind::Color => {
                let own = self.color(node)?;
                match own {
                    Some(c) if c.w < 1.0 && color.is_none() && self.ghostly => self.see_through(node, c, m),
                    _ => self.union(kids, m, color.or(own)),
                }
            }
            Kind::Hull => self.hull(node, m, color),
            Kind::Minkowski => self.minkowski(node, m, color),
            Kind::Resize => self.resize(node, m, color),
            Kind::Primitive => match self.primitive(node, m, color)? {
                None => Ok(Built::Empty),
                Some(Made::Convex(p)) => self.push(p),
                Some(Made::Mesh(mesh)) => self.push_mesh(node, mesh, m, color),
            },
            Kind::LinearExtrude => self.linear_extrude(node, m, color),
            Kind::RotateExtrude => self.rotate_extrude(node, m, color),
            Kind::Import => self.import(node, m, color),
            Kind::Surface => self.surface(node, m, color),
            // Flat kinds were drawn as plates above.
            Kind::Shape2d | Kind::Text | Kind::Offset | Kind::Projection | Kind::Fill => Ok(Built::Empty),
        }
    }

    /// A `color()` with alpha below 1: a see-through part of its own where it
    /// stands alone in the model; inside an operation, drawn opaque with a
    /// warning.
    fn see_through(&mut self, node: &CsgNode, color: Vec4, m: Affine3A) -> Result<Built> {
        if !self.open {
            let message = format!(
                "this colour's alpha ({}) is drawn opaque: kage draws a see-through colour only on a part no operation combines",
                color.w
            );
            self.warn(&node.span, message);
            return self.union(&node.children, m, Some(color));
        }
        let solid = self.faceted_solid(&node.children, m)?;
        if solid.tree.is_none() {
            return Ok(Built::Empty);
        }
        self.see_through.push(Tinted { color, solid, source: node.span.clone() });
        Ok(Built::Skipped)
    }

    /// `color()`'s own colour (`None` for OpenSCAD's "no colour").
    fn color(&self, node: &CsgNode) -> Result<Option<Vec4>> {
        let rgba = self.floats(node, None, 4)?;
        let own = (rgba[..3] != [-1.0; 3]).then(|| Vec4::from_slice(&rgba));
        if own.is_some_and(|c| !c.cmpge(Vec4::ZERO).all() || !c.cmple(Vec4::ONE).all()) {
            let message = format!("colour components must be between 0 and 1, not {rgba:?}");
            return Err(self.invalid(&node.span, message));
        }
        Ok(own)
    }

    /// The children's trees, skipped ones left out; `None` if one is empty and
    /// `empty_spoils` (an intersection).
    fn children(
        &mut self,
        kids: &[CsgNode],
        m: Affine3A,
        color: Option<Vec4>,
        empty_spoils: bool,
    ) -> Result<Option<Vec<CsgTree>>> {
        let mut trees = Vec::new();
        for kid in kids {
            match self.node(kid, m, color)? {
                Built::Skipped => {}
                Built::Empty if empty_spoils => return Ok(None),
                Built::Empty => {}
                Built::Tree(t) => trees.push(t),
            }
        }
        Ok(Some(trees))
    }

    pub(super) fn union(&mut self, kids: &[CsgNode], m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let trees = self.children(kids, m, color, false)?.unwrap_or_default();
        Ok(combine(trees, CsgTree::Union))
    }

    fn intersection(&mut self, kids: &[CsgNode], m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        Ok(match self.children(kids, m, color, true)? {
            None => Built::Empty,
            Some(trees) => combine(trees, CsgTree::Intersection),
        })
    }

    fn difference(&mut self, kids: &[CsgNode], m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let mut rest = kids.iter();
        // The first child that counts is the positive one.
        let positive = loop {
            let Some(kid) = rest.next() else { return Ok(Built::Empty) };
            match self.node(kid, m, color)? {
                Built::Skipped => continue,
                Built::Empty => return Ok(Built::Empty),
                Built::Tree(t) => break t,
            }
        };
        self.cutting += 1;
        let cutters = self.children(rest.as_slice(), m, color, false);
        self.cutting -= 1;
        let cutters = cutters?.unwrap_or_default();
        Ok(Built::Tree(if cutters.is_empty() { positive } else { CsgTree::Difference(Box::new(positive), cutters) }))
    }

    /// A 2-D shape outside an extrusion: a plate 1 unit thick about its
    /// plane, as OpenSCAD's preview draws it (a subtracted one 1.1 units).
    fn plate(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let region = self.flat(node)?;
        if region.is_empty() {
            return Ok(Built::Empty);
        }
        self.plates.0 += 1;
        self.plates.1.get_or_insert_with(|| node.span.clone());
        let half = if self.cutting > 0 { PLATE.1 } else { PLATE.0 };
        let pieces = convex_pieces(&region);
        self.push_all(node, pieces.iter().map(|p| slab(p, p, -half, half)), m, color)
    }

    /// `hull()`: one convex polyhedron around every corner of the
    /// children's surfaces (spheres and cylinders by their facets, as
    /// OpenSCAD does; a cut or intersected part by its mesh's corners).
    fn hull(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let solid = self.faceted_solid(&node.children, Affine3A::IDENTITY)?;
        let points = surface_points(&solid);
        let what = || "this hull's points (its children's corners)".into();
        self.check(node, Limit::Facets, points.len() as u64, what)?;
        let Some(poly) = convex_hull(&points) else { return Ok(Built::Empty) };
        let shape = Shape::Polyhedron(poly);
        self.push(Primitive { shape, transform: m, color, source: node.span.clone() })
    }

    /// `minkowski()`: each child as a union of convex pieces (its parts, or
    /// for a child cut or intersected the pieces [`convex_summands`] splits it
    /// into), then the union, over every choice of one piece per child, of
    /// the hull of the sums of their corners (a Minkowski sum distributes
    /// over unions, and that of convex pieces is the hull of their corners'
    /// sums). Children holding meshes, or splitting into more than
    /// [`MINKOWSKI_PIECES`] pieces, are summed by Manifold as meshes, into
    /// one closed mesh.
    fn minkowski(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let mut solids = Vec::new();
        for kid in node.children.iter().filter(|k| !k.background) {
            let solid = self.faceted_solid(std::slice::from_ref(kid), Affine3A::IDENTITY)?;
            if solid.tree.is_none() {
                return Ok(Built::Empty);
            }
            solids.push(solid);
        }
        let pieces: Option<Vec<_>> = solids.iter().map(|s| convex_summands(s, MINKOWSKI_PIECES)).collect();
        let Some(factors) = pieces else {
            let mesh = minkowski_of_meshes(&solids);
            return match mesh {
                Some(mesh) => self.push_mesh(node, mesh, m, color),
                None => Ok(Built::Empty),
            };
        };
        let count: u64 = factors.iter().map(|f| f.len() as u64).product();
        self.check(node, Limit::Primitives, count, || "this minkowski()'s pieces (one per choice of parts)".into())?;
        let mut sums: Vec<Vec<Vec3>> = vec![vec![Vec3::ZERO]];
        for factor in &factors {
            sums = sums
                .iter()
                .flat_map(|s| {
                    factor.iter().map(move |part| s.iter().flat_map(|a| part.iter().map(move |b| *a + *b)).collect())
                })
                .collect();
            let most = sums.iter().map(Vec::len).max().unwrap_or(0);
            self.check(node, Limit::Facets, most as u64, || "the points of one of this minkowski()'s hulls".into())?;
        }
        let hulls: Vec<_> = sums.iter().filter_map(|points| convex_hull(points)).collect();
        self.push_all(node, hulls, m, color)
    }

    /// `resize()`: the children scaled about the origin so that their box
    /// takes the new size on each axis given (> 0); an `auto` axis not given
    /// takes the largest scale of those given.
    fn resize(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let size = Vec3::from_slice(&self.floats(node, Some("newsize"), 3)?);
        let auto = self.floats(node, Some("auto"), 3)?;
        let solid = self.faceted_solid(&node.children, Affine3A::IDENTITY)?;
        let Some((lo, hi)) = surface_bounds(&solid) else { return Ok(Built::Empty) };
        let now = hi - lo;
        let given = |i: usize| size[i] > 0.0 && now[i] > 0.0;
        let mut scale = Vec3::ONE;
        for i in 0..3 {
            if given(i) {
                scale[i] = size[i] / now[i];
            }
        }
        let largest = (0..3).filter(|&i| given(i)).map(|i| scale[i]).fold(f32::NAN, f32::max);
        for i in 0..3 {
            if !given(i) && auto[i] != 0.0 && largest.is_finite() {
                scale[i] = largest;
            }
        }
        self.union(&node.children, m * Affine3A::from_scale(scale), color)
    }

    /// `linear_extrude()`: each convex piece of the children's region made a
    /// prism ([`Layers`]); twisted or stretched, OpenSCAD's mesh of it.
    fn linear_extrude(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let height = self.number(node, "height")?;
        let twist_deg = self.number_or(node, "twist", 0.0)?;
        let scale = if node.arg("scale").is_some() { self.pair(node, "scale")?.max(DVec2::ZERO) } else { DVec2::ONE };
        if !(height > 0.0 && height.is_finite()) {
            return Ok(Built::Empty);
        }
        let region = self.flat_children(node)?;
        let slices = if twist_deg != 0.0 {
            self.number_or(node, "slices", 1.0)?.max(1.0)
        } else if scale.x != scale.y {
            // OpenSCAD's slices for a stretched extrusion: $fn, else one per
            // $fs along the longest path a corner takes.
            let fine = self.number_or(node, "$fn", 0.0)?;
            let reach = region.points().map(|p| (p - p * scale).length_squared()).fold(0.0, f64::max);
            let fs = self.number_or(node, "$fs", 2.0)?.max(1e-9);
            if fine > 0.0 {
                fine.floor().max(1.0)
            } else {
                ((reach + height * height).sqrt() / fs).max(1.0).ceil()
            }
        } else {
            1.0
        };
        self.check(node, Limit::Slices, slices.min(1e18) as u64, || "this linear_extrude()'s slices".into())?;
        let z0 = if self.flag_or(node, "center", false)? { -height / 2.0 } else { 0.0 };
        let layers = Layers { z0, height, twist_deg, slices: slices as usize, scale };
        let pieces = if layers.prisms() { convex_pieces(&region) } else { Vec::new() };
        if pieces.is_empty() || pieces.len() > MESHED_PIECES {
            return match layers.mesh(&region) {
                Some(mesh) => self.push_mesh(node, mesh, m, color),
                None => Ok(Built::Empty),
            };
        }
        let slabs: Vec<_> = pieces.iter().flat_map(|p| layers.slabs(p)).collect();
        self.push_all(node, slabs, m, color)
    }

    /// `rotate_extrude()`: each convex piece of the children's region (all
    /// on one side of the y axis, as OpenSCAD asks) revolved about z in
    /// OpenSCAD's segments.
    fn rotate_extrude(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let angle = self.number_or(node, "angle", 360.0)?.clamp(-360.0, 360.0);
        let region = self.flat_children(node)?;
        let Some((lo, hi)) = region.bounds() else { return Ok(Built::Empty) };
        if lo.x < 0.0 && hi.x > 0.0 {
            let message = format!(
                "all points of a rotate_extrude()'s shape must lie on one side of the y axis (x runs from {} to {})",
                lo.x, hi.x
            );
            return Err(self.invalid(&node.span, message));
        }
        if angle == 0.0 {
            return Ok(Built::Empty);
        }
        let reach = lo.x.abs().max(hi.x.abs());
        if !self.faceted(node)? {
            return self.revolve_exactly(node, &region, angle, (lo, hi), m, color);
        }
        let full = self.fragments(node, reach as f32)? as f64;
        // OpenSCAD 2021.01 truncates a part turn's share of the fragments.
        let segments = (full * angle.abs() / 360.0).max(1.0).floor();
        self.check(node, Limit::Slices, segments as u64, || "this rotate_extrude()'s segments".into())?;
        let pieces = convex_pieces(&region);
        let parts: Vec<_> = pieces.iter().flat_map(|p| revolved(p, angle, segments as usize)).collect();
        self.push_all(node, parts, m, color)
    }

    /// `rotate_extrude()` of `region` (bounded by `lo`, `hi`) in exact
    /// geometry: each convex piece its cones ([`revolution`]), a part turn cut
    /// by one wedge or (past half a turn) the union of two.
    fn revolve_exactly(
        &mut self,
        node: &CsgNode,
        region: &Region,
        angle: f64,
        (lo, hi): (DVec2, DVec2),
        m: Affine3A,
        color: Option<Vec4>,
    ) -> Result<Built> {
        // A shape left of the axis sweeps the far side: radius −x, half a turn on.
        let left = hi.x <= 0.0;
        let turn = if left { 180.0 } else { 0.0 };
        let (from, to) = if angle > 0.0 { (turn, turn + angle) } else { (turn + angle, turn) };
        let reach = 1.01 * lo.x.abs().max(hi.x.abs()) + 1e-6;
        let margin = 0.01 * (hi.y - lo.y) + 1e-6;
        let (z0, z1) = (lo.y - margin, hi.y + margin);
        let wedges: Vec<ConvexPolyhedron> = match to - from {
            a if a >= 360.0 => Vec::new(),
            a if a <= 180.0 => vec![wedge(from, to, reach, z0, z1)],
            _ => vec![wedge(from, from + 180.0, reach, z0, z1), wedge(from + 180.0, to, reach, z0, z1)],
        };
        let mut parts = Vec::new();
        for piece in convex_pieces(region) {
            let piece: Vec<DVec2> =
                if left { piece.iter().rev().map(|p| DVec2::new(-p.x, p.y)).collect() } else { piece };
            let Some(rev) = revolution(&piece) else { continue };
            let mut within = Vec::new();
            for cone in &rev.within {
                within.extend(self.push_cone(node, cone, m, color)?.into_tree());
            }
            if !wedges.is_empty() {
                within.extend(self.push_all(node, wedges.iter().cloned(), m, color)?.into_tree());
            }
            let mut without = Vec::new();
            for cone in &rev.without {
                without.extend(self.push_cone(node, cone, m, color)?.into_tree());
            }
            let Built::Tree(body) = combine(within, CsgTree::Intersection) else { continue };
            parts.push(if without.is_empty() { body } else { CsgTree::Difference(Box::new(body), without) });
        }
        Ok(combine(parts, CsgTree::Union))
    }

    /// A frustum about the z axis, placed by `m`, as a quadric primitive.
    fn push_cone(&mut self, node: &CsgNode, cone: &Cone, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let big = cone.r0.max(cone.r1);
        let size = Vec3::new(big as f32, big as f32, (cone.z1 - cone.z0) as f32);
        let place = Affine3A::from_scale_rotation_translation(size, glam::Quat::IDENTITY, Vec3::Z * cone.z0 as f32);
        let shape = Shape::Frustum { bottom: (cone.r0 / big) as f32, top: (cone.r1 / big) as f32 };
        self.push(Primitive { shape, transform: m * place, color, source: node.span.clone() })
    }

    /// The union of a node's children as one 2-D region (an extrusion's
    /// shape), or the DXF drawing the extrusion names in `file`.
    fn flat_children(&mut self, node: &CsgNode) -> Result<Region> {
        // The old way: a DXF drawing named by the extrusion itself.
        if let Some(CsgValue::Text(file)) = node.arg("file").map(|a| &a.value) {
            if !file.is_empty() {
                return self.dxf(node, &file.clone());
            }
        }
        let mut regions = Vec::new();
        for kid in &node.children {
            regions.push(self.flat(kid)?);
        }
        Ok(Region::union(&regions))
    }
}
