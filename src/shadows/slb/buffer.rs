//! The light pass's buffers of seed 000 (§3.2, Table 1): the edge buffer (one
//! bit per texel: a silhouette crosses it) and the silhouette-line buffer, built
//! from the casters' triangles as the light sees them (a CSG solid's are
//! those of its outline band, [`super::solid`], with its [`SolidCoverage`]
//! over the centres the band does not reach).
//!
//! Every edge of every triangle is walked ([`super::walk`]) and recorded in the
//! texels it crosses; then, per texel (§3.3.2), a record of one object that
//! matches another in every field but the Polygon ID and an opposite L/R flag is
//! an edge shared by two of its polygons and both go; and (§3.3.3) lines behind
//! a polygon that covers the whole texel nearer the light go, the texel's edge
//! bit with them when none is left.
//!
//! Store: a sorted compact form rather than the paper's hashed linked lists.
//! The records are sorted by texel (in parallel), so one texel's lines are
//! adjacent, grouped by object; a texel finds them through the edge bits and
//! a running count of set bits per 64 texels (a rank: one popcount), with no
//! hashing, no collisions and no pointers — 1.5 bits per texel plus 4 bytes
//! per edge texel on top of the lines.
//!
//! Beyond the paper, the eye pass counts crossings from the texel's centre
//! ([`super::region`]), so each edge texel also keeps the surfaces that cover
//! its centre (their depth planes): the *layers*, every caster triangle over
//! the centre by exact integer tests on the walk's grid, plus a correction
//! wherever a line's k-bit form puts the centre on the other side of it than
//! the exact edge does.

use rayon::prelude::*;

use super::light::LightTriangle;
use super::line::{Facing, Layer, SilhouetteLine, TexelDepth};
use super::solid::SolidCoverage;
use super::walk::{Edge, WalkPoint, WALK_BITS};

/// What one edge texel holds.
#[derive(Debug, Clone, Copy)]
pub struct Entry<'a> {
    /// Its silhouette lines, grouped by object.
    pub lines: &'a [SilhouetteLine],
    /// The surfaces over its centre.
    pub layers: &'a [Layer],
}

/// Counts from one build, for the paper's Table 8 and the benchmarks.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct BuildStats {
    /// Records the walk made (of the edges not found shared beforehand).
    pub walked: usize,
    /// Edges (unwalked) and records removed as shared.
    pub shared: usize,
    /// Records removed as hidden.
    pub hidden: usize,
}

/// The edge buffer and the silhouette-line buffer of one light view.
#[derive(Debug, Clone, Default)]
pub struct SilhouetteLineBuffer {
    width: u32,
    height: u32,
    bits: u32,
    edge: Vec<u64>,
    rank: Vec<u32>,
    line_start: Vec<u32>,
    lines: Vec<SilhouetteLine>,
    layer_start: Vec<u32>,
    layers: Vec<Layer>,
    stats: BuildStats,
}

/// A line being built, with where it lies and what the exact edge says of
/// the texel's centre.
#[derive(Debug, Clone, Copy)]
struct Record {
    texel: u32,
    line: SilhouetteLine,
    /// The exact edge has the centre on the polygon's side.
    exact_centre_inside: bool,
    /// The vertices at the line's start and end, where they lie in the texel.
    ends: [Option<WalkPoint>; 2],
}

impl Record {
    /// Everything the paper compares for shared edges (all but the Polygon
    /// ID and the L/R flag), texel first.
    fn key(&self) -> (u32, u32, u8, u32, u32, u32, u32) {
        let l = &self.line;
        let kind = (l.line.major as u8) << 2 | u8::from(l.line.x_positive) << 1 | u8::from(l.cross);
        let end = |e: Option<f32>| e.map_or(u32::MAX, f32::to_bits);
        (self.texel, l.object, kind, l.fraction, l.slope, end(l.start), end(l.end))
    }
}

/// `sign(a × b)` for walk-grid vectors, exactly.
fn cross(a: (i64, i64), b: (i64, i64)) -> i128 {
    i128::from(a.0) * i128::from(b.1) - i128::from(a.1) * i128::from(b.0)
}

/// Which side of the directed line `p → q` the point `c + (ε, ε²)` lies on
/// (simulation of simplicity: never on it), as ±1.
fn side(p: WalkPoint, q: WalkPoint, c: (i64, i64)) -> i32 {
    let d = (q.x - p.x, q.y - p.y);
    let s = cross(d, (c.0 - p.x, c.1 - p.y));
    let s = if s != 0 {
        s
    } else if d.1 != 0 {
        -i128::from(d.1)
    } else {
        i128::from(d.0)
    };
    if s > 0 {
        1
    } else {
        -1
    }
}

/// The centre of texel `(x, y)` in walk units.
fn centre(x: i64, y: i64) -> (i64, i64) {
    let half = 1i64 << (WALK_BITS - 1);
    ((x << WALK_BITS) + half, (y << WALK_BITS) + half)
}

/// A triangle snapped to the walk grid, with its depth plane.
struct Snapped {
    p: [WalkPoint; 3],
    /// +1 or −1: the orientation of `p`.
    turn: i32,
    /// z = c + dx·x + dy·y in texel coordinates.
    plane: (f64, f64, f64),
    object: u32,
    polygon: u32,
    open: u8,
    facing: Facing,
}

impl Snapped {
    fn new(t: &LightTriangle) -> Option<Snapped> {
        let p = t.points.map(|v| WalkPoint::snap(v.x, v.y));
        let area = cross((p[1].x - p[0].x, p[1].y - p[0].y), (p[2].x - p[0].x, p[2].y - p[0].y));
        if area == 0 || !t.points.iter().all(|v| v.is_finite()) {
            return None;
        }
        let [a, b, c] = t.points;
        let det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
        let dx = ((b.z - a.z) * (c.y - a.y) - (c.z - a.z) * (b.y - a.y)) / det;
        let dy = ((c.z - a.z) * (b.x - a.x) - (b.z - a.z) * (c.x - a.x)) / det;
        let plane = (a.z - dx * a.x - dy * a.y, dx, dy);
        let turn = if area > 0 { 1 } else { -1 };
        Some(Snapped { p, turn, plane, object: t.object, polygon: t.polygon, open: t.open, facing: t.facing })
    }

    fn depth(&self, x: i64, y: i64) -> TexelDepth {
        let (c, dx, dy) = self.plane;
        TexelDepth { c: (c + dx * x as f64 + dy * y as f64) as f32, dx: dx as f32, dy: dy as f32 }
    }

    /// Whether the centre of texel `(x, y)` (perturbed) lies inside.
    fn covers_centre(&self, x: i64, y: i64) -> bool {
        let c = centre(x, y);
        (0..3).all(|i| side(self.p[i], self.p[(i + 1) % 3], c) == self.turn)
    }

    /// Whether the whole of texel `(x, y)` lies inside: its four corners do
    /// (perturbed as the centre is).
    fn covers_texel(&self, x: i64, y: i64) -> bool {
        let unit = 1i64 << WALK_BITS;
        let corners =
            [(0, 0), (unit, 0), (0, unit), (unit, unit)].map(|(dx, dy)| ((x << WALK_BITS) + dx, (y << WALK_BITS) + dy));
        corners.iter().all(|&c| (0..3).all(|i| side(self.p[i], self.p[(i + 1) % 3], c) == self.turn))
    }

    /// The bounding box in texels, inside a `width` × `height` map.
    fn bounds(&self, width: u32, height: u32) -> Option<(i64, i64, i64, i64)> {
        let lo = |f: fn(&WalkPoint) -> i64| self.p.iter().map(f).min().unwrap_or(0) >> WALK_BITS;
        let hi = |f: fn(&WalkPoint) -> i64| self.p.iter().map(f).max().unwrap_or(0) >> WALK_BITS;
        let (x0, y0) = (lo(|p| p.x).max(0), lo(|p| p.y).max(0));
        let (x1, y1) = (hi(|p| p.x).min(i64::from(width) - 1), hi(|p| p.y).min(i64::from(height) - 1));
        (x0 <= x1 && y0 <= y1).then_some((x0, y0, x1, y1))
    }
}

/// `p → q` clipped to the rectangle `[lo, hi]²`-ish (`x ∈ [x0, x1]`,
/// `y ∈ [y0, y1]`), parametrically; `None` when it misses.
fn clip(p: (f64, f64), q: (f64, f64), x: (f64, f64), y: (f64, f64)) -> Option<((f64, f64), (f64, f64))> {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    let d = (q.0 - p.0, q.1 - p.1);
    for (o, dd, (lo, hi)) in [(p.0, d.0, x), (p.1, d.1, y)] {
        if dd == 0.0 {
            if o < lo || o > hi {
                return None;
            }
            continue;
        }
        let (a, b) = ((lo - o) / dd, (hi - o) / dd);
        let (a, b) = if a < b { (a, b) } else { (b, a) };
        (t0, t1) = (t0.max(a), t1.min(b));
    }
    if t0 > t1 {
        return None;
    }
    let at = |t: f64| {
        if t == 0.0 {
            p
        } else if t == 1.0 {
            q
        } else {
            (p.0 + d.0 * t, p.1 + d.1 * t)
        }
    };
    Some((at(t0), at(t1)))
}

impl SilhouetteLineBuffer {
    /// Builds the buffers of a `width` × `height` light view of `triangles`,
    /// Fraction and Slope in `bits` bits (4 ..= 16), with `solids` over the
    /// centres their triangles do not hold.
    #[must_use]
    pub fn build(
        width: u32,
        height: u32,
        bits: u32,
        triangles: &[LightTriangle],
        solids: &[SolidCoverage],
    ) -> SilhouetteLineBuffer {
        let snapped: Vec<Snapped> = triangles.par_iter().filter_map(Snapped::new).collect();
        let edges = silhouette_edges(&snapped);
        let mut records: Vec<Record> = edges
            .par_iter()
            .fold(Vec::new, |mut out, &(t, i)| {
                walk_edge(&snapped[t], i, width, height, bits, &mut out);
                out
            })
            .flatten()
            .collect();
        let walked = records.len();
        records.par_sort_unstable_by_key(Record::key);
        let records = remove_shared(records);
        let shared = 3 * snapped.len() - edges.len() + walked - records.len();
        let mut buffer = SilhouetteLineBuffer {
            width,
            height,
            bits,
            stats: BuildStats { walked, shared, hidden: 0 },
            ..SilhouetteLineBuffer::default()
        };
        buffer.set_edges(records.iter().map(|r| r.texel));
        let layers = buffer.centre_layers(&snapped, solids);
        buffer.finish(records, layers);
        buffer
    }

    /// Sets the edge bits of `texels` (sorted) and the rank over them.
    fn set_edges(&mut self, texels: impl Iterator<Item = u32>) {
        let n = self.width as usize * self.height as usize;
        self.edge = vec![0; n.div_ceil(64)];
        for t in texels {
            self.edge[t as usize / 64] |= 1 << (t % 64);
        }
        self.rank = ranks(&self.edge);
    }

    /// Every triangle over the centre of every edge texel, and every solid
    /// there that no triangle stands for: (texel, layer, whether the
    /// triangle covers the texel whole).
    fn centre_layers(&self, snapped: &[Snapped], solids: &[SolidCoverage]) -> Vec<(u32, Layer, bool)> {
        let w = self.width as i64;
        let mut layers: Vec<(u32, Layer, bool)> = snapped
            .par_iter()
            .fold(Vec::new, |mut out, t| {
                let Some((x0, y0, x1, y1)) = t.bounds(self.width, self.height) else { return out };
                for y in y0..=y1 {
                    let (first, last) = (y * w + x0, y * w + x1);
                    let mut k = first;
                    while k <= last {
                        let word = self.edge[k as usize / 64] >> (k % 64);
                        if word == 0 {
                            k += 64 - k % 64;
                            continue;
                        }
                        k += i64::from(word.trailing_zeros());
                        if k > last {
                            break;
                        }
                        let x = k - y * w;
                        if t.covers_centre(x, y) {
                            let texel = k as u32;
                            let whole = t.covers_texel(x, y);
                            let layer = Layer { depth: t.depth(x, y), count: 1, object: t.object, facing: t.facing };
                            out.push((texel, layer, whole));
                        }
                        k += 1;
                    }
                }
                out
            })
            .flatten()
            .collect();
        if !solids.is_empty() {
            let width = self.width as usize;
            let edge = &self.edge;
            layers.par_extend(edge.par_iter().enumerate().flat_map_iter(|(w, &word)| {
                let bits = (0..64).filter(move |b| word >> b & 1 == 1);
                bits.flat_map(move |b| {
                    let t = w * 64 + b;
                    let (x, y) = (t % width, t / width);
                    solids.iter().filter_map(move |s| s.layer(x, y)).map(move |l| (t as u32, l, false))
                })
            }));
        }
        layers.par_sort_unstable_by_key(|l| l.0);
        layers
    }

    /// Per edge texel: the corrections, hidden-line removal, and the final
    /// compact arrays.
    fn finish(&mut self, records: Vec<Record>, layers: Vec<(u32, Layer, bool)>) {
        let (mut lines, mut kept_layers) = (Vec::with_capacity(records.len()), Vec::new());
        let (mut line_start, mut layer_start, mut texels) = (vec![0u32], vec![0u32], Vec::new());
        let mut hidden = 0;
        let (mut r, mut l) = (0, 0);
        let mut here: Vec<Layer> = Vec::new();
        while r < records.len() {
            let texel = records[r].texel;
            let r_end = r + records[r..].iter().take_while(|x| x.texel == texel).count();
            while l < layers.len() && layers[l].0 < texel {
                l += 1;
            }
            let l_end = l + layers[l..].iter().take_while(|x| x.0 == texel).count();
            here.clear();
            here.extend(layers[l..l_end].iter().map(|x| x.1));
            for rec in &records[r..r_end] {
                if rec.exact_centre_inside != rec.line.centre_inside {
                    let count = if rec.line.centre_inside { 1 } else { -1 };
                    here.push(Layer { depth: rec.line.depth, count, object: rec.line.object, facing: rec.line.facing });
                }
            }
            // §3.3.3: a triangle over the whole texel hides what lies behind it
            // at all four corners.
            let front = layers[l..l_end].iter().filter(|x| x.2).map(|x| x.1.depth).max_by(|a, b| a.c.total_cmp(&b.c));
            let behind = |d: &TexelDepth| {
                front.is_some_and(|f| {
                    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)].iter().all(|&(x, y)| d.at(x, y) < f.at(x, y))
                })
            };
            let before = lines.len();
            let mut mine: Vec<Record> = records[r..r_end].to_vec();
            close_vertices(&mut mine, self.bits, self.width);
            lines.extend(mine.iter().map(|x| x.line).filter(|line| !behind(&line.depth)));
            hidden += (r_end - r) - (lines.len() - before);
            if lines.len() > before {
                kept_layers.extend(here.iter().filter(|x| !behind(&x.depth)));
                texels.push(texel);
                line_start.push(lines.len() as u32);
                layer_start.push(kept_layers.len() as u32);
            }
            (r, l) = (r_end, l_end);
        }
        self.stats.hidden = hidden;
        self.set_edges(texels.into_iter());
        (self.lines, self.layers, self.line_start, self.layer_start) = (lines, kept_layers, line_start, layer_start);
    }

    /// Whether a silhouette crosses texel `(x, y)` (the edge buffer).
    #[inline]
    #[must_use]
    pub fn is_edge(&self, x: u32, y: u32) -> bool {
        let t = (y * self.width + x) as usize;
        self.edge.get(t / 64).is_some_and(|w| w >> (t % 64) & 1 == 1)
    }

    /// The edge buffer: one bit per texel, row by row, 64 to a word.
    #[must_use]
    pub fn edge_words(&self) -> &[u64] {
        &self.edge
    }

    /// Whether a silhouette crosses any texel of columns `x0..=x1` and rows
    /// `y0..=y1` (clipped to the buffer), reading the edge buffer a word at
    /// a time.
    #[must_use]
    pub fn any_edge(&self, (x0, x1): (i64, i64), (y0, y1): (i64, i64)) -> bool {
        let (w, h) = (i64::from(self.width), i64::from(self.height));
        let (x0, x1, y0, y1) = (x0.max(0), x1.min(w - 1), y0.max(0), y1.min(h - 1));
        if x0 > x1 || y0 > y1 {
            return false;
        }
        (y0..=y1).any(|y| {
            let (mut k, last) = ((y * w + x0) as usize, (y * w + x1) as usize);
            while k <= last {
                let take = (64 - k % 64).min(last - k + 1);
                let mask = if take == 64 { u64::MAX } else { (1u64 << take) - 1 };
                if self.edge[k / 64] >> (k % 64) & mask != 0 {
                    return true;
                }
                k += take;
            }
            false
        })
    }

    /// The lines and layers of texel `(x, y)`, if a silhouette crosses it.
    #[inline]
    #[must_use]
    pub fn entry(&self, x: u32, y: u32) -> Option<Entry<'_>> {
        if x >= self.width || y >= self.height {
            return None;
        }
        let i = ranked(&self.edge, &self.rank, (y * self.width + x) as usize)?;
        let (l0, l1) = (self.line_start[i] as usize, self.line_start[i + 1] as usize);
        let (m0, m1) = (self.layer_start[i] as usize, self.layer_start[i + 1] as usize);
        Some(Entry { lines: &self.lines[l0..l1], layers: &self.layers[m0..m1] })
    }

    /// Fraction and Slope bits.
    #[must_use]
    pub fn bits(&self) -> u32 {
        self.bits
    }

    /// Texels a silhouette crosses (the paper's "SL交差グリッド数").
    #[must_use]
    pub fn edge_texels(&self) -> usize {
        self.line_start.len() - 1
    }

    /// Lines stored (the paper's "SL数").
    #[must_use]
    pub fn line_count(&self) -> usize {
        self.lines.len()
    }

    /// What the build walked and removed.
    #[must_use]
    pub fn stats(&self) -> BuildStats {
        self.stats
    }

    /// Bytes held: edge bits, ranks, the lines and the layers.
    #[must_use]
    pub fn memory_bytes(&self) -> usize {
        self.edge.len() * 8
            + self.rank.len() * 4
            + (self.line_start.len() + self.layer_start.len()) * 4
            + self.lines.len() * std::mem::size_of::<SilhouetteLine>()
            + self.layers.len() * std::mem::size_of::<Layer>()
    }
}

/// Per word of a bit set, how many bits are set in the words before it.
#[must_use]
pub(super) fn ranks(words: &[u64]) -> Vec<u32> {
    let mut total = 0u32;
    words
        .iter()
        .map(|w| {
            let r = total;
            total += w.count_ones();
            r
        })
        .collect()
}

/// Bit `t`'s place among the set bits of `words` (whose [`ranks`] are
/// `rank`), if it is set.
#[inline]
#[must_use]
pub(super) fn ranked(words: &[u64], rank: &[u32], t: usize) -> Option<usize> {
    let word = *words.get(t / 64)?;
    if word >> (t % 64) & 1 == 0 {
        return None;
    }
    let below = word & ((1u64 << (t % 64)) - 1);
    Some((rank[t / 64] + below.count_ones()) as usize)
}

/// §3.3.2 once per edge rather than once per texel: the edges of one
/// object's triangles that are not shared by two triangles lying on its
/// opposite sides, as (triangle, edge) pairs. Both triangles of a shared edge
/// walk it between the same two points, so their records would match in
/// every texel but for the Polygon ID and the L/R flag: this finds the same
/// pairs the paper's per-texel comparison finds, without walking them.
fn silhouette_edges(snapped: &[Snapped]) -> Vec<(usize, usize)> {
    // Each triangle edge once, by a 96-bit hash of its object and its ends
    // in walk order (two edges with different ends share one with odds of
    // about 1e-19 a frame), with its L/R flag and whether it is open:
    // 16 bytes an edge, sorted and paired without reading the triangles
    // again (the demo's 92k edges pair in 2 ms; sorted by their exact ends,
    // 15 ms).
    const LEFT: u32 = 1 << 31;
    const OPEN: u32 = 1 << 30;
    // 3 edges a triangle in the low 30 bits: 357M triangles, past any
    // scene's memory (their records alone would take 36 GB).
    debug_assert!(snapped.len() < (OPEN as usize) / 3);
    let keys: Vec<(u64, u32, u32)> = snapped
        .par_iter()
        .enumerate()
        .flat_map_iter(|(t, tri)| {
            (0..3).map(move |i| {
                let (p, q, r) = (tri.p[i], tri.p[(i + 1) % 3], tri.p[(i + 2) % 3]);
                let (p, q) = if Edge::reversed(p, q) { (q, p) } else { (p, q) };
                let (hash, check) = edge_hash(tri.object, p, q);
                let left = if side(p, q, (r.x, r.y)) < 0 { LEFT } else { 0 };
                let open = if tri.open >> i & 1 == 1 { OPEN } else { 0 };
                (hash, check, (t * 3 + i) as u32 | left | open)
            })
        })
        .collect();
    let keys = sort_by_hash(keys);
    let same = |a: &(u64, u32, u32), b: &(u64, u32, u32)| (a.0, a.1) == (b.0, b.1);
    let pair = |piece: &[(u64, u32, u32)]| {
        let mut kept = Vec::new();
        for run in piece.chunk_by(same) {
            match run {
                // An edge of one triangle alone: a silhouette.
                [(_, _, e)] => kept.push(*e),
                // Two triangles' (the usual case): shared when they lie on
                // opposite sides of it.
                [(_, _, a), (_, _, b)] => {
                    if (a ^ b) & LEFT == 0 {
                        kept.extend([*a, *b]);
                    }
                }
                _ => kept.extend(unpaired(run, |_, _| true, |e| e.2 & LEFT != 0).into_iter().map(|e| e.2)),
            }
        }
        kept
    };
    // Paired across the workers, in pieces cut between runs.
    let kept: Vec<u32> = runs_in_pieces(&keys, same, 1 << 14).par_iter().flat_map_iter(|piece| pair(piece)).collect();
    kept.into_iter()
        .filter(|e| e & OPEN == 0)
        .map(|e| {
            let e = (e & !(LEFT | OPEN)) as usize;
            (e / 3, e % 3)
        })
        .collect()
}

/// `sorted` cut into pieces of about `size` items, never inside a run of
/// `same` items.
fn runs_in_pieces<T>(sorted: &[T], same: impl Fn(&T, &T) -> bool, size: usize) -> Vec<&[T]> {
    let mut pieces = Vec::new();
    let mut rest = sorted;
    while !rest.is_empty() {
        let mut end = size.min(rest.len());
        while end < rest.len() && same(&rest[end - 1], &rest[end]) {
            end += 1;
        }
        let (piece, tail) = rest.split_at(end);
        pieces.push(piece);
        rest = tail;
    }
    pieces
}

/// `keys` sorted: split among the workers into 256 parts by the hashes'
/// top byte, each part then sorted on its own ([`sort_part`]), so a
/// scanned model's millions of edges are sorted on every worker rather
/// than by one counting sort while the others wait.
fn sort_by_hash(keys: Vec<(u64, u32, u32)>) -> Vec<(u64, u32, u32)> {
    const PARTS: usize = 256;
    let top = |k: &(u64, u32, u32)| (k.0 >> 56) as usize;
    if keys.len() < 1 << 16 {
        return sort_part(keys, 0);
    }
    let chunk = keys.len().div_ceil(4 * rayon::current_num_threads().max(1));
    let split: Vec<Vec<Vec<(u64, u32, u32)>>> = keys
        .par_chunks(chunk)
        .map(|keys| {
            let mut parts = vec![Vec::new(); PARTS];
            keys.iter().for_each(|k| parts[top(k)].push(*k));
            parts
        })
        .collect();
    let parts: Vec<Vec<(u64, u32, u32)>> = (0..PARTS)
        .into_par_iter()
        .map(|p| sort_part(split.iter().flat_map(|s| s[p].iter().copied()).collect(), 8))
        .collect();
    parts.concat()
}

/// `keys`, whose hashes agree on their top `known` bits, sorted: a counting
/// sort on the next bits (about one bucket per key), then each bucket of
/// more than one on its own — linear where a comparison sort of the demo's
/// 92k edges took 3.5 ms of the light pass.
fn sort_part(keys: Vec<(u64, u32, u32)>, known: u32) -> Vec<(u64, u32, u32)> {
    let bits = (usize::BITS - keys.len().leading_zeros()).clamp(1, 24);
    let shift = 64 - bits;
    let bucket = |k: &(u64, u32, u32)| ((k.0 << known) >> shift) as usize;
    let mut start = vec![0u32; (1 << bits) + 1];
    keys.iter().for_each(|k| start[bucket(k) + 1] += 1);
    for b in 1..start.len() {
        start[b] += start[b - 1];
    }
    let mut sorted = vec![(0, 0, 0); keys.len()];
    for k in keys {
        let at = &mut start[bucket(&k)];
        sorted[*at as usize] = k;
        *at += 1;
    }
    for run in sorted.chunk_by_mut(|a, b| bucket(a) == bucket(b)) {
        if run.len() > 1 {
            run.sort_unstable();
        }
    }
    sorted
}

/// Two independent hashes (64 and 32 bits) of an edge's object and ends:
/// splitmix64's finaliser over each word in turn, from two seeds.
fn edge_hash(object: u32, p: WalkPoint, q: WalkPoint) -> (u64, u32) {
    let mix = |h: u64, v: i64| {
        let mut z = (h ^ v as u64).wrapping_add(0x9e37_79b9_7f4a_7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    };
    let words = [p.x, p.y, q.x, q.y];
    let first = words.into_iter().fold(u64::from(object), mix);
    let second = words.into_iter().fold(u64::from(object) ^ 0x5851_f42d_4c95_7f2d, mix);
    (first, (second >> 32) as u32)
}

/// §3.3.2's pairing over `sorted`, whose runs of `same` items are adjacent:
/// in each run, items of opposite L/R flags (`left`) cancel in pairs and the
/// surplus of the more numerous flag is kept.
fn unpaired<T>(sorted: &[T], same: impl Fn(&T, &T) -> bool, left: impl Fn(&T) -> bool) -> Vec<&T> {
    let left = &left;
    sorted
        .chunk_by(same)
        .flat_map(|run| {
            let lefts = run.iter().filter(|r| left(r)).count();
            let keep_left = 2 * lefts > run.len();
            let surplus = lefts.abs_diff(run.len() - lefts);
            run.iter().filter(move |r| left(r) == keep_left).take(surplus)
        })
        .collect()
}

/// Records of edge `i` of `t` in the texels of a `width` × `height` map it
/// crosses.
fn walk_edge(t: &Snapped, i: usize, width: u32, height: u32, bits: u32, out: &mut Vec<Record>) {
    let unit = (1i64 << WALK_BITS) as f64;
    let (w, h) = (i64::from(width), i64::from(height));
    let (p, q, r) = (t.p[i], t.p[(i + 1) % 3], t.p[(i + 2) % 3]);
    // Walk order, so both triangles of a shared edge clip it alike.
    let (p, q) = if Edge::reversed(p, q) { (q, p) } else { (p, q) };
    let inside = side(p, q, (r.x, r.y));
    let f = |v: WalkPoint| (v.x as f64 / unit, v.y as f64 / unit);
    let Some((a, b)) = clip(f(p), f(q), (-1.0, w as f64 + 1.0), (-1.0, h as f64 + 1.0)) else { return };
    let (a, b) =
        (if a == f(p) { p } else { WalkPoint::snap(a.0, a.1) }, if b == f(q) { q } else { WalkPoint::snap(b.0, b.1) });
    let Some(edge) = Edge::new(a, b) else { return };
    // L/R: the polygon on the +x side of the walk is a left edge; the
    // walk runs towards +y, so +x is the side where p→q × (x step) < 0.
    let left = inside < 0;
    edge.walk(|v| {
        if v.x < 0 || v.y < 0 || i64::from(v.x) >= w || i64::from(v.y) >= h {
            return;
        }
        let mut line = SilhouetteLine::new(&v, edge.line, edge.slope, left, bits);
        (line.polygon, line.object, line.facing) = (t.polygon, t.object, t.facing);
        line.depth = t.depth(i64::from(v.x), i64::from(v.y));
        let c = centre(i64::from(v.x), i64::from(v.y));
        // The exact edge's side of the centre, counted only where the
        // centre lies along the line's part in this texel.
        let (a0, a1) = line.extent();
        let (ca, _) = line.canonical(0.5, 0.5);
        let exact = side(p, q, c) == inside;
        let exact_centre_inside = if (a0..=a1).contains(&ca) { exact } else { line.centre_inside };
        let ends = [v.start.map(|_| a), v.end.map(|_| b)];
        out.push(Record { texel: (v.y as u32) * width + v.x as u32, line, exact_centre_inside, ends });
    });
}

/// Moves the stored ends of lines meeting at one vertex to where their
/// stored (quantised) lines meet, so that no way from the centre slips
/// between them: the records of one texel of a map `width` texels wide. Two
/// lines of nearly one direction (a curved outline's chords) meet far from
/// their vertex once quantised; where the meeting point lies more than
/// 2^(2−k) texel from the vertex, the ends stay where the vertex is.
fn close_vertices(records: &mut [Record], bits: u32, width: u32) {
    let Some(first) = records.first() else { return };
    let (tx, ty) = (f64::from(first.texel % width), f64::from(first.texel / width));
    let reach = 4.0 / f64::from(1u32 << bits);
    let mut vertices: Vec<WalkPoint> = records.iter().flat_map(|r| r.ends).flatten().collect();
    vertices.sort_unstable();
    vertices.dedup();
    for v in vertices {
        let at: Vec<(usize, usize)> = (0..records.len())
            .flat_map(|i| (0..2).map(move |e| (i, e)))
            .filter(|&(i, e)| records[i].ends[e] == Some(v))
            .collect();
        let lines: Vec<&SilhouetteLine> = at.iter().map(|&(i, _)| &records[i].line).collect();
        let Some(meet) = meeting_point(&lines, bits) else { continue };
        let (vx, vy) = v.texels();
        if (f64::from(meet.0) - (vx - tx)).hypot(f64::from(meet.1) - (vy - ty)) > reach {
            continue;
        }
        for (i, e) in at {
            let line = &mut records[i].line;
            let a = line.canonical(meet.0, meet.1).0.clamp(0.0, 1.0);
            if e == 0 {
                line.start = Some(a);
            } else {
                line.end = Some(a);
            }
        }
    }
}

/// Where the first two distinct lines among `lines` cross (texel
/// coordinates), if they are not nearly parallel.
fn meeting_point(lines: &[&SilhouetteLine], bits: u32) -> Option<(f32, f32)> {
    let points = |l: &SilhouetteLine| {
        let p = |a: f32| {
            let (x, y) = l.texel_point(a, l.b_at(a, bits));
            (f64::from(x), f64::from(y))
        };
        (p(0.0), p(1.0))
    };
    let first = lines.first()?;
    let same = |a: &SilhouetteLine, b: &SilhouetteLine| {
        (a.line, a.cross, a.fraction, a.slope) == (b.line, b.cross, b.fraction, b.slope)
    };
    let second = lines.iter().find(|l| !same(first, l))?;
    let ((p0, p1), (q0, q1)) = (points(first), points(second));
    let (d, e) = ((p1.0 - p0.0, p1.1 - p0.1), (q1.0 - q0.0, q1.1 - q0.1));
    let det = d.0 * e.1 - d.1 * e.0;
    if det.abs() < 1e-6 * (d.0.hypot(d.1) * e.0.hypot(e.1)) {
        return None;
    }
    let t = ((q0.0 - p0.0) * e.1 - (q0.1 - p0.1) * e.0) / det;
    let m = (p0.0 + t * d.0, p0.1 + t * d.1);
    // A meeting point far outside the texel means the lines barely differ.
    (m.0.abs() < 2.0 && m.1.abs() < 2.0).then_some((m.0 as f32, m.1 as f32))
}

/// §3.3.2: in each texel, records of one object equal in all but the
/// Polygon ID and with opposite L/R flags are an edge two of its polygons
/// share: they go in pairs. `records` are sorted by [`Record::key`].
fn remove_shared(records: Vec<Record>) -> Vec<Record> {
    unpaired(&records, |a, b| a.key() == b.key(), |r| r.line.left).into_iter().copied().collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The split sort orders keys as a plain sort does, over the parallel
    /// path's size and below it, duplicates and shared top bytes included.
    #[test]
    fn sorting_by_hash_is_a_sort() {
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for n in [0usize, 1, 1000, 200_000] {
            let keys: Vec<(u64, u32, u32)> = (0..n)
                .map(|i| {
                    let h = next();
                    // Every 7th key repeats a hash: the runs the pairing reads.
                    let h = if i % 7 == 0 { h & 0xff00_0000_0000_00ff } else { h };
                    (h, (next() >> 40) as u32 & 3, i as u32)
                })
                .collect();
            let mut want = keys.clone();
            want.sort_unstable();
            assert_eq!(sort_by_hash(keys), want, "{n} keys");
        }
    }
}
