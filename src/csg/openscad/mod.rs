//! OpenSCAD `.csg` files as CSG solids.
//!
//! [`syntax`] reads the file into a tree of nodes; this module says what the nodes
//! mean, following `../shared/peers/openscad/CSG_FORMAT.md` §3–5:
//!
//! - `group`, `union`, `render` are unions; `intersection`; `difference` (its first
//!   written child is the positive one: if that is empty, so is the difference);
//! - `multmatrix` composes its 4 × 4 matrix onto the children's (a singular one
//!   flattens them to nothing); `color` gives its colour to the primitives below
//!   unless an outer `color` already did (the outermost wins; `[-1, -1, -1, a]` is
//!   "no colour");
//! - `cube`, `sphere`, `cylinder` and convex `polyhedron` are primitives (sizes
//!   ≤ 0 and zero-radius cylinders make nothing, as in OpenSCAD); a polyhedron is
//!   checked for convexity and planar faces;
//! - `%` subtrees are not part of the model and are skipped; `#` is plain;
//! - `hull()` of primitives (under groups, transforms, colours) is one convex
//!   polyhedron around their corners, spheres and cylinders by their facets;
//! - every other node (`linear_extrude`, `text`, `import`, `minkowski`, ...) is
//!   an error naming the node, file, line and column, or, with
//!   [`CsgOptions::skip_unsupported`], skipped with a warning.
//!
//! Spheres and cylinders are exact quadrics ([`Geometry::Exact`], seed 003's
//! primitives) or the convex polyhedra OpenSCAD's own mesh uses
//! ([`Geometry::Faceted`], by its `$fn/$fa/$fs` rules), so kage's image can be
//! compared pixel for pixel with OpenSCAD's. A `$fn` of 8 or less is always
//! faceted: hexagonal nut traps are meant to be hexagons.

mod hull;
pub mod syntax;

use std::f32::consts::PI;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Mat4, Vec3, Vec4};

use super::model::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use crate::camera::{Camera, Projection};
use crate::error::{Error, Result, SourceLocation};
use crate::limits::{Limit, Limits};
use hull::{bounds_size, convex_from_faces, convex_hull};
use syntax::{parse_csg, CsgNode, CsgValue};

/// How spheres and cylinders become primitives.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Geometry {
    /// True quadrics (seed 003).
    #[default]
    Exact,
    /// The convex polyhedra OpenSCAD tessellates them into.
    Faceted,
}

/// How a `.csg` file is read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CsgOptions {
    /// Exact quadrics or OpenSCAD's facets.
    pub geometry: Geometry,
    /// Skip nodes kage cannot render (with a warning) instead of failing.
    pub skip_unsupported: bool,
}

/// A `.csg` file read as a solid.
#[derive(Debug, Clone)]
pub struct LoadedCsg {
    /// The solid.
    pub solid: CsgSolid,
    /// What was skipped or changed, one line each, with its location.
    pub warnings: Vec<String>,
}

/// The camera of an OpenSCAD camera sidecar (the corpus's `NAME.camera.txt`:
/// `key=value` lines with `eye`, `center`, `up`, `fovy_deg`, `near`, `far` and
/// `imgsize`), with the image size it was made for; `None` if a field is
/// missing or malformed.
#[must_use]
pub fn sidecar_camera(text: &str) -> Option<(Camera, u32, u32)> {
    let field = |key: &str| -> Option<Vec<f32>> {
        let line = text.lines().find_map(|l| l.strip_prefix(key)?.strip_prefix('='))?;
        line.split(',').map(|v| v.trim().parse().ok()).collect()
    };
    let v3 = |key: &str| field(key).filter(|v| v.len() == 3).map(|v| Vec3::new(v[0], v[1], v[2]));
    let scalar = |key: &str| field(key).and_then(|v| v.first().copied());
    let size = field("imgsize").filter(|v| v.len() == 2)?;
    let camera = Camera {
        eye: v3("eye")?,
        target: v3("center")?,
        up: v3("up")?,
        near: scalar("near")?,
        far: scalar("far")?,
        projection: Projection::Perspective { fov_y_deg: scalar("fovy_deg")? },
        shift: glam::Vec2::ZERO,
    };
    Some((camera, size[0] as u32, size[1] as u32))
}

/// OpenSCAD's default view of a model with bounds `(lo, hi)` (CSG_FORMAT.md
/// §7): looking at the centre from 35° above the xy-plane and 25° round from
/// −y, z up, at the distance where the bounding sphere fills the 22.5° field of
/// view; near and far at 0.1 and 100 times that distance.
#[must_use]
pub fn default_view((lo, hi): (Vec3, Vec3)) -> Camera {
    let fov_y_deg: f32 = 22.5;
    let centre = (lo + hi) * 0.5;
    let radius = ((hi - lo).length() * 0.5).max(1e-3);
    let distance = radius / (fov_y_deg * 0.5).to_radians().sin();
    let (elevation, azimuth) = (35f32.to_radians(), 25f32.to_radians());
    let towards_eye = Vec3::new(elevation.cos() * azimuth.sin(), -elevation.cos() * azimuth.cos(), elevation.sin());
    Camera {
        eye: centre + towards_eye * distance,
        target: centre,
        up: Vec3::Z,
        near: 0.1 * distance,
        far: 100.0 * distance,
        projection: Projection::Perspective { fov_y_deg },
        shift: glam::Vec2::ZERO,
    }
}

/// `$fn` at or below which spheres and cylinders stay faceted in exact mode.
const ALWAYS_FACETED_FN: f64 = 8.0;

/// Reads the text of a `.csg` file (named `path` in messages) as a solid,
/// within `limits` ([`Limit::Nesting`], [`Limit::Segments`], [`Limit::Facets`]
/// and [`Limit::Primitives`] are checked here).
///
/// # Errors
///
/// As [`parse_csg`]; [`Error::CsgInvalid`] for a node kage cannot render
/// (unless [`CsgOptions::skip_unsupported`]), a malformed argument, a
/// polyhedron that is not convex, or a request over a limit.
pub fn load_csg(path: &Path, text: Arc<str>, options: &CsgOptions, limits: &Limits) -> Result<LoadedCsg> {
    let nodes = parse_csg(path, Arc::clone(&text), limits)?;
    let mut b = Builder {
        path: path.to_path_buf(),
        text,
        options: *options,
        limits: *limits,
        solid: CsgSolid::default(),
        warnings: Vec::new(),
    };
    let tree = b.union(&nodes, Affine3A::IDENTITY, None)?;
    b.solid.tree = tree.into_tree().map(CsgTree::flattened);
    Ok(LoadedCsg { solid: b.solid, warnings: b.warnings })
}

/// What a node makes.
enum Built {
    /// Nothing, and it does not count (a `%` subtree, a skipped node).
    Skipped,
    /// A solid with no volume.
    Empty,
    /// A solid.
    Tree(CsgTree),
}

impl Built {
    fn into_tree(self) -> Option<CsgTree> {
        match self {
            Built::Tree(t) => Some(t),
            Built::Skipped | Built::Empty => None,
        }
    }
}

/// One child, or the boolean `make` of several.
fn combine(mut trees: Vec<CsgTree>, make: fn(Vec<CsgTree>) -> CsgTree) -> Built {
    match trees.len() {
        0 => Built::Empty,
        1 => Built::Tree(trees.pop().expect("one tree")),
        _ => Built::Tree(make(trees)),
    }
}

struct Builder {
    path: PathBuf,
    text: Arc<str>,
    options: CsgOptions,
    limits: Limits,
    solid: CsgSolid,
    warnings: Vec<String>,
}

impl Builder {
    fn location(&self, span: &Range<usize>) -> SourceLocation {
        SourceLocation::new(&self.path, Arc::clone(&self.text), span.clone())
    }

    fn invalid(&self, span: &Range<usize>, message: String) -> Error {
        Error::CsgInvalid { location: Box::new(self.location(span)), message }
    }

    fn node(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        if node.background {
            return Ok(Built::Skipped);
        }
        let kids = &node.children;
        match node.name.as_str() {
            "group" | "union" | "render" => self.union(kids, m, color),
            "intersection" => self.intersection(kids, m, color),
            "difference" => self.difference(kids, m, color),
            "multmatrix" => {
                let matrix = self.matrix(node)?;
                if matrix.determinant().abs() < 1e-12 {
                    self.warnings.push(format!(
                        "{}: a singular multmatrix flattens its children to nothing",
                        self.location(&node.span)
                    ));
                    return Ok(Built::Empty);
                }
                self.union(kids, m * Affine3A::from_mat4(matrix), color)
            }
            "color" => {
                let rgba = self.floats(node, None, 4)?;
                let own = (rgba[..3] != [-1.0; 3]).then(|| Vec4::from_slice(&rgba));
                if own.is_some_and(|c| !c.cmpge(Vec4::ZERO).all() || !c.cmple(Vec4::ONE).all()) {
                    let message = format!("colour components must be between 0 and 1, not {rgba:?}");
                    return Err(self.invalid(&node.span, message));
                }
                self.union(kids, m, color.or(own))
            }
            "hull" => self.hull(node, m, color),
            "cube" | "sphere" | "cylinder" | "polyhedron" => {
                let Some(p) = self.primitive(node, m, color)? else { return Ok(Built::Empty) };
                self.push(p)
            }
            name => {
                let message = format!("`{name}()` is not a node kage renders (only cube, sphere, cylinder, convex polyhedron and their booleans, transforms and colours)");
                if self.options.skip_unsupported {
                    self.warnings.push(format!("{}: skipped: {message}", self.location(&node.span)));
                    Ok(Built::Skipped)
                } else {
                    Err(self.invalid(&node.span, message))
                }
            }
        }
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

    fn union(&mut self, kids: &[CsgNode], m: Affine3A, color: Option<Vec4>) -> Result<Built> {
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
        let cutters = self.children(rest.as_slice(), m, color, false)?.unwrap_or_default();
        Ok(Built::Tree(if cutters.is_empty() { positive } else { CsgTree::Difference(Box::new(positive), cutters) }))
    }

    /// `hull()`: one convex polyhedron around every point of the children's
    /// primitives (spheres and cylinders by their facets, as OpenSCAD does).
    fn hull(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let mut points = Vec::new();
        self.hull_points(&node.children, Affine3A::IDENTITY, &mut points)?;
        let Some(poly) = convex_hull(&points) else { return Ok(Built::Empty) };
        let shape = Shape::Polyhedron(poly);
        self.push(Primitive { shape, transform: m, color, source: node.span.clone() })
    }

    /// Adds `p` to the solid as a leaf, refused past [`Limit::Primitives`].
    fn push(&mut self, p: Primitive) -> Result<Built> {
        let count = self.solid.primitives.len() as u64 + 1;
        if let Err(e) = self.limits.check(Limit::Primitives, count, || "the solid's primitives".into()) {
            return Err(self.invalid(&p.source, e.to_string()));
        }
        self.solid.primitives.push(p);
        Ok(Built::Tree(CsgTree::Leaf(self.solid.primitives.len() - 1)))
    }

    /// The corners of every primitive below `nodes` (placed by `m`) into `out`.
    fn hull_points(&mut self, nodes: &[CsgNode], m: Affine3A, out: &mut Vec<Vec3>) -> Result<()> {
        for node in nodes.iter().filter(|n| !n.background) {
            match node.name.as_str() {
                "group" | "union" | "render" | "color" | "hull" => self.hull_points(&node.children, m, out)?,
                "multmatrix" => self.hull_points(&node.children, m * Affine3A::from_mat4(self.matrix(node)?), out)?,
                "cube" | "sphere" | "cylinder" | "polyhedron" => {
                    let faceted = std::mem::replace(&mut self.options.geometry, Geometry::Faceted);
                    let made = self.primitive(node, m, None);
                    self.options.geometry = faceted;
                    if let Some(Primitive { shape: Shape::Polyhedron(p), transform, .. }) = made? {
                        out.extend(p.vertices.iter().map(|v| transform.transform_point3(*v)));
                    }
                    // Refused as soon as the points pass the limit, not after
                    // a file of 100,000 cubes has been read into the hull.
                    let what = || "this hull's points (its children's corners)".into();
                    if let Err(e) = self.limits.check(Limit::Facets, out.len() as u64, what) {
                        return Err(self.invalid(&node.span, e.to_string()));
                    }
                }
                name => {
                    return Err(self.invalid(&node.span, format!("`{name}()` inside `hull()` is not supported (only primitives, groups, transforms and colours)")));
                }
            }
        }
        Ok(())
    }

    /// A primitive node as a primitive, or `None` if it has no volume.
    fn primitive(&mut self, node: &CsgNode, m: Affine3A, color: Option<Vec4>) -> Result<Option<Primitive>> {
        let made = match node.name.as_str() {
            "cube" => self.cube(node)?,
            "sphere" => self.sphere(node)?,
            "cylinder" => self.cylinder(node)?,
            _ => self.polyhedron(node)?.map(|p| (Shape::Polyhedron(p), Affine3A::IDENTITY)),
        };
        Ok(made.map(|(shape, local)| Primitive { shape, transform: m * local, color, source: node.span.clone() }))
    }

    fn cube(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let size = Vec3::from_slice(&self.floats(node, Some("size"), 3)?);
        if !(size.min_element() > 0.0 && size.is_finite()) {
            return Ok(None);
        }
        let offset = if self.flag(node, "center")? { -size * 0.5 } else { Vec3::ZERO };
        Ok(Some((
            Shape::Polyhedron(ConvexPolyhedron::unit_cube()),
            Affine3A::from_scale_rotation_translation(size, glam::Quat::IDENTITY, offset),
        )))
    }

    fn sphere(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let r = self.number(node, "r")? as f32;
        if !(r > 0.0 && r.is_finite()) {
            return Ok(None);
        }
        let n = self.fragments(node, r)?;
        if !self.faceted(node)? {
            return Ok(Some((Shape::Sphere, Affine3A::from_scale(Vec3::splat(r)))));
        }
        // OpenSCAD's sphere: (n + 1) / 2 rings of n vertices, flat caps, no poles.
        let rings = n.div_ceil(2);
        let facets = (n * (rings - 1) + 2) as u64;
        if let Err(e) = self.limits.check(Limit::Facets, facets, || "this faceted sphere".into()) {
            return Err(self.invalid(&node.span, e.to_string()));
        }
        let points: Vec<Vec3> = (0..rings)
            .flat_map(|k| {
                let phi = PI * (k as f32 + 0.5) / rings as f32;
                circle(n, r * phi.sin(), r * phi.cos())
            })
            .collect();
        let mut faces: Vec<Vec<usize>> = vec![(0..n).collect(), ((rings - 1) * n..rings * n).collect()];
        for k in 0..rings - 1 {
            faces.extend(
                (0..n).map(|i| vec![k * n + i, k * n + (i + 1) % n, (k + 1) * n + (i + 1) % n, (k + 1) * n + i]),
            );
        }
        Ok(Some((Shape::Polyhedron(convex_from_faces(points, &faces)), Affine3A::IDENTITY)))
    }

    fn cylinder(&self, node: &CsgNode) -> Result<Option<(Shape, Affine3A)>> {
        let h = self.number(node, "h")? as f32;
        let (r1, r2) = (self.number(node, "r1")? as f32, self.number(node, "r2")? as f32);
        let big = r1.max(r2);
        if !(h > 0.0 && h.is_finite() && big > 0.0 && big.is_finite() && r1 >= 0.0 && r2 >= 0.0) {
            return Ok(None);
        }
        let z0 = if self.flag(node, "center")? { -h * 0.5 } else { 0.0 };
        if !self.faceted(node)? {
            let to_solid = Affine3A::from_scale_rotation_translation(
                Vec3::new(big, big, h),
                glam::Quat::IDENTITY,
                Vec3::new(0.0, 0.0, z0),
            );
            return Ok(Some((Shape::Frustum { bottom: r1 / big, top: r2 / big }, to_solid)));
        }
        // OpenSCAD's cylinder: two n-gons (a point where a radius is 0) joined by
        // quads or triangles.
        let n = self.fragments(node, big)?;
        let ring = |r: f32, z: f32| if r > 0.0 { circle(n, r, z) } else { vec![Vec3::new(0.0, 0.0, z)] };
        let (bottom, top) = (ring(r1, z0), ring(r2, z0 + h));
        let (nb, nt) = (bottom.len(), top.len());
        let mut faces = Vec::new();
        for i in 0..n {
            let mut f = vec![i % nb, (i + 1) % nb, nb + (i + 1) % nt, nb + i % nt];
            f.dedup();
            if f.first() == f.last() && f.len() > 1 {
                f.pop();
            }
            faces.push(f);
        }
        faces.extend([(0..nb).collect::<Vec<_>>(), (nb..nb + nt).collect()].into_iter().filter(|f| f.len() >= 3));
        let points = bottom.into_iter().chain(top).collect();
        Ok(Some((Shape::Polyhedron(convex_from_faces(points, &faces)), Affine3A::IDENTITY)))
    }

    fn polyhedron(&self, node: &CsgNode) -> Result<Option<ConvexPolyhedron>> {
        let points: Vec<Vec3> =
            self.list(node, "points")?.iter().map(|p| self.vec3(node, "points", p)).collect::<Result<_>>()?;
        let faces: Vec<Vec<usize>> = self
            .list(node, "faces")?
            .iter()
            .map(|f| {
                let CsgValue::Vector(ix) = f else {
                    return Err(
                        self.invalid(&self.span_of(node, "faces"), "a face must be a list of point indices".into())
                    );
                };
                ix.iter()
                    .map(|i| match i {
                        CsgValue::Number(k) if *k >= 0.0 && (*k as usize) < points.len() && k.fract() == 0.0 => {
                            Ok(*k as usize)
                        }
                        _ => Err(self.invalid(
                            &self.span_of(node, "faces"),
                            format!("face index {i:?} is not one of the {} points", points.len()),
                        )),
                    })
                    .collect()
            })
            .collect::<Result<_>>()?;
        if points.len() < 4 || faces.len() < 4 {
            return Ok(None);
        }
        let poly = convex_from_faces(points, &faces);
        let size = bounds_size(&poly.vertices);
        let eps = 1e-4 * size.max(f32::MIN_POSITIVE);
        if let Some(v) = poly.vertices.iter().find(|v| !poly.contains(**v, eps)) {
            return Err(self.invalid(&node.span, format!("this polyhedron is not convex (its point {v} lies outside the plane of one of its faces); kage renders convex polyhedra only")));
        }
        Ok(Some(poly))
    }

    /// Whether a sphere or cylinder is made of facets.
    fn faceted(&self, node: &CsgNode) -> Result<bool> {
        let fine = self.number(node, "$fn")?;
        Ok(self.options.geometry == Geometry::Faceted || (fine > 0.0 && fine <= ALWAYS_FACETED_FN))
    }

    /// OpenSCAD's number of fragments around a circle of radius `r`, at
    /// most [`Limit::Segments`]; `$fn`, `$fa` and `$fs` must be finite (and
    /// `$fa`, `$fs` positive when `$fn` does not decide).
    fn fragments(&self, node: &CsgNode, r: f32) -> Result<usize> {
        let (fine, fa, fs) = (self.number(node, "$fn")?, self.number(node, "$fa")?, self.number(node, "$fs")?);
        for (name, v) in [("$fn", fine), ("$fa", fa), ("$fs", fs)] {
            if !v.is_finite() {
                return Err(
                    self.invalid(&self.span_of(node, name), format!("`{name}` must be a finite number, not {v}"))
                );
            }
        }
        let n = if f64::from(r) < 1e-10 {
            3.0
        } else if fine > 0.0 {
            fine.floor().max(3.0)
        } else if fa <= 0.0 || fs <= 0.0 {
            let name = if fa <= 0.0 { "$fa" } else { "$fs" };
            return Err(self.invalid(&self.span_of(node, name), format!("`{name}` must be above 0 when `$fn` is 0")));
        } else {
            (360.0 / fa).min(2.0 * std::f64::consts::PI * f64::from(r) / fs).max(5.0).ceil()
        };
        let what = || format!("`{}()`'s circle", node.name);
        if let Err(e) = self.limits.check(Limit::Segments, n.min(1e18) as u64, what) {
            let span = self.span_of(node, if fine > 0.0 { "$fn" } else { "$fs" });
            return Err(self.invalid(&span, e.to_string()));
        }
        Ok(n as usize)
    }

    fn arg<'n>(&self, node: &'n CsgNode, name: &str) -> Result<&'n CsgValue> {
        node.arg(name)
            .map(|a| &a.value)
            .ok_or_else(|| self.invalid(&node.span, format!("`{}()` has no `{name}` argument", node.name)))
    }

    fn span_of(&self, node: &CsgNode, name: &str) -> Range<usize> {
        node.arg(name).map_or(node.span.clone(), |a| a.span.clone())
    }

    fn number(&self, node: &CsgNode, name: &str) -> Result<f64> {
        match self.arg(node, name)? {
            CsgValue::Number(x) if x.is_finite() && (*x as f32).is_finite() => Ok(*x),
            CsgValue::Number(x) => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` must be a finite number, not {x}")))
            }
            other => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be a number, not {other:?}")))
            }
        }
    }

    fn flag(&self, node: &CsgNode, name: &str) -> Result<bool> {
        match self.arg(node, name)? {
            CsgValue::Bool(b) => Ok(*b),
            other => {
                Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be true or false, not {other:?}")))
            }
        }
    }

    fn list<'n>(&self, node: &'n CsgNode, name: &str) -> Result<&'n [CsgValue]> {
        match self.arg(node, name)? {
            CsgValue::Vector(v) => Ok(v),
            other => Err(self.invalid(&self.span_of(node, name), format!("`{name}` should be a list, not {other:?}"))),
        }
    }

    fn vec3(&self, node: &CsgNode, name: &str, v: &CsgValue) -> Result<Vec3> {
        let bad = || self.invalid(&self.span_of(node, name), format!("`{name}` should hold [x, y, z] points"));
        let CsgValue::Vector(xs) = v else { return Err(bad()) };
        match xs[..] {
            [CsgValue::Number(x), CsgValue::Number(y), CsgValue::Number(z)] => {
                let p = Vec3::new(x as f32, y as f32, z as f32);
                if p.is_finite() {
                    Ok(p)
                } else {
                    Err(self.invalid(&self.span_of(node, name), format!("`{name}` holds a point that is not finite")))
                }
            }
            _ => Err(bad()),
        }
    }

    /// `count` numbers from the argument `name` (`None`: the first, unnamed).
    fn floats(&self, node: &CsgNode, name: Option<&str>, count: usize) -> Result<Vec<f32>> {
        let (value, span) = match name {
            Some(n) => (self.arg(node, n)?, self.span_of(node, n)),
            None => node
                .args
                .first()
                .map(|a| (&a.value, a.span.clone()))
                .ok_or_else(|| self.invalid(&node.span, format!("`{}()` needs an argument", node.name)))?,
        };
        let numbers: Option<Vec<f32>> = match value {
            CsgValue::Vector(xs) if xs.len() == count => xs
                .iter()
                .map(|x| if let CsgValue::Number(v) = x { Some(*v as f32).filter(|v| v.is_finite()) } else { None })
                .collect(),
            _ => None,
        };
        numbers.ok_or_else(|| self.invalid(&span, format!("expected {count} finite numbers")))
    }

    /// `multmatrix`'s row-major 4 × 4 matrix.
    fn matrix(&self, node: &CsgNode) -> Result<Mat4> {
        let bad = || self.invalid(&node.span, "`multmatrix` needs a 4 x 4 matrix of numbers".into());
        let Some(CsgValue::Vector(rows)) = node.args.first().map(|a| &a.value) else { return Err(bad()) };
        let mut m = [[0.0f32; 4]; 4];
        for (r, row) in rows.iter().enumerate().take(4) {
            let CsgValue::Vector(xs) = row else { return Err(bad()) };
            for (c, x) in xs.iter().enumerate().take(4) {
                let CsgValue::Number(v) = x else { return Err(bad()) };
                m[r][c] = *v as f32;
                if !m[r][c].is_finite() {
                    let message = format!("`multmatrix` entry ({}, {}) must be a finite number, not {v}", r + 1, c + 1);
                    return Err(self.invalid(&node.span, message));
                }
            }
        }
        if rows.len() != 4 {
            return Err(bad());
        }
        Ok(Mat4::from_cols_array_2d(&m).transpose())
    }
}

/// `n` points on the circle of radius `r` at height `z`, the first on +x.
fn circle(n: usize, r: f32, z: f32) -> Vec<Vec3> {
    (0..n)
        .map(|i| {
            let a = 2.0 * PI * i as f32 / n as f32;
            Vec3::new(r * a.cos(), r * a.sin(), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn load(text: &str, geometry: Geometry) -> Result<LoadedCsg> {
        load_csg(
            Path::new("t.csg"),
            Arc::from(text),
            &CsgOptions { geometry, skip_unsupported: false },
            &Limits::default(),
        )
    }

    fn solid(text: &str) -> CsgSolid {
        load(text, Geometry::Exact).unwrap().solid
    }

    #[test]
    fn transforms_compose_and_primitives_keep_their_exact_shape() {
        // A sphere of radius 2 moved to x = 10 inside a scale by 2 in z: an ellipsoid.
        let s = solid("multmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 2, 0], [0, 0, 0, 1]]) {\n\tmultmatrix([[1, 0, 0, 10], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {\n\t\tsphere($fn = 0, $fa = 12, $fs = 2, r = 2);\n\t}\n}\n");
        assert!(s.contains(Vec3::new(10.0, 0.0, 3.9)) && !s.contains(Vec3::new(10.0, 0.0, 4.1)));
        assert!(s.contains(Vec3::new(11.9, 0.0, 0.0)) && !s.contains(Vec3::new(12.1, 0.0, 0.0)));
        // A centred cone: radius 3 at the bottom, 0 at the top.
        let c = solid("cylinder($fn = 0, $fa = 12, $fs = 2, h = 4, r1 = 3, r2 = 0, center = true);");
        assert!(c.contains(Vec3::new(2.9, 0.0, -1.99)) && !c.contains(Vec3::new(1.6, 0.0, 0.0)));
        assert!(c.contains(Vec3::new(1.4, 0.0, 0.0)) && !c.contains(Vec3::new(0.0, 0.0, 2.1)));
    }

    #[test]
    fn booleans_background_parts_and_empty_children_follow_openscad() {
        let cube = "cube(size = [2, 2, 2], center = true);";
        let ball = "sphere($fn = 0, $fa = 12, $fs = 2, r = 1.2);";
        let s = solid(&format!("difference() {{\n{cube}\n{ball}\n}}"));
        assert!(!s.contains(Vec3::ZERO) && s.contains(Vec3::splat(0.95)));
        let s = solid(&format!("intersection() {{\n{cube}\n{ball}\n}}"));
        assert!(s.contains(Vec3::ZERO) && !s.contains(Vec3::splat(0.95)));
        // A `%` part is not part of the model: the difference keeps its cube whole.
        let s = solid(&format!("difference() {{\n{cube}\n%{ball}\n}}"));
        assert!(s.contains(Vec3::ZERO));
        // An empty first child empties the difference; an empty cutter cuts nothing.
        assert_eq!(solid(&format!("difference() {{\n\tgroup();\n{cube}\n}}")).tree, None);
        assert!(solid(&format!("difference() {{\n{cube}\n\tcube(size = [0, 1, 1], center = false);\n}}"))
            .contains(Vec3::ZERO));
        assert_eq!(solid(&format!("intersection() {{\n{cube}\n\tcylinder($fn = 0, $fa = 12, $fs = 2, h = 1, r1 = 0, r2 = 0, center = false);\n}}")).tree, None);
    }

    #[test]
    fn the_outermost_colour_wins() {
        let s = solid("color([1, 0, 0, 1]) {\n\tcolor([0, 1, 0, 1]) {\n\t\tcube(size = [1, 1, 1], center = false);\n\t}\n}\ncolor([-1, -1, -1, 1]) {\n\tcolor([0, 0, 1, 0.5]) {\n\t\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n\t}\n}\n");
        assert_eq!(s.primitives[0].color, Some(Vec4::new(1.0, 0.0, 0.0, 1.0)));
        assert_eq!(s.primitives[1].color, Some(Vec4::new(0.0, 0.0, 1.0, 0.5)), "[-1, -1, -1, a] is no colour");
    }

    #[test]
    fn small_fn_stays_faceted_and_faceted_mode_follows_openscads_rules() {
        // A hexagonal prism (a nut trap): the point between two corners, just
        // outside the flat side, is outside even in exact mode.
        let hex = solid("cylinder($fn = 6, $fa = 12, $fs = 2, h = 1, r1 = 1, r2 = 1, center = false);");
        let Shape::Polyhedron(p) = &hex.primitives[0].shape else { panic!("faceted") };
        assert_eq!(p.planes.len(), 8);
        assert!(!hex.contains(Vec3::new(0.0, 0.9, 0.5)) && hex.contains(Vec3::new(0.0, 0.85, 0.5)));
        // r = 10 with the defaults: 30 fragments, 15 rings, flat caps at z = ±9.945.
        let ball = load("sphere($fn = 0, $fa = 12, $fs = 2, r = 10);", Geometry::Faceted).unwrap().solid;
        let Shape::Polyhedron(p) = &ball.primitives[0].shape else { panic!("faceted") };
        assert_eq!((p.vertices.len(), p.planes.len()), (15 * 30, 2 + 14 * 30));
        assert!(ball.contains(Vec3::new(0.0, 0.0, 9.94)) && !ball.contains(Vec3::new(0.0, 0.0, 9.95)));
    }

    #[test]
    fn what_cannot_be_rendered_is_named_with_its_place() {
        let concave = "group() {\n\tpolyhedron(points = [[0, 0, 0], [4, 0, 0], [4, 4, 0], [0, 4, 0], [2, 2, 1], [2, 2, -3]], faces = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4], [1, 0, 5], [2, 1, 5], [3, 2, 5], [0, 3, 5]], convexity = 1);\n}\n";
        // Convex as written (a double pyramid), so it loads; now dent its top in.
        assert!(load(concave, Geometry::Exact).is_ok());
        let dented = concave.replace("[2, 2, 1]", "[2, 2, -1]");
        match load(&dented, Geometry::Exact) {
            Err(Error::CsgInvalid { location, message }) => {
                assert_eq!((location.line, location.column), (2, 2), "{message}");
                assert!(message.contains("not convex"), "{message}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        let text = "group() {\n\tlinear_extrude(height = 1, center = false, convexity = 1, scale = [1, 1], $fn = 0, $fa = 12, $fs = 2) {\n\t\tsquare(size = [1, 1], center = false);\n\t}\n\tcube(size = [1, 1, 1], center = false);\n}\n";
        match load(text, Geometry::Exact) {
            Err(e @ Error::CsgInvalid { .. }) => {
                let shown = e.to_string();
                assert!(shown.starts_with("t.csg:2:2: `linear_extrude()` is not a node kage renders"), "{shown}");
            }
            other => panic!("expected an error, got {other:?}"),
        }
        let options = CsgOptions { geometry: Geometry::Exact, skip_unsupported: true };
        let loaded = load_csg(Path::new("t.csg"), Arc::from(text), &options, &Limits::default()).unwrap();
        assert_eq!(loaded.solid.primitives.len(), 1);
        assert!(loaded.warnings[0].starts_with("t.csg:2:2: skipped"), "{:?}", loaded.warnings);
    }

    #[test]
    fn a_hull_of_two_balls_is_a_capsule_around_their_facets() {
        let ball = |x: i32| {
            format!("\tmultmatrix([[1, 0, 0, {x}], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]) {{\n\t\tsphere($fn = 0, $fa = 12, $fs = 2, r = 10);\n\t}}\n")
        };
        let s = solid(&format!("hull() {{\n{}{}}}\n", ball(0), ball(40)));
        assert_eq!(s.primitives.len(), 1);
        assert!(s.contains(Vec3::new(20.0, 9.0, 0.0)) && !s.contains(Vec3::new(20.0, 10.5, 0.0)));
        assert!(s.contains(Vec3::new(49.0, 0.0, 0.0)) && !s.contains(Vec3::new(51.0, 0.0, 0.0)));
        let Shape::Polyhedron(p) = &s.primitives[0].shape else { panic!("a polyhedron") };
        // Coplanar triangles merged: the two flat caps are one plane each.
        assert_eq!(p.planes.iter().filter(|q| q.z.abs() > 0.999).count(), 2);
    }

    #[test]
    fn a_singular_transform_flattens_its_children_to_nothing() {
        let loaded = load("multmatrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 0, 0], [0, 0, 0, 1]]) {\n\tcube(size = [1, 1, 1], center = false);\n}\n", Geometry::Exact).unwrap();
        assert_eq!(loaded.solid.tree, None);
        assert_eq!(loaded.warnings.len(), 1);
    }
}
