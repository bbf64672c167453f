//! `import()` of a DXF drawing (and the old `linear_extrude(file = ...)`,
//! `rotate_extrude(file = ...)`), read as OpenSCAD 2021.01 reads it, so
//! that kage draws the shape OpenSCAD makes of the same file:
//!
//! - The file is pairs of lines, a group code and its value. Only the
//!   `ENTITIES` and `BLOCKS` sections count; `layer` (empty: every layer)
//!   picks the entities drawn.
//! - `LINE`, `LWPOLYLINE` (straight pieces; bulges are not read),
//!   `CIRCLE`, `ARC`, `ELLIPSE` and `INSERT` (a block's lines moved,
//!   scaled and turned) become straight lines; circles, arcs and ellipses
//!   take OpenSCAD's fragment count for their radius (`$fn`, `$fa`, `$fs`).
//!   Any other entity (`POLYLINE`, `SPLINE`, `TEXT`, `HATCH`, ...) is not
//!   drawn and is counted for a warning, as OpenSCAD warns.
//! - A point is `(value − origin) × scale`, then snapped to a grid of
//!   1/1024 (to a neighbouring grid point already used, when one is).
//! - Lines meeting at a grid point are joined into paths: first the open
//!   ones, each from the first line with a loose end, then the closed ones.
//!   An open path is closed by a straight line back to its start.
//! - The paths are filled by the even-odd rule.
//!
//! A hand-written reader, not a DXF library: what the model means is what
//! this reader makes of the group codes, quirks included (a library reads
//! entities OpenSCAD ignores and turns away files OpenSCAD reads).

use std::collections::{BTreeSet, HashMap};

use glam::DVec2;

use super::flat::Region;

/// OpenSCAD's grid for DXF points (its `GRID_COARSE`).
const GRID: f64 = 1.0 / 1024.0;

/// The farthest a point may lie from the origin (lines past it, or not
/// finite, are left out with a warning).
const FARTHEST: f64 = 1e12;

/// How to read a drawing: the node's `layer`, `origin`, `scale`, and the
/// circle fragment count for a radius (the node's `$fn`, `$fa`, `$fs`).
pub(crate) struct DxfOptions<'a> {
    /// The layer drawn; every layer when empty.
    pub layer: &'a str,
    /// Subtracted from every entity point.
    pub origin: DVec2,
    /// Multiplies every entity point after `origin` is subtracted.
    pub scale: f64,
    /// Straight pieces round a full circle of a radius.
    pub fragments: &'a dyn Fn(f64) -> usize,
    /// The most straight lines read; reading stops past it.
    pub max_lines: usize,
}

/// What a DXF file draws.
#[derive(Debug, Default)]
pub(crate) struct DxfDrawing {
    /// The filled paths.
    pub region: Region,
    /// Straight lines made, the drawing's and its blocks' (past
    /// [`DxfOptions::max_lines`], the reading stopped there and the region
    /// is empty).
    pub lines: usize,
    /// Entities not drawn: their name and how many.
    pub unsupported: Vec<(String, usize)>,
    /// Values that could not be read, with their line.
    pub problems: Vec<String>,
}

/// The drawing of DXF `bytes` as OpenSCAD 2021.01 reads it.
#[must_use]
pub(crate) fn dxf_region(bytes: &[u8], options: &DxfOptions) -> DxfDrawing {
    let text = String::from_utf8_lossy(bytes);
    let mut reader = Reader::new(options);
    let mut lines = text.lines();
    let mut number = 0;
    while let Some(code) = lines.next() {
        number += 1;
        let value = lines.next().unwrap_or("").trim();
        number += 1;
        let code = code.trim();
        let Ok(code) = code.parse::<i32>() else {
            if !code.is_empty() {
                reader.problems.push(format!("line {}: `{code}` is no group code; the rest is not read", number - 1));
            }
            break;
        };
        if let Err(e) = reader.pair(code, value) {
            reader.problems.push(format!("line {number}: {e}"));
        }
        if reader.added > options.max_lines {
            return DxfDrawing { lines: reader.added, ..DxfDrawing::default() };
        }
    }
    if reader.far > 0 {
        let (n, noun) = (reader.far, if reader.far == 1 { "line" } else { "lines" });
        reader.problems.push(format!("{n} {noun} beyond {FARTHEST:e} units (or not finite) left out"));
    }
    let paths = reader.grid.paths(&reader.lines);
    let mut unsupported: Vec<(String, usize)> = reader.unsupported.into_iter().collect();
    unsupported.sort();
    DxfDrawing { region: Region::even_odd(&paths), lines: reader.lines.len(), unsupported, problems: reader.problems }
}

/// The entity being read: the values its group codes gave so far.
#[derive(Debug, Default)]
struct Entity {
    /// Its name (group code 0).
    kind: String,
    layer: String,
    /// Group code 2: a section's or block's name, an insert's block.
    name: String,
    /// Group code 70: a polyline's flags.
    flags: i64,
    xs: Vec<f64>,
    ys: Vec<f64>,
    /// Group code 40: a radius, an ellipse's axis ratio.
    g40: f64,
    /// Group codes 41 and 42: an ellipse's start and end, an insert's scale.
    g41: f64,
    g42: f64,
    /// Group codes 50 and 51: an arc's start and end, an insert's turn.
    g50: f64,
    g51: f64,
}

/// The reader's state between group codes.
struct Reader<'a> {
    options: &'a DxfOptions<'a>,
    entity: Entity,
    in_entities: bool,
    in_blocks: bool,
    block: Option<String>,
    grid: Grid,
    /// The drawing's lines, as grid points.
    lines: Vec<[(i64, i64); 2]>,
    /// Each block's lines (block coordinates, snapped).
    blocks: HashMap<String, Vec<[DVec2; 2]>>,
    unsupported: HashMap<String, usize>,
    problems: Vec<String>,
    /// Lines left out for lying past [`FARTHEST`].
    far: usize,
    /// Lines made, into the drawing or into blocks.
    added: usize,
}

impl<'a> Reader<'a> {
    fn new(options: &'a DxfOptions<'a>) -> Self {
        Reader {
            options,
            entity: Entity::default(),
            in_entities: false,
            in_blocks: false,
            block: None,
            grid: Grid::default(),
            lines: Vec::new(),
            blocks: HashMap::new(),
            unsupported: HashMap::new(),
            problems: Vec::new(),
            far: 0,
            added: 0,
        }
    }

    /// Takes one group code and its value.
    fn pair(&mut self, code: i32, value: &str) -> Result<(), String> {
        let number = || value.parse::<f64>().map_err(|_| format!("`{value}` is not a number (group code {code})"));
        let (blocks, origin, scale) = (self.in_blocks, self.options.origin, self.options.scale);
        let place = |v: f64, o: f64| if blocks { v } else { (v - o) * scale };
        let e = &mut self.entity;
        match code {
            0 => {
                let done = std::mem::take(&mut self.entity);
                self.finish(done)?;
                self.entity.kind = value.to_string();
                if value == "INSERT" {
                    (self.entity.g41, self.entity.g42) = (1.0, 1.0);
                }
            }
            2 => e.name = value.to_string(),
            8 => e.layer = value.to_string(),
            10 | 11 => e.xs.push(place(number()?, origin.x)),
            20 | 21 => e.ys.push(place(number()?, origin.y)),
            40 => e.g40 = number()? * if blocks { 1.0 } else { scale },
            41 => e.g41 = number()?,
            42 => e.g42 = number()?,
            50 => e.g50 = number()?,
            51 => e.g51 = number()?,
            70 => {
                e.flags =
                    value.parse::<i64>().map_err(|_| format!("`{value}` is not a whole number (group code 70)"))?
            }
            _ => {}
        }
        Ok(())
    }

    /// Turns the entity just read into lines (or a section or block mark).
    fn finish(&mut self, e: Entity) -> Result<(), String> {
        let short = || format!("a {} without enough points is left out", e.kind);
        let at = |i: usize| -> Result<DVec2, String> {
            Ok(DVec2::new(*e.xs.get(i).ok_or_else(short)?, *e.ys.get(i).ok_or_else(short)?))
        };
        match e.kind.as_str() {
            "SECTION" => {
                self.in_entities = e.name == "ENTITIES";
                self.in_blocks = e.name == "BLOCKS";
            }
            "BLOCK" => self.block = Some(e.name.clone()),
            "ENDBLK" => self.block = None,
            "ENDSEC" => {}
            "LINE" => {
                let (a, b) = (at(0)?, at(1)?);
                self.add(&e, a, b);
            }
            "LWPOLYLINE" => {
                let n = e.xs.len().max(e.ys.len());
                let points = (0..n).map(at).collect::<Result<Vec<_>, _>>()?;
                for w in points.windows(2) {
                    self.add(&e, w[0], w[1]);
                }
                if e.flags & 1 == 1 && n > 0 {
                    self.add(&e, points[n - 1], points[0]);
                }
            }
            "CIRCLE" => {
                let (centre, r) = (at(0)?, e.g40);
                let n = self.pieces((self.options.fragments)(r), 1.0);
                let on = |i: usize| centre + r * unit(360.0 * i as f64 / n as f64);
                for i in 0..n {
                    self.add(&e, on(i), on(i + 1));
                }
            }
            "ARC" => {
                let (centre, r) = (at(0)?, e.g40);
                let sweep = sweep(e.g50, e.g51, 360.0)
                    .ok_or_else(|| format!("an ARC from {}° to {}° is left out", e.g50, e.g51))?;
                let n = self.pieces((self.options.fragments)(r), sweep / 360.0);
                let on = |i: usize| centre + r * unit(e.g50 + sweep * i as f64 / n as f64);
                for i in 0..n {
                    self.add(&e, on(i), on(i + 1));
                }
            }
            "ELLIPSE" => self.ellipse(&e, at(0)?, at(1)?)?,
            "INSERT" => {
                let place = at(0)?;
                let turn = e.g50;
                let lines = self.blocks.get(&e.name).cloned().unwrap_or_default();
                let scale = if self.in_blocks { 1.0 } else { self.options.scale };
                let map = |p: DVec2| {
                    let q = p * DVec2::new(e.g41, e.g42);
                    place + rotate(q, turn) * scale
                };
                for [a, b] in lines {
                    self.add(&e, map(a), map(b));
                }
            }
            // What OpenSCAD reads for its `dxf_dim()`, which draws nothing.
            "DIMENSION" => {}
            "" => {}
            _ if self.in_blocks || (self.in_entities && self.on_layer(&e)) => {
                *self.unsupported.entry(e.kind.clone()).or_default() += 1;
            }
            _ => {}
        }
        Ok(())
    }

    /// An `ELLIPSE`: centre, major axis end (from the centre), axis ratio,
    /// start and end parameters in radians.
    fn ellipse(&mut self, e: &Entity, centre: DVec2, major: DVec2) -> Result<(), String> {
        let sweep = sweep(e.g41, e.g42, std::f64::consts::TAU)
            .ok_or_else(|| format!("an ELLIPSE from {} to {} is left out", e.g41, e.g42))?;
        let r_major = major.length();
        let turn = {
            let a = (major.x / r_major).clamp(-1.0, 1.0).acos().to_degrees();
            if major.y < 0.0 {
                360.0 - a
            } else {
                a
            }
        };
        let r_minor = r_major * e.g40;
        let n = self.pieces((self.options.fragments)(r_major), sweep / std::f64::consts::TAU);
        let on = |i: usize| {
            let t = e.g41 + sweep * i as f64 / n as f64;
            centre + rotate(DVec2::new(t.cos() * r_major, t.sin() * r_minor), turn)
        };
        for i in 1..=n {
            self.add(e, on(i - 1), on(i));
        }
        Ok(())
    }

    /// Straight pieces for `share` of a full turn of `full` pieces; none
    /// (but counted) when they would pass the line limit.
    fn pieces(&mut self, full: usize, share: f64) -> usize {
        let n = (full as f64 * share).ceil().clamp(0.0, 1e15) as usize;
        if self.added.saturating_add(n) > self.options.max_lines {
            self.added = self.added.saturating_add(n);
            return 0;
        }
        n
    }

    fn on_layer(&self, e: &Entity) -> bool {
        self.options.layer.is_empty() || self.options.layer == e.layer
    }

    /// One straight line of entity `e`: into the drawing (on its layer, in
    /// the entities section), or into the block being read.
    fn add(&mut self, e: &Entity, a: DVec2, b: DVec2) {
        self.added += 1;
        if self.added > self.options.max_lines {
            return;
        }
        if !(a.is_finite() && b.is_finite()) || a.abs().max(b.abs()).max_element() > FARTHEST {
            self.far += 1;
            return;
        }
        if self.in_entities && self.on_layer(e) {
            let (a, b) = (self.grid.snap(a), self.grid.snap(b));
            self.grid.note(a, self.lines.len());
            self.grid.note(b, self.lines.len());
            self.lines.push([a, b]);
        } else if self.in_blocks {
            let (a, b) = (self.grid.snap(a), self.grid.snap(b));
            if let Some(block) = &self.block {
                self.blocks.entry(block.clone()).or_default().push([a, b].map(Grid::point));
            }
        }
    }
}

/// How far an arc runs from `start` to `stop`, OpenSCAD's way: `stop`
/// moved on by whole turns until it is not below `start`. `None` when
/// either is not finite.
fn sweep(start: f64, stop: f64, turn: f64) -> Option<f64> {
    if !(start.is_finite() && stop.is_finite()) {
        return None;
    }
    let mut stop = stop;
    if start > stop {
        stop += turn * ((start - stop) / turn).ceil();
        if start > stop {
            stop += turn;
        }
    }
    Some(stop - start)
}

/// The unit vector at `degrees`.
fn unit(degrees: f64) -> DVec2 {
    let (s, c) = degrees.to_radians().sin_cos();
    DVec2::new(c, s)
}

/// Whether OpenSCAD reverses a closed path (its `fixup_path_direction`):
/// at the first point of least x, by the angles (x before y, as OpenSCAD
/// writes them) of the lines to its neighbours.
fn turned_back(path: &[DVec2]) -> bool {
    let n = path.len();
    if n < 3 {
        return false;
    }
    let b = (1..n).fold(0, |best, j| if path[j].x < path[best].x { j } else { best });
    let a = if b == 0 { n - 2 } else { b - 1 };
    let c = if b == n - 1 { 1 } else { b + 1 };
    let (ba, bc) = (path[a] - path[b], path[c] - path[b]);
    ba.x.atan2(ba.y) < bc.x.atan2(bc.y)
}

/// `p` turned by `degrees` about the origin.
fn rotate(p: DVec2, degrees: f64) -> DVec2 {
    unit(degrees).rotate(p)
}

/// Grid points in use and the drawing's lines at each.
#[derive(Debug, Default)]
struct Grid {
    cells: HashMap<(i64, i64), Vec<usize>>,
}

impl Grid {
    /// `p` on the grid: its nearest grid point, or the closest used
    /// neighbour of that point when it is not used itself.
    fn snap(&mut self, p: DVec2) -> (i64, i64) {
        let (ix, iy) = ((p.x / GRID).round() as i64, (p.y / GRID).round() as i64);
        if self.cells.contains_key(&(ix, iy)) {
            return (ix, iy);
        }
        let mut best = ((ix, iy), 10);
        for jx in ix - 1..=ix + 1 {
            for jy in iy - 1..=iy + 1 {
                let d = (ix - jx).abs() + (iy - jy).abs();
                if d < best.1 && self.cells.contains_key(&(jx, jy)) {
                    best = ((jx, jy), d);
                }
            }
        }
        self.cells.entry(best.0).or_default();
        best.0
    }

    fn point((x, y): (i64, i64)) -> DVec2 {
        DVec2::new(x as f64 * GRID, y as f64 * GRID)
    }

    fn note(&mut self, at: (i64, i64), line: usize) {
        self.cells.entry(at).or_default().push(line);
    }

    /// The lines joined into paths, OpenSCAD's way: first every open path
    /// (from the first line with an end no other line meets), then the
    /// closed ones (from the first line left); at each point the first
    /// line left that meets it goes on.
    fn paths(&self, lines: &[[(i64, i64); 2]]) -> Vec<Vec<DVec2>> {
        let mut enabled = vec![true; lines.len()];
        let loose = |enabled: &[bool], line: usize, end: usize| {
            self.cells[&lines[line][end]].iter().all(|&k| k == line || !enabled[k])
        };
        let mut open: BTreeSet<usize> =
            (0..lines.len()).filter(|&l| loose(&enabled, l, 0) || loose(&enabled, l, 1)).collect();
        let mut paths = Vec::new();
        while let Some(&line) = open.first() {
            let end = usize::from(!loose(&enabled, line, 0));
            let (path, touched) = self.walk(lines, &mut enabled, line, end);
            paths.push(path);
            for cell in touched {
                for &k in &self.cells[&cell] {
                    if !enabled[k] {
                        open.remove(&k);
                    } else if loose(&enabled, k, 0) || loose(&enabled, k, 1) {
                        open.insert(k);
                    }
                }
            }
        }
        let any_open = !paths.is_empty();
        let mut next = 0;
        while let Some(line) = (next..lines.len()).find(|&l| enabled[l]) {
            next = line;
            let (mut path, _) = self.walk(lines, &mut enabled, line, 0);
            // OpenSCAD turns closed paths one way round, but only when no
            // path is open; then leaves out a closed path's first point (its
            // last repeats it, unless the walk ended where three lines met).
            if !any_open && turned_back(&path) {
                path.reverse();
            }
            path.remove(0);
            paths.push(path);
        }
        paths
    }

    /// Follows lines from `line`'s end `end`, disabling each; the path's
    /// points and the grid points it passed.
    fn walk(
        &self,
        lines: &[[(i64, i64); 2]],
        enabled: &mut [bool],
        mut line: usize,
        mut end: usize,
    ) -> (Vec<DVec2>, Vec<(i64, i64)>) {
        let mut cells = vec![lines[line][end]];
        loop {
            let at = lines[line][1 - end];
            cells.push(at);
            enabled[line] = false;
            let Some(k) = self.cells[&at].iter().copied().find(|&k| enabled[k]) else { break };
            (line, end) = (k, usize::from(lines[k][0] != at));
        }
        (cells.iter().copied().map(Grid::point).collect(), cells)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn read(text: &str, layer: &str) -> DxfDrawing {
        let fragments = |r: f64| super::super::args::fragment_count([0.0, 12.0, 2.0], r) as usize;
        let options = DxfOptions { layer, origin: DVec2::ZERO, scale: 1.0, fragments: &fragments, max_lines: 100_000 };
        dxf_region(text.as_bytes(), &options)
    }

    /// A DXF file of `entities` (each a list of group codes and values).
    fn dxf(entities: &[&[(i32, &str)]]) -> String {
        let mut s = String::from("0\nSECTION\n2\nENTITIES\n");
        for e in entities {
            for (code, value) in *e {
                s += &format!("{code}\n{value}\n");
            }
        }
        s + "0\nENDSEC\n0\nEOF\n"
    }

    #[test]
    fn lines_join_into_filled_paths_and_open_ones_are_closed() {
        // A 10 × 10 square of four LINEs drawn in any order and direction,
        // on layer A, and a triangle's two sides on layer B (open: closed
        // by its third side).
        let line = |x1: &'static str, y1: &'static str, x2: &'static str, y2: &'static str, layer: &'static str| {
            vec![(0, "LINE"), (8, layer), (10, x1), (20, y1), (11, x2), (21, y2)]
        };
        let entities = [
            line("0", "0", "10", "0", "A"),
            line("10", "10", "10", "0", "A"),
            line("0", "10", "0", "0", "A"),
            line("10", "10", "0", "10", "A"),
            line("20", "0", "30", "0", "B"),
            line("30", "0", "30", "10", "B"),
        ];
        let refs: Vec<&[(i32, &str)]> = entities.iter().map(Vec::as_slice).collect();
        let text = dxf(&refs);
        assert!((read(&text, "").region.area() - 150.0).abs() < 1e-9);
        assert!((read(&text, "A").region.area() - 100.0).abs() < 1e-9);
        assert!((read(&text, "B").region.area() - 50.0).abs() < 1e-9);
        assert!(read(&text, "C").region.is_empty());
    }

    #[test]
    fn polylines_circles_arcs_and_ellipses_take_openscads_fragments() {
        // A closed LWPOLYLINE square with a CIRCLE hole (r = 2: 7 fragments).
        let text = dxf(&[
            &[
                (0, "LWPOLYLINE"),
                (70, "1"),
                (10, "0"),
                (20, "0"),
                (10, "10"),
                (20, "0"),
                (10, "10"),
                (20, "10"),
                (10, "0"),
                (20, "10"),
            ],
            &[(0, "CIRCLE"), (10, "5"), (20, "5"), (40, "2")],
        ]);
        let heptagon = 0.5 * 7.0 * 4.0 * (std::f64::consts::TAU / 7.0).sin();
        let got = read(&text, "");
        assert!((got.region.area() - (100.0 - heptagon)).abs() < 1e-3, "{}", got.region.area());
        // A half disc: an ARC from 0° to 180° (r = 10: 30 fragments, 15 of
        // them), closed by its diameter.
        let arc = read(&dxf(&[&[(0, "ARC"), (10, "0"), (20, "0"), (40, "10"), (50, "0"), (51, "180")]]), "");
        let half = 0.5 * 15.0 * 100.0 * (std::f64::consts::TAU / 30.0).sin();
        assert!((arc.region.area() - half).abs() < 1e-2, "{}", arc.region.area());
        // A full ellipse, major axis 10 along y, ratio 0.5: the polygon's
        // area is close to the ellipse's.
        let ellipse = read(
            &dxf(&[&[
                (0, "ELLIPSE"),
                (10, "0"),
                (20, "0"),
                (11, "0"),
                (21, "10"),
                (40, "0.5"),
                (41, "0"),
                (42, "6.283185307179586"),
            ]]),
            "",
        );
        let (lo, hi) = ellipse.region.bounds().unwrap();
        assert!((hi.y - 10.0).abs() < 1e-2 && (lo.x + 5.0).abs() < 0.05, "{lo} {hi}");
        assert!((ellipse.region.area() / (std::f64::consts::PI * 50.0) - 1.0).abs() < 0.01);
    }

    #[test]
    fn blocks_are_inserted_moved_scaled_and_turned_and_unknown_entities_counted() {
        let text = "0\nSECTION\n2\nBLOCKS\n0\nBLOCK\n2\nSQ\n\
            0\nLWPOLYLINE\n70\n1\n10\n0\n20\n0\n10\n1\n20\n0\n10\n1\n20\n1\n10\n0\n20\n1\n\
            0\nENDBLK\n0\nENDSEC\n\
            0\nSECTION\n2\nENTITIES\n\
            0\nINSERT\n2\nSQ\n10\n100\n20\n0\n41\n4\n42\n2\n50\n90\n\
            0\nSPLINE\n10\n0\n20\n0\n0\nSPLINE\n0\nTEXT\n1\nhello\n\
            0\nENDSEC\n0\nEOF\n";
        let got = read(text, "");
        // The unit square scaled to 4 × 2, turned a quarter: x from 98 to 100.
        let (lo, hi) = got.region.bounds().unwrap();
        assert!((lo - DVec2::new(98.0, 0.0)).length() < 1e-9 && (hi - DVec2::new(100.0, 4.0)).length() < 1e-9);
        assert_eq!(got.unsupported, vec![("SPLINE".to_string(), 2), ("TEXT".to_string(), 1)]);
        // A bad number is named with its line; reading goes on.
        let bad = read("0\nSECTION\n2\nENTITIES\n0\nLINE\n10\nx\n", "");
        assert!(bad.problems[0].starts_with("line 8:"), "{:?}", bad.problems);
    }

    #[test]
    fn a_real_layout_fills_as_openscad_fills_it() {
        // The construct model's drawing: areas and bounds of OpenSCAD
        // 2021.01's own outlines of it (its SVG export), one layer as it is,
        // and every layer moved by `origin`, halved, with $fn = 12.
        let bytes =
            std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/openscad/parts/gasket.dxf")).unwrap();
        let cases = [
            ("outline", DVec2::ZERO, 1.0, 0.0, 2133.551, [0.0, 0.0, 60.0, 40.0]),
            ("", DVec2::new(30.0, 20.0), 0.5, 12.0, 461.453, [-15.0, -10.0, 25.0, 10.0]),
        ];
        for (layer, origin, scale, fine, area, [x0, y0, x1, y1]) in cases {
            let fragments = |r: f64| super::super::args::fragment_count([fine, 12.0, 2.0], r) as usize;
            let options = DxfOptions { layer, origin, scale, fragments: &fragments, max_lines: 100_000 };
            let got = dxf_region(&bytes, &options).region;
            let (lo, hi) = got.bounds().unwrap();
            assert!((got.area() - area).abs() < 2e-3, "{layer}: {}", got.area());
            assert!(
                (lo - DVec2::new(x0, y0)).length() < 1e-9 && (hi - DVec2::new(x1, y1)).length() < 1e-9,
                "{lo} {hi}"
            );
        }
        // Past the line limit: nothing drawn, the count said.
        let few = |_: f64| 30;
        let options = DxfOptions { layer: "", origin: DVec2::ZERO, scale: 1.0, fragments: &few, max_lines: 10 };
        let stopped = dxf_region(&bytes, &options);
        assert!(stopped.lines > 10 && stopped.region.is_empty());
    }

    #[test]
    fn lines_meeting_three_at_a_point_fill_as_openscads_walk_leaves_them() {
        // Eleven lines of a meshed outline (OpenSCAD's `polygon-mesh.dxf`
        // test drawing): one closed walk that ends where it did not start,
        // turned round and cut short as OpenSCAD does; 8495.69 is the area
        // of OpenSCAD 2021.01's outline of it.
        let ends = [
            [50, 140, 0, 140],
            [140, 0, 0, 0],
            [0, 0, 0, 140],
            [50, 140, 0, 0],
            [50, 140, 45, 100],
            [45, 100, 60, 80],
            [0, 0, 45, 100],
            [45, 50, 140, 0],
            [60, 80, 45, 50],
            [45, 50, 0, 0],
            [45, 100, 45, 50],
        ];
        let mut text = String::from("0\nSECTION\n2\nENTITIES\n");
        for [x1, y1, x2, y2] in ends {
            text += &format!("0\nLINE\n8\n0\n10\n{x1}\n20\n{y1}\n11\n{x2}\n21\n{y2}\n");
        }
        text += "0\nENDSEC\n0\nEOF\n";
        let area = read(&text, "").region.area();
        assert!((area - 8495.69).abs() < 0.01, "{area}");
    }
}
