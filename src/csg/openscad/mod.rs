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

mod args;
mod drawing;
mod dxf;
mod extrude;
mod flat;
mod hull;
mod import;
mod meshed;
mod pieces;
pub use import::drawing_outlines;
pub use meshed::surface_mesh;
pub use text::text_outlines;
mod partition;
mod planar;
mod primitives;
mod solid;
pub mod syntax;
mod text;

use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Affine3A, Vec3, Vec4};

use super::mesh::ClosedMesh;
use super::model::{ConvexPolyhedron, CsgSolid, CsgTree, Primitive, Shape};
use crate::camera::{Camera, Projection};
use crate::error::{Error, Result, SourceLocation};
use crate::limits::{Limit, Limits};
use syntax::{parse_csg, CsgNode};

/// What a warning about a part left out of the model holds (after its
/// place): the image lacks that part.
pub const SKIPPED: &str = "skipped (not drawn): ";

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
    /// The parts OpenSCAD's preview draws see-through over the model: each
    /// `#` (highlighted) and `%` (background) subtree.
    pub ghosts: Vec<Ghost>,
    /// The `color()` subtrees with an alpha below 1 that stand alone in the
    /// model (no boolean or other operation above them), drawn see-through
    /// in their colour as OpenSCAD's preview draws them.
    pub see_through: Vec<Tinted>,
    /// What was skipped or changed, one line each, with its location.
    pub warnings: Vec<String>,
}

/// A see-through `color()` subtree as its own solid (with OpenSCAD's
/// facets, in the file's space).
#[derive(Debug, Clone)]
pub struct Tinted {
    /// Its colour, sRGB, and alpha (below 1).
    pub color: Vec4,
    /// The subtree's solid.
    pub solid: CsgSolid,
    /// Bytes of the `color()` node.
    pub source: Range<usize>,
}

/// How OpenSCAD's preview marks a part drawn see-through.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GhostKind {
    /// `#`: part of the model, and drawn again in translucent pink on top,
    /// even where it is subtracted (the cutting tool made visible).
    Highlight,
    /// `%`: not part of the model; drawn in translucent grey.
    Background,
}

/// A `#` or `%` subtree as its own solid (with OpenSCAD's facets, in the
/// file's space), to be drawn see-through.
#[derive(Debug, Clone)]
pub struct Ghost {
    /// Which mark.
    pub kind: GhostKind,
    /// The subtree's solid.
    pub solid: CsgSolid,
    /// Bytes of the marked node.
    pub source: Range<usize>,
}

impl GhostKind {
    /// OpenSCAD's preview colour of the mark, sRGB with alpha.
    #[must_use]
    pub fn color(self) -> Vec4 {
        match self {
            GhostKind::Highlight => Vec4::new(1.0, 81.0 / 255.0, 81.0 / 255.0, 0.5),
            GhostKind::Background => Vec4::new(180.0 / 255.0, 180.0 / 255.0, 180.0 / 255.0, 0.5),
        }
    }
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
    load_csg_with(path, text, options, limits, &NoImports)
}

/// [`load_csg`] with the files `import()` and `surface()` name read by
/// `imports` (relative to the `.csg` file's folder).
///
/// # Errors
///
/// As [`load_csg`]; an `import()` or `surface()` whose file cannot be read
/// or drawn is a located [`Error::CsgInvalid`] naming the file.
pub fn load_csg_with(
    path: &Path,
    text: Arc<str>,
    options: &CsgOptions,
    limits: &Limits,
    imports: &dyn Imports,
) -> Result<LoadedCsg> {
    let nodes = parse_csg(path, Arc::clone(&text), limits)?;
    let mut b = Builder::new(path, text, *options, *limits, imports);
    let tree = b.union(&nodes, Affine3A::IDENTITY, None)?;
    b.solid.tree = tree.into_tree().map(CsgTree::flattened);
    if let (count, Some(first)) = b.plates.clone() {
        let message = format!("{count} 2-D shape(s) outside an extrusion, drawn 1 unit thick as OpenSCAD's preview draws them (they are no part of an exported 3-D model)");
        b.warn(&first, message);
    }
    Ok(LoadedCsg { solid: b.solid, ghosts: b.ghosts, see_through: b.see_through, warnings: b.warnings })
}

/// Reads the files a `.csg` names (`import()`, `surface()`), each as
/// written in the file (relative to the `.csg` file's folder).
pub trait Imports {
    /// The vertices and triangles of a mesh file (STL, OFF, OBJ).
    ///
    /// # Errors
    ///
    /// What went wrong, in a sentence naming the file.
    fn mesh(&self, file: &str) -> std::result::Result<(Vec<Vec3>, Vec<[u32; 3]>), String>;
    /// The bytes of a file (a heightmap).
    ///
    /// # Errors
    ///
    /// What went wrong, in a sentence naming the file.
    fn bytes(&self, file: &str) -> std::result::Result<Vec<u8>, String>;
}

/// No files to read: an `import()` or `surface()` says so.
pub struct NoImports;

impl Imports for NoImports {
    fn mesh(&self, file: &str) -> std::result::Result<(Vec<Vec3>, Vec<[u32; 3]>), String> {
        Err(format!("{file}: the model was not read from a folder, so its imports cannot be found"))
    }

    fn bytes(&self, file: &str) -> std::result::Result<Vec<u8>, String> {
        self.mesh(file).map(|_| Vec::new())
    }
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

/// What a node does, by its name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    /// `group`, `union`, `render`.
    Union,
    Intersection,
    Difference,
    /// `multmatrix`.
    Transform,
    Color,
    Hull,
    Minkowski,
    Resize,
    /// `cube`, `sphere`, `cylinder`, `polyhedron`.
    Primitive,
    LinearExtrude,
    RotateExtrude,
    /// `square`, `circle`, `polygon`.
    Shape2d,
    Text,
    Offset,
    Projection,
    /// `import()`: a mesh, or a 2-D drawing.
    Import,
    /// `surface()`: a heightmap.
    Surface,
    /// `fill()`: a 2-D shape without its holes.
    Fill,
}

/// Whether a node's result is flat (2-D) or solid, or as its children's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Dim {
    Flat,
    Solid,
    /// As the first child's that says.
    Children,
    /// As the named file's kind (a 2-D drawing or a mesh).
    File,
}

/// Every node kage reads: its name, what it does, its dimension.
const NODES: [(&str, Kind, Dim); 25] = [
    ("group", Kind::Union, Dim::Children),
    ("union", Kind::Union, Dim::Children),
    ("render", Kind::Union, Dim::Children),
    ("intersection", Kind::Intersection, Dim::Children),
    ("difference", Kind::Difference, Dim::Children),
    ("multmatrix", Kind::Transform, Dim::Children),
    ("color", Kind::Color, Dim::Children),
    ("hull", Kind::Hull, Dim::Children),
    ("minkowski", Kind::Minkowski, Dim::Children),
    ("resize", Kind::Resize, Dim::Children),
    ("cube", Kind::Primitive, Dim::Solid),
    ("sphere", Kind::Primitive, Dim::Solid),
    ("cylinder", Kind::Primitive, Dim::Solid),
    ("polyhedron", Kind::Primitive, Dim::Solid),
    ("linear_extrude", Kind::LinearExtrude, Dim::Solid),
    ("rotate_extrude", Kind::RotateExtrude, Dim::Solid),
    ("square", Kind::Shape2d, Dim::Flat),
    ("circle", Kind::Shape2d, Dim::Flat),
    ("polygon", Kind::Shape2d, Dim::Flat),
    ("text", Kind::Text, Dim::Flat),
    ("offset", Kind::Offset, Dim::Flat),
    ("projection", Kind::Projection, Dim::Flat),
    ("import", Kind::Import, Dim::File),
    ("surface", Kind::Surface, Dim::Solid),
    ("fill", Kind::Fill, Dim::Flat),
];

/// What `node` does, `None` for a node kage does not know.
fn kind(node: &CsgNode) -> Option<Kind> {
    NODES.iter().find(|(name, ..)| *name == node.name).map(|&(_, k, _)| k)
}

/// Whether `node` makes a 2-D shape (`Some(true)`) or a solid: by its kind,
/// or for booleans, transforms and the like by its first child that is not
/// a `%` part and says; `None` for a node with nothing below it that says
/// (an empty group).
fn flatness(node: &CsgNode) -> Option<bool> {
    let (_, _, d) = NODES.iter().find(|(name, ..)| *name == node.name)?;
    match d {
        Dim::Children => node.children.iter().filter(|c| !c.background).find_map(flatness),
        Dim::File => Some(import::drawing(node)),
        Dim::Flat => Some(true),
        Dim::Solid => Some(false),
    }
}

/// Whether `node` makes a 2-D shape ([`flatness`]; an empty group does not).
fn is_flat(node: &CsgNode) -> bool {
    flatness(node) == Some(true)
}

/// Reads a `.csg` file's nodes into a solid.
struct Builder<'a> {
    /// Reads the files `import()` and `surface()` name.
    imports: &'a dyn Imports,
    path: PathBuf,
    text: Arc<str>,
    options: CsgOptions,
    limits: Limits,
    solid: CsgSolid,
    warnings: Vec<String>,
    /// Inside how many differences' cutters the node at hand lies (a 2-D
    /// shape there is drawn a little thicker, as OpenSCAD's preview does).
    cutting: u32,
    /// 2-D shapes drawn as plates: how many, and the first one's place.
    plates: (usize, Option<Range<usize>>),
    /// `#` and `%` subtrees (none gathered in a builder of a subtree's own).
    ghosts: Vec<Ghost>,
    /// Whether `#` and `%` marks make ghosts here.
    ghostly: bool,
    /// Whether only groups, unions, transforms and colours lie above the node
    /// at hand (a see-through colour there becomes a part of its own).
    open: bool,
    /// See-through `color()` subtrees.
    see_through: Vec<Tinted>,
}

impl Builder<'_> {
    /// A builder for the file `path` holding `text`, its imports read by `imports`.
    fn new<'a>(
        path: &Path,
        text: Arc<str>,
        options: CsgOptions,
        limits: Limits,
        imports: &'a dyn Imports,
    ) -> Builder<'a> {
        Builder {
            imports,
            path: path.to_path_buf(),
            text,
            options,
            limits,
            solid: CsgSolid::default(),
            warnings: Vec::new(),
            cutting: 0,
            plates: (0, None),
            ghosts: Vec::new(),
            ghostly: true,
            open: true,
            see_through: Vec::new(),
        }
    }

    fn location(&self, span: &Range<usize>) -> SourceLocation {
        SourceLocation::new(&self.path, Arc::clone(&self.text), span.clone())
    }

    fn invalid(&self, span: &Range<usize>, message: String) -> Error {
        Error::CsgInvalid { location: Box::new(self.location(span)), message }
    }

    /// A warning about `span`.
    fn warn(&mut self, span: &Range<usize>, message: impl std::fmt::Display) {
        let line = format!("{}: {message}", self.location(span));
        self.warnings.push(line);
    }

    /// A node kage cannot draw: an error, or skipped with a warning
    /// ([`CsgOptions::skip_unsupported`]) that holds [`SKIPPED`].
    fn unsupported(&mut self, node: &CsgNode, message: String) -> Result<()> {
        if self.options.skip_unsupported {
            self.warn(&node.span, format!("{SKIPPED}{message}"));
            Ok(())
        } else {
            Err(self.invalid(&node.span, message))
        }
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

    /// A `#` or `%` subtree as a ghost of its own (placed by `m`).
    fn ghost(&mut self, node: &CsgNode, kind: GhostKind, m: Affine3A) -> Result<()> {
        let plain = CsgNode { background: false, highlight: false, ..node.clone() };
        let solid = self.faceted_solid(std::slice::from_ref(&plain), m)?;
        if solid.tree.is_some() {
            self.ghosts.push(Ghost { kind, solid, source: node.span.clone() });
        }
        Ok(())
    }

    /// A closed mesh placed by `m`, made by `node`: the union of its layers.
    fn push_mesh(&mut self, node: &CsgNode, mesh: ClosedMesh, m: Affine3A, color: Option<Vec4>) -> Result<Built> {
        let mesh = Arc::new(mesh);
        let first = self.solid.primitives.len();
        for layer in 0..mesh.layers() {
            let shape = Shape::Mesh { mesh: Arc::clone(&mesh), layer };
            self.push(Primitive { shape, transform: m, color, source: node.span.clone() })?;
        }
        Ok(Built::Tree(CsgTree::mesh_layers(first, mesh.layers())))
    }

    /// The union of convex `pieces` placed by `m`, made by `node`.
    fn push_all(
        &mut self,
        node: &CsgNode,
        pieces: impl IntoIterator<Item = ConvexPolyhedron>,
        m: Affine3A,
        color: Option<Vec4>,
    ) -> Result<Built> {
        let mut trees = Vec::new();
        for poly in pieces {
            let shape = Shape::Polyhedron(poly);
            if let Built::Tree(t) = self.push(Primitive { shape, transform: m, color, source: node.span.clone() })? {
                trees.push(t);
            }
        }
        Ok(combine(trees, CsgTree::Union))
    }
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

    /// A small deterministic generator of points in a box.
    fn points(n: usize, lo: Vec3, hi: Vec3) -> impl Iterator<Item = Vec3> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..n).map(move |_| lo + (hi - lo) * Vec3::new(next(), next(), next()))
    }

    #[test]
    fn an_exact_revolution_is_its_profile_turned() {
        // An L-shaped profile (a rectangle with a step: non-convex, two or
        // more pieces) left of the axis, turned 250° the negative way, and a
        // triangle touching the axis turned whole (a cone less a cone).
        let l_shape =
            "polygon(points = [[-2, 0], [-6, 0], [-6, 1], [-3, 1], [-3, 4], [-2, 4]], paths = undef, convexity = 1);";
        let cases = [
            (format!("rotate_extrude(angle = -250, convexity = 2, $fn = 0, $fa = 12, $fs = 2) {{\n{l_shape}\n}}"), -250.0),
            ("rotate_extrude(angle = 360, convexity = 2, $fn = 0, $fa = 12, $fs = 2) {\npolygon(points = [[0, 0], [3, 0], [1, 2]], paths = undef, convexity = 1);\n}".to_string(), 360.0),
        ];
        let in_l = |r: f32, z: f32| {
            (2.0..6.0).contains(&r) && (0.0..1.0).contains(&z) || (2.0..3.0).contains(&r) && (0.0..4.0).contains(&z)
        };
        let in_tri = |r: f32, z: f32| z > 0.0 && r >= 0.0 && r < 3.0 - z && r > 0.5 * z;
        for (k, (text, angle)) in cases.iter().enumerate() {
            let s = solid(text);
            let mut wrong = Vec::new();
            for p in points(20_000, Vec3::new(-7.0, -7.0, -1.0), Vec3::new(7.0, 7.0, 5.0)) {
                let (r, z) = (p.truncate().length(), p.z);
                let truth = if k == 0 {
                    // The shape's radius is −x: it sweeps from 180° (x < 0) by −250°.
                    let a = (p.y.atan2(p.x).to_degrees() - 180.0).rem_euclid(360.0);
                    in_l(r, z) && (a == 0.0 || a >= 360.0 + angle)
                } else {
                    in_tri(r, z)
                };
                // Points within a hair of a surface may go either way.
                let near = |q: Vec3| s.contains(q) != truth;
                if near(p) && [Vec3::X, Vec3::Y, Vec3::Z].iter().all(|&d| near(p + d * 1e-3) && near(p - d * 1e-3)) {
                    wrong.push(p);
                }
            }
            assert!(
                wrong.is_empty(),
                "case {k}: {} points wrong, e.g. {:?}",
                wrong.len(),
                &wrong[..wrong.len().min(5)]
            );
        }
        // Exact: a whole turn is quadrics (and a part turn its wedges), not a polyhedron per segment.
        let tube = solid("rotate_extrude($fn = 0, $fa = 12, $fs = 2) {\npolygon(points = [[5, 0], [6, 0], [6, 2], [5, 2]], paths = undef, convexity = 1);\n}\n");
        assert_eq!(tube.primitives.len(), 2);
        assert!(tube.primitives.iter().all(|p| matches!(p.shape, Shape::Frustum { .. })));
        assert!(tube.contains(Vec3::new(0.0, 5.05, 1.0)) && !tube.contains(Vec3::new(0.0, 4.95, 1.0)));
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
    fn a_missing_font_is_said_and_helvetica_is_liberation_sans_as_fontconfig_has_it() {
        let text = |font: &str| {
            format!("linear_extrude(height = 1, center = false, convexity = 1, scale = [1, 1], $fn = 0, $fa = 12, $fs = 2) {{\n\ttext(text = \"Hi\", size = 10, spacing = 1, font = \"{font}\", direction = \"ltr\", language = \"en\", script = \"latin\", halign = \"left\", valign = \"baseline\", $fn = 0, $fa = 12, $fs = 2);\n}}\n")
        };
        let warnings = |font: &str| load(&text(font), Geometry::Exact).unwrap().warnings;
        assert!(warnings("Helvetica:style=Bold").is_empty(), "{:?}", warnings("Helvetica:style=Bold"));
        let missing = warnings("No Such Typeface:style=Bold");
        assert!(
            missing.len() == 1 && missing[0].contains("No Such Typeface") && missing[0].contains("t.csg:2:2"),
            "{missing:?}"
        );
    }

    #[test]
    fn the_outermost_colour_wins() {
        let s = solid("color([1, 0, 0, 1]) {\n\tcolor([0, 1, 0, 1]) {\n\t\tcube(size = [1, 1, 1], center = false);\n\t}\n}\ncolor([-1, -1, -1, 1]) {\n\tcolor([0, 0, 1, 1]) {\n\t\tsphere($fn = 0, $fa = 12, $fs = 2, r = 1);\n\t}\n}\n");
        assert_eq!(s.primitives[0].color, Some(Vec4::new(1.0, 0.0, 0.0, 1.0)));
        assert_eq!(s.primitives[1].color, Some(Vec4::new(0.0, 0.0, 1.0, 1.0)), "[-1, -1, -1, a] is no colour");
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
        // Convex as written (a double pyramid): one convex primitive.
        let convex = load(concave, Geometry::Exact).unwrap().solid;
        assert!(matches!(convex.primitives[..], [Primitive { shape: Shape::Polyhedron(_), .. }]));
        // Its top dented in: a closed mesh, drawn by its layers.
        let dented = load(&concave.replace("[2, 2, 1]", "[2, 2, -1]"), Geometry::Exact).unwrap().solid;
        assert!(dented.primitives.iter().all(|p| matches!(p.shape, Shape::Mesh { .. })));
        assert!(dented.contains(Vec3::new(0.15, 2.0, -0.1)) && dented.contains(Vec3::new(2.0, 2.0, -2.0)));
        assert!(!dented.contains(Vec3::new(2.0, 2.0, -0.5)) && !dented.contains(Vec3::new(0.5, 2.0, -0.2)));
        // `roof()`, of OpenSCAD's later releases.
        let text = "group() {\n\troof(method = \"voronoi\", convexity = 1) {\n\t\tsquare(size = [1, 1], center = false);\n\t}\n\tcube(size = [1, 1, 1], center = false);\n}\n";
        match load(text, Geometry::Exact) {
            Err(e @ Error::CsgInvalid { .. }) => {
                let shown = e.to_string();
                assert!(shown.starts_with("t.csg:2:2: `roof()` is not a node kage knows"), "{shown}");
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
