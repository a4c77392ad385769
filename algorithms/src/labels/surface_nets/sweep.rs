//! The sweep of multi-label surface nets: cell layers in slabs on rayon, each cell's pieces
//! (from a cache of the patterns met) as vertices, each differing lattice edge as a quad, the
//! slabs joined in order into the net the parent module smooths and triangulates.

use super::super::blocks::LabelBlock;
use super::super::cell::{edge_index, EDGES, FACES, NONE};
use super::super::Label;
use super::pieces::{PieceCache, VertexPlace};
use super::split::walls_of_face;
use super::Net;
use glam::Vec3;
use rayon::prelude::*;

/// The unsmoothed net of `block`'s computed cells (its owned cells and apron; `all` the map's
/// cells per axis, padded), and the number of owned surface cells.
pub(super) fn net<T: Label>(block: &LabelBlock<'_, T>, all: &[std::ops::Range<usize>; 3], needs: Needs) -> (Net, usize) {
    let computed: [std::ops::Range<usize>; 3] = std::array::from_fn(|a| block.computed(a, &all[a]));
    // The local frame starts one sample before the first computed cell (or at the padding).
    let origin = computed.clone().map(|r| r.start.saturating_sub(1));
    let width = |a: usize| (computed[a].end + 1).min(block.map_dims[a] + 1) + 1 - origin[a];
    let window = Window { block, origin, p: [width(0), width(1)] };
    let local = |r: &std::ops::Range<usize>, a: usize| (r.start - origin[a])..(r.end - origin[a]);
    let frame = Frame {
        lo: std::array::from_fn(|a| computed[a].start - origin[a]),
        hi: std::array::from_fn(|a| computed[a].end - origin[a]),
        all: std::array::from_fn(|a| (all[a].start as isize - origin[a] as isize, all[a].end as isize - origin[a] as isize)),
        owned: std::array::from_fn(|a| local(&block.cells[a].clone(), a)),
        origin,
    };
    // Slabs of cell layers in parallel (one per thread, at least SLAB_LAYERS layers each), each
    // numbering its own vertices and naming those of the layer below it by their place in that
    // layer; joined in order, the net is the one a single sweep makes.
    let (lo, hi) = (frame.lo[2], frame.hi[2]);
    let layers = hi.saturating_sub(lo);
    let slabs = rayon::current_num_threads().min(layers / SLAB_LAYERS).max(1);
    let bounds: Vec<usize> = (0..=slabs).map(|k| lo + layers * k / slabs).collect();
    let parts: Vec<Slab> = (0..slabs).into_par_iter().map(|k| sweep(&window, &frame, bounds[k]..bounds[k + 1], needs)).collect();
    let (mut net, active_cells) = join(parts);
    net.cell_box = computed.map(|r| r.start as u32..r.end as u32);
    (net, active_cells)
}

/// The samples one sweep reads, in a local frame: local padded sample `s` is padded sample
/// `s + origin` of the map (background outside the map).
struct Window<'b, 'a, T> {
    block: &'b LabelBlock<'a, T>,
    /// The map's padded sample at local `0`.
    origin: [usize; 3],
    /// Local samples per layer row and column.
    p: [usize; 2],
}

impl<T: Label> Window<'_, '_, T> {
    /// Local sample layer `pz` into `layer`: background outside the map (and for the layers
    /// below and above the window, which only the ring rule's neighbour lookups read).
    fn fill_layer(&self, pz: isize, layer: &mut Vec<T>) {
        let [px, py] = self.p;
        layer.clear();
        layer.resize(px * py, T::default());
        let b = self.block;
        let gz = pz + self.origin[2] as isize;
        if gz <= 0 || gz > b.map_dims[2] as isize {
            return;
        }
        let [wx, wy, _] = b.window_dims;
        let z = gz as usize - 1 - b.window_lo[2];
        // Local x with a map sample: padded 1 ..= nx.
        let x0 = 1usize.saturating_sub(self.origin[0]);
        let x1 = (b.map_dims[0] + 1 - self.origin[0]).min(px);
        for y in 0..py {
            let gy = y + self.origin[1];
            if gy == 0 || gy > b.map_dims[1] || x0 >= x1 {
                continue;
            }
            let row = wx * (gy - 1 - b.window_lo[1] + wy * z);
            let from = row + x0 + self.origin[0] - 1 - b.window_lo[0];
            layer[px * y + x0..px * y + x1].copy_from_slice(&b.samples[from..from + (x1 - x0)]);
        }
    }
}

/// One layer of cells: the first vertex of each surface cell and its piece table.
struct CellLayer {
    first: Vec<u32>,
    table: Vec<u32>,
}

impl CellLayer {
    fn reset(&mut self, n: usize) {
        self.first.clear();
        self.first.resize(n, u32::MAX);
        self.table.clear();
        self.table.resize(n, 0);
    }
}

/// The cells a sweep meshes, in the window's local frame.
struct Frame {
    /// Computed cells per axis: `lo[a]..hi[a]`.
    lo: [usize; 3],
    hi: [usize; 3],
    /// The map's cells (the ring rule looks at a neighbour only if the map has it).
    all: [(isize, isize); 3],
    /// The block's own cells (counted as surface cells).
    owned: [std::ops::Range<usize>; 3],
    /// The map's padded sample at local `0`.
    origin: [usize; 3],
}

/// Cells (or edges) skipped at once where a run of samples shows none.
const SKIP: usize = 16;

/// Fewest cell layers a slab task takes.
const SLAB_LAYERS: usize = 16;

/// Marks a vertex of the layer below a slab: the rest is its place in that layer.
const BELOW: u32 = 1 << 31;

/// One slab's net: its own vertices and quads (some naming [`BELOW`] vertices), where its last
/// cell layer's vertices start, and its surface cells.
struct Slab {
    net: Net,
    last_layer_start: u32,
    active_cells: usize,
}

/// The slabs' nets in order as one: vertex indices offset by the slabs before, [`BELOW`]
/// vertices resolved to the previous slab's last layer.
fn join(parts: Vec<Slab>) -> (Net, usize) {
    let mut parts = parts.into_iter();
    let Some(first) = parts.next() else { return (Net { label_start: vec![0], ..Net::default() }, 0) };
    let mut net = first.net;
    let mut previous_last_layer = first.last_layer_start;
    let mut active_cells = first.active_cells;
    for part in parts {
        let offset = net.positions.len() as u32;
        let label_offset = net.labels.len() as u32;
        active_cells += part.active_cells;
        net.positions.extend_from_slice(&part.net.positions);
        net.cells.extend_from_slice(&part.net.cells);
        net.caps.extend(part.net.caps.iter().map(|c| c.map(|v| v + offset)));
        net.labels.extend_from_slice(&part.net.labels);
        net.label_start.extend(part.net.label_start[1..].iter().map(|&s| s + label_offset));
        let below = previous_last_layer;
        net.quads
            .extend(part.net.quads.iter().map(|q| q.map(|v| if v & BELOW != 0 { below + (v & !BELOW) } else { offset + v })));
        net.pairs.extend_from_slice(&part.net.pairs);
        net.tris.extend(part.net.tris.iter().map(|t| t.map(|v| if v & BELOW != 0 { below + (v & !BELOW) } else { offset + v })));
        net.tri_pairs.extend_from_slice(&part.net.tri_pairs);
        previous_last_layer = offset + part.last_layer_start;
    }
    (net, active_cells)
}

/// The sweep over cell layers `layers_range` (the vertex layer below the first one is recomputed
/// to name its vertices, not kept).
fn sweep<T: Label>(window: &Window<'_, '_, T>, frame: &Frame, layers_range: std::ops::Range<usize>, needs: Needs) -> Slab {
    let p = window.p;
    let (lo, hi) = (frame.lo, frame.hi);
    let cells_x = p[0] - 1;
    let layer_cells = cells_x * (p[1] - 1);
    let mut cache = PieceCache::default();
    let mut net = Net::default();
    net.label_start.push(0);
    let mut active_cells = 0;
    let mut last_layer_start = 0;
    // The layer below the slab (not the map's first): its vertices are named, not made.
    let first = if layers_range.start > lo[2] { layers_range.start - 1 } else { layers_range.start };
    // Sample layers cz - 1 ..= cz + 2 (the ring rule reads the cells above and below).
    let mut layers: [Vec<T>; 4] = Default::default();
    for (k, layer) in layers.iter_mut().enumerate().skip(1) {
        window.fill_layer(first as isize + k as isize - 2, layer);
    }
    let mut prev_split: Vec<SplitCell<T>> = Vec::new();
    let mut cur_split: Vec<SplitCell<T>> = Vec::new();
    let mut prev = CellLayer { first: Vec::new(), table: Vec::new() };
    let mut cur = CellLayer { first: Vec::new(), table: Vec::new() };
    let in_range = |c: [isize; 3]| (0..3).all(|d| c[d] >= frame.all[d].0 && c[d] < frame.all[d].1);
    let owned = |c: [usize; 3]| (0..3).all(|d| frame.owned[d].contains(&c[d]));
    for cz in first..layers_range.end {
        let below = cz < layers_range.start;
        layers.rotate_left(1);
        window.fill_layer(cz as isize + 2, &mut layers[3]);
        std::mem::swap(&mut prev, &mut cur);
        cur.reset(layer_cells);
        std::mem::swap(&mut prev_split, &mut cur_split);
        cur_split.clear();
        let px = p[0];
        let at = |layer: &Vec<T>, x: usize, y: usize| layer[x + px * y];
        // The labels of the cell at (x, y) whose lower layer is `layers[k]`.
        let cell_labels = |k: usize, x: usize, y: usize| -> [T; 8] {
            std::array::from_fn(|i| at(&layers[k + (i >> 2)], x + (i & 1), y + (i >> 1 & 1)))
        };
        let (s0, s1) = (&layers[1], &layers[2]);
        // Vertices of cell layer cz (below the slab: only their places in the layer).
        last_layer_start = net.positions.len() as u32;
        let mut named = 0u32;
        for cy in lo[1]..hi[1] {
            let rows = [&s0[px * cy..][..px], &s0[px * (cy + 1)..][..px], &s1[px * cy..][..px], &s1[px * (cy + 1)..][..px]];
            let mut cx = lo[0];
            while cx < hi[0] {
                // Skip a run of cells of one label: the four rows agree over the run and are
                // constant along it.
                if cx + SKIP < px {
                    let run = &rows[0][cx..=cx + SKIP];
                    if rows[1..].iter().all(|r| &r[cx..=cx + SKIP] == run) && run.iter().all(|&l| l == run[0]) {
                        cx += SKIP;
                        continue;
                    }
                }
                let x = cx;
                cx += 1;
                let [r0, r1, r2, r3] = rows;
                let labels = [r0[x], r0[x + 1], r1[x], r1[x + 1], r2[x], r2[x + 1], r3[x], r3[x + 1]];
                if labels.iter().all(|&l| l == labels[0]) {
                    continue;
                }
                let cx = x;
                if !below && owned([cx, cy, cz]) {
                    active_cells += 1;
                }
                // The labels of the cell across face `f`, if the map has it.
                let across = |f: usize| {
                    let mut n = [cx as isize, cy as isize, cz as isize];
                    n[f / 2] += if f % 2 == 1 { 1 } else { -1 };
                    in_range(n).then(|| cell_labels((n[2] - cz as isize + 1) as usize, n[0] as usize, n[1] as usize))
                };
                let (plain, base) = cache.plain(&labels);
                let mut flips = base;
                let mut rings = cache.rings[plain as usize];
                while rings != 0 {
                    let f = rings.trailing_zeros() as usize;
                    rings &= rings - 1;
                    let Some(theirs) = across(f) else { continue };
                    let (t, _) = cache.plain(&theirs);
                    if cache.rings[t as usize] >> (f ^ 1) & 1 == 1 {
                        flips ^= 1 << f;
                    }
                }
                let mut t = if flips == base { plain } else { cache.get(&labels, flips) };
                // A pinched label is split where no neighbour's own split clashes with it: where
                // the cell's faces are its plain ones, no neighbour's plain split puts another
                // label's walls on a face of four labels where it has walls; where the ring rule
                // changed them (its neighbours' splits unknown here), it has no walls on such
                // a face.
                let split_table = cache.split_of[t as usize];
                let clear = split_table != u32::MAX
                    && if flips == base {
                        !clashes(&mut cache, split_table, &labels, &across)
                    } else {
                        !walls_on_four_labels(&cache, split_table, &labels)
                    };
                if clear {
                    t = split_table;
                    cur_split.push(SplitCell { x: cx, y: cy, flips, labels });
                }
                let pieces = &cache.pieces[t as usize];
                let c = cx + cells_x * cy;
                cur.table[c] = t;
                if below {
                    cur.first[c] = BELOW | named;
                    named += u32::from(pieces.count);
                } else {
                    cur.first[c] = net.positions.len() as u32;
                    let o = frame.origin;
                    let c = [cx + o[0], cy + o[1], cz + o[2]];
                    add_vertices(&mut net, cache.places(t), &cache.rests[t as usize], &labels, c, needs);
                }
            }
        }
        let vertex = |layer: &CellLayer, cx: usize, cy: usize, d: usize, corner: u8| -> u32 {
            let c = cx + cells_x * cy;
            layer.first[c] + u32::from(cache.pieces[layer.table[c] as usize].piece[edge_index(d, corner)])
        };
        if below {
            continue;
        }
        // The walls of split cells, each face once: this layer's split cells on their faces in
        // the layer (shared with a split cell: by the first of the two) and below, and the
        // layer below's split cells on their faces above (shared with a cell not split).
        let face_vertices = |layer: &CellLayer, cx: usize, cy: usize, f: usize| -> Option<[u32; 4]> {
            let c = cx + cells_x * cy;
            let first = *layer.first.get(c)?;
            (first != u32::MAX).then(|| {
                let piece = &cache.pieces[layer.table[c] as usize].piece;
                FACES[f].edges.map(|e| first.wrapping_add(u32::from(piece[e as usize])))
            })
        };
        let split_at = |layer: &CellLayer, cx: usize, cy: usize| {
            let c = cx + cells_x * cy;
            layer.first[c] != u32::MAX && cache.has_walls(layer.table[c])
        };
        for s in &cur_split {
            for f in 0..5 {
                let (d, side) = (f / 2, f % 2);
                let (mut nx, mut ny) = (s.x as isize, s.y as isize);
                match d {
                    0 => nx += if side == 1 { 1 } else { -1 },
                    1 => ny += if side == 1 { 1 } else { -1 },
                    _ if cz == first => continue,
                    _ => {}
                }
                if nx < lo[0] as isize || ny < lo[1] as isize || nx >= hi[0] as isize || ny >= hi[1] as isize {
                    continue;
                }
                let (nx, ny) = (nx as usize, ny as usize);
                let layer = if d == 2 { &prev } else { &cur };
                if d < 2 && split_at(layer, nx, ny) && (ny, nx) < (s.y, s.x) {
                    continue;
                }
                let (Some(here), Some(there)) = (face_vertices(&cur, s.x, s.y, f), face_vertices(layer, nx, ny, f ^ 1)) else {
                    continue;
                };
                push_walls(&mut net, f, &s.labels, s.flips, here, there);
            }
        }
        if cz > first {
            for s in &prev_split {
                if split_at(&cur, s.x, s.y) {
                    continue;
                }
                let (Some(here), Some(there)) = (face_vertices(&prev, s.x, s.y, 5), face_vertices(&cur, s.x, s.y, 4)) else {
                    continue;
                };
                push_walls(&mut net, 5, &s.labels, s.flips, here, there);
            }
        }
        // z edges from sample layer cz to cz + 1: their four cells are in layer cz.
        for y in (lo[1] + 1)..hi[1] {
            if s0[px * y..][..px] == s1[px * y..][..px] {
                continue;
            }
            let (r0, r1) = (&s0[px * y..][..px], &s1[px * y..][..px]);
            let mut ex = lo[0] + 1;
            while ex < hi[0] {
                // Skip a run where the two layers agree.
                if ex + SKIP <= hi[0] && r0[ex..ex + SKIP] == r1[ex..ex + SKIP] {
                    ex += SKIP;
                    continue;
                }
                let x = ex;
                ex += 1;
                let (a, b) = (r0[x], r1[x]);
                if a != b {
                    let q = [
                        vertex(&cur, x - 1, y - 1, 2, 3),
                        vertex(&cur, x, y - 1, 2, 2),
                        vertex(&cur, x, y, 2, 0),
                        vertex(&cur, x - 1, y, 2, 1),
                    ];
                    push_quad(&mut net, q, a.id(), b.id());
                }
            }
        }
        // x and y edges of sample layer cz: cells in layers cz - 1 and cz.
        if cz > lo[2] {
            for y in lo[1]..hi[1] {
                let row = &s0[px * y..][..px];
                if row.iter().all(|&l| l == row[0]) && s0[px * (y + 1)..][..px] == *row {
                    continue;
                }
                let next = &s0[px * (y + 1)..][..px];
                let mut ex = lo[0];
                while ex < hi[0] {
                    // Skip a run of one label (no x edge) that the next row repeats (no y edge).
                    // (`hi[0] < px`: the run's last sample is in the row.)
                    if ex + SKIP <= hi[0] {
                        let run = &row[ex..=ex + SKIP];
                        if run.iter().all(|&l| l == run[0]) && next[ex..ex + SKIP] == run[..SKIP] {
                            ex += SKIP;
                            continue;
                        }
                    }
                    let x = ex;
                    ex += 1;
                    let a = at(s0, x, y);
                    // x edge (x, y) - (x + 1, y): cells (x, y - 1 ..= y, cz - 1 ..= cz).
                    let b = at(s0, x + 1, y);
                    if y > lo[1] && a != b {
                        let q = [
                            vertex(&prev, x, y - 1, 0, 6),
                            vertex(&prev, x, y, 0, 4),
                            vertex(&cur, x, y, 0, 0),
                            vertex(&cur, x, y - 1, 0, 2),
                        ];
                        push_quad(&mut net, q, a.id(), b.id());
                    }
                    // y edge (x, y) - (x, y + 1): cells (x - 1 ..= x, y, cz - 1 ..= cz).
                    let b = at(s0, x, y + 1);
                    if x > lo[0] && a != b {
                        let q = [
                            vertex(&prev, x - 1, y, 1, 5),
                            vertex(&cur, x - 1, y, 1, 1),
                            vertex(&cur, x, y, 1, 0),
                            vertex(&prev, x, y, 1, 4),
                        ];
                        push_quad(&mut net, q, a.id(), b.id());
                    }
                }
            }
        }
    }
    Slab { net, last_layer_start, active_cells }
}

/// Whether a cell with corner labels `labels` and split table `split` has a neighbour (its
/// labels `across(f)` across face `f`) whose own split puts another label's walls on a face of
/// four labels where it has walls: two labels split onto one point of three labels meet at a
/// tetrahedron ([`walls_of_face`]), of four they clash. Out of the sweep's hot loop: few cells
/// split.
#[inline(never)]
fn clashes<T: Label>(cache: &mut PieceCache, split: u32, labels: &[T; 8], across: &dyn Fn(usize) -> Option<[T; 8]>) -> bool {
    let walls = cache.walls[split as usize];
    for (f, &w) in walls.iter().enumerate() {
        if w == NONE || !four_labels(labels, f) {
            continue;
        }
        let Some(theirs) = across(f) else { continue };
        let (tn, _) = cache.plain(&theirs);
        let sn = cache.split_of[tn as usize];
        if sn != u32::MAX {
            let wn = cache.walls[sn as usize][f ^ 1];
            if wn != NONE && theirs[wn as usize] != labels[w as usize] {
                return true;
            }
        }
    }
    false
}

/// Whether split table `split` of a cell with corner labels `labels` has walls on a face of four
/// labels.
#[inline(never)]
fn walls_on_four_labels<T: Label>(cache: &PieceCache, split: u32, labels: &[T; 8]) -> bool {
    cache.walls[split as usize].iter().enumerate().any(|(f, &w)| w != NONE && four_labels(labels, f))
}

/// Whether face `f` of a cell with corner labels `labels` has four different labels.
fn four_labels<T: Label>(labels: &[T; 8], f: usize) -> bool {
    let face = FACES[f].corners.map(|c| labels[c as usize]);
    (0..4).all(|i| (i + 1..4).all(|j| face[i] != face[j]))
}

/// A cell whose pinched labels were split, for its walls.
struct SplitCell<T> {
    x: usize,
    y: usize,
    flips: u8,
    labels: [T; 8],
}

/// The walls ([`walls_of_face`]) on face `f` of a split cell with corner labels `labels` and
/// face flips `flips`: `here[k]` is its vertex of the face's edge slot `k`, `there[k]` the vertex
/// of the cell across the face. Each is wound outward for its larger label, as quads are.
fn push_walls<T: Label>(net: &mut Net, f: usize, labels: &[T; 8], flips: u8, here: [u32; 4], there: [u32; 4]) {
    let l = FACES[f].corners.map(|c| labels[c as usize]);
    for w in walls_of_face(l, flips >> f & 1 == 1, here, there) {
        // Whether the label after the slot, going round its quad outward, runs from the cell
        // across the face into this one: the quad of an edge along axis t runs through the
        // cells at (p, q) offsets (-1, -1), (0, -1), (0, 0), (-1, 0) from the edge's lower
        // sample (p, q the axes after t), wound outward for the lower sample's label.
        let (a, b) = EDGES[FACES[f].edges[w.slot] as usize];
        let t = (a ^ b).trailing_zeros() as usize;
        let (p, q) = ((t + 1) % 3, (t + 2) % 3);
        let here_at = [-i32::from(a >> p & 1), -i32::from(a >> q & 1)];
        let mut there_at = here_at;
        let step = if f % 2 == 1 { 1 } else { -1 };
        there_at[usize::from(f / 2 == q)] += step;
        let place = |o: [i32; 2]| [[-1, -1], [0, -1], [0, 0], [-1, 0]].iter().position(|&c| c == o).unwrap_or(0);
        let forward = place(here_at) == (place(there_at) + 1) % 4;
        let x_low = labels[a as usize] == w.x;
        let [s1, n1, n2, s2] = w.polygon;
        let mut polygon = if forward == x_low { vec![s1, n1, n2, s2] } else { vec![s2, n2, n1, s1] };
        polygon.dedup();
        if polygon.first() == polygon.last() {
            polygon.pop();
        }
        let (x, z) = (w.x.id(), w.z.id());
        if x < z {
            polygon.reverse();
        }
        let pair = [x.max(z), x.min(z)];
        match polygon[..] {
            [a, b, c] => {
                net.tris.push([a, b, c]);
                net.tri_pairs.push(pair);
            }
            [a, b, c, d] => {
                net.quads.push([a, b, c, d]);
                net.pairs.push(pair);
            }
            _ => {}
        }
    }
}

/// The vertices of one surface cell at padded cell `c` (its pieces' `places`), with the labels
/// each separates and its cell as `needs` says.
#[inline]
fn add_vertices<T: Label>(net: &mut Net, places: &[VertexPlace], rest: &[u8; 12], labels: &[T; 8], c: [usize; 3], needs: Needs) {
    let base = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
    let first = net.positions.len() as u32;
    for (piece, place) in places.iter().enumerate() {
        let r = rest[piece];
        if r != NONE {
            net.caps.push([first + piece as u32, first + u32::from(r)]);
        }
        net.positions.push(base + place.offset);
        if needs.cells {
            net.cells.push(c.map(|v| v as u32));
        }
        if needs.labels {
            let corners = place.label_corners;
            if corners.count_ones() == 2 {
                let (a, b) = (labels[corners.trailing_zeros() as usize].id(), labels[7 - corners.leading_zeros() as usize].id());
                net.labels.push(a.min(b));
                net.labels.push(a.max(b));
            } else {
                let start = net.labels.len();
                let mut rest = corners;
                while rest != 0 {
                    net.labels.push(labels[rest.trailing_zeros() as usize].id());
                    rest &= rest - 1;
                }
                net.labels[start..].sort_unstable();
            }
            net.label_start.push(net.labels.len() as u32);
        }
    }
}

/// What the net's vertices carry besides their positions: their labels (for smoothing) and
/// their cells (for smoothing and blocks).
#[derive(Clone, Copy, Debug)]
pub(super) struct Needs {
    pub labels: bool,
    pub cells: bool,
}

/// A quad around an edge from a sample of label `a` to one of label `b`, given counter-clockwise
/// seen from the `b` side: kept when `a` is the larger (inside) label, reversed otherwise.
fn push_quad(net: &mut Net, q: [u32; 4], a: u32, b: u32) {
    if a > b {
        net.quads.push(q);
        net.pairs.push([a, b]);
    } else {
        net.quads.push([q[0], q[3], q[2], q[1]]);
        net.pairs.push([b, a]);
    }
}
