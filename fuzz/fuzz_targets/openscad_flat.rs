//! OpenSCAD's 2-D shapes and extrusions: each input byte picks a node and
//! its numbers (squares, circles, polygons with holes, text, offsets, 2-D
//! booleans, hulls, Minkowski sums, resizes; straight, twisted, stretched and
//! revolved extrusions), the tree written as OpenSCAD writes a `.csg`, then
//! read, drawn by the scanline walk beside rays, and rendered.
#![no_main]
use std::path::Path;
use std::sync::Arc;

use kage::csg::openscad::{load_csg, CsgOptions, Geometry};

/// The input as a stream of small numbers.
struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn next(&mut self) -> u8 {
        let (first, rest) = self.0.split_first().map_or((0, &[][..]), |(f, r)| (*f, r));
        self.0 = rest;
        first
    }

    /// A number from −8 to 8 in steps of 1/16, with zero, huge and tiny ones.
    fn number(&mut self) -> String {
        match self.next() {
            255 => "1e30".into(),
            254 => "-1e-30".into(),
            253 => "0".into(),
            b => format!("{}", (f64::from(b) - 128.0) / 16.0),
        }
    }

    /// A 2-D node, nested at most `depth` deep.
    fn flat(&mut self, depth: u32) -> String {
        let kind = if depth == 0 { self.next() % 4 } else { self.next() % 10 };
        let kids = |b: &mut Bytes, depth: u32| -> String {
            let n = 1 + b.next() % 3;
            (0..n).map(|_| b.flat(depth - 1)).collect::<Vec<_>>().join("\n")
        };
        match kind {
            0 => format!("square(size = [{}, {}], center = {});", self.number(), self.number(), self.next() % 2 == 0),
            1 => format!("circle($fn = {}, $fa = 12, $fs = 2, r = {});", self.next() % 40, self.number()),
            2 => {
                let n = 3 + self.next() % 9;
                let points: Vec<String> = (0..n).map(|_| format!("[{}, {}]", self.number(), self.number())).collect();
                let split = 3 + self.next() % n.max(4);
                let paths = if split + 2 < n {
                    format!("[[{}], [{}]]", (0..split).map(|i| i.to_string()).collect::<Vec<_>>().join(", "), (split..n).map(|i| i.to_string()).collect::<Vec<_>>().join(", "))
                } else {
                    "undef".into()
                };
                format!("polygon(points = [{}], paths = {paths}, convexity = 1);", points.join(", "))
            }
            3 => format!("text(text = \"{}\", size = {}, spacing = 1, font = \"\", direction = \"ltr\", language = \"en\", script = \"latin\", halign = \"center\", valign = \"baseline\", $fn = 0, $fa = 12, $fs = 2);", ["Ag", "%&", "ok 52", "W"][self.next() as usize % 4], self.number()),
            4 => format!("offset(r = {}, $fn = 8, $fa = 12, $fs = 2) {{\n{}\n}}", self.number(), kids(self, depth)),
            5 => format!("offset(delta = {}, chamfer = {}, $fn = 0, $fa = 12, $fs = 2) {{\n{}\n}}", self.number(), self.next() % 2 == 0, kids(self, depth)),
            6 => format!("{}() {{\n{}\n}}", ["union", "difference", "intersection"][self.next() as usize % 3], kids(self, depth)),
            7 => format!("{}() {{\n{}\n}}", ["hull", "minkowski", "group"][self.next() as usize % 3], kids(self, depth)),
            8 => format!("resize(newsize = [{},{},0], auto = [1,0,0], convexity = 0) {{\n{}\n}}", self.number(), self.number(), kids(self, depth)),
            _ => format!("multmatrix([[{}, {}, 0, {}], [{}, {}, 0, {}], [0, 0, 1, 0], [0, 0, 0, 1]]) {{\n{}\n}}", self.number(), self.number(), self.number(), self.number(), self.number(), self.number(), kids(self, depth)),
        }
    }

    /// An extrusion of a 2-D node.
    fn solid(&mut self) -> String {
        let shape = self.flat(2);
        match self.next() % 4 {
            0 => format!("linear_extrude(height = {}, center = false, convexity = 1, scale = [{}, {}], $fn = 0, $fa = 12, $fs = 2) {{\n{shape}\n}}", self.number(), self.number(), self.number()),
            1 => format!("linear_extrude(height = {}, center = true, convexity = 1, twist = {}, slices = {}, scale = [{}, {}]) {{\n{shape}\n}}", self.number(), self.number(), self.next() % 30, self.number(), self.number()),
            2 => format!("rotate_extrude(angle = {}, convexity = 2, $fn = {}, $fa = 12, $fs = 2) {{\n{shape}\n}}", f64::from(self.next()) * 2.0 - 200.0, self.next() % 40),
            _ => shape,
        }
    }
}

libfuzzer_sys::fuzz_target!(|bytes: &[u8]| {
    let mut input = Bytes(bytes);
    let text = format!("{}\n{}\n", input.solid(), input.solid());
    let limits = kage_fuzz::limits();
    for geometry in [Geometry::Exact, Geometry::Faceted] {
        let options = CsgOptions { geometry, skip_unsupported: true };
        let Ok(loaded) = load_csg(Path::new("m.csg"), Arc::from(text.as_str()), &options, &limits) else { continue };
        if let Some(bounds) = loaded.solid.bounds() {
            let camera = kage::csg::openscad::default_view(bounds);
            kage_fuzz::walk_beside_rays(&loaded.solid, &camera, kage_fuzz::SIZE, false);
        }
    }
    kage_fuzz::model("m.csg", text.as_bytes());
});
