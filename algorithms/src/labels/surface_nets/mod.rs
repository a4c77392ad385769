//! # Multi-label surface nets
//!
//! **Paper:** S. F. Frisken, "SurfaceNets for Multi-Label Segmentations with Preservation of
//! Sharp Boundaries", Journal of Computer Graphics Techniques 11(1), 34–54, 2022 (the algorithm
//! of VTK's `vtkSurfaceNets3D`); after S. F. F. Gibson, "Constrained elastic surface nets",
//! MICCAI 1998.
//!
//! **Summary.** Every cell (the cube between eight samples) whose corners are not all one label
//! gets one vertex per piece of interface in it ([`super::cell`]), first at the mean of the
//! midpoints of the piece's crossing edges. Every lattice edge whose two samples differ gets one
//! quad joining the vertices of its four cells, tagged with the two labels and wound so that its
//! normal points from the larger label into the smaller; quads are split along their shorter
//! diagonal after smoothing. Cells are swept in layers along z, keeping two layers of vertex
//! indices.
//!
//! **Smoothing** (`smoothing=constrained`, the default), as Frisken's: each vertex moves toward
//! the mean of its net neighbours whose labels include all of its own, `x += λ (mean − x)`, and
//! never out of its cell. A vertex on the interface of two labels follows its surface; one on a
//! junction of three labels follows only the junction line, so the line stays sharp; a vertex
//! where four or more labels meet has no such neighbour and stays. `iterations` (16) and
//! `relaxation` (λ = 0.5) are the defaults of pyvista's `contour_labels`, which runs
//! `vtkSurfaceNets3D`.
//!
//! **Border.** With `border=closed` (the default) the map is surrounded by background, so every
//! label's mesh is closed; `border=open` meshes only cells inside the map, and a label's mesh is
//! open where the label reaches the border.
//!
//! **Guarantees.** Every vertex lies in its cell, before and after smoothing (smoothing keeps it
//! a tenth of a sample inside, so a label of one sample cannot turn inside out). The interface of
//! two labels is the same triangles in both labels' meshes (one mesh, tagged: see [`super`]).
//! Each label's mesh is closed, encloses its samples and no other, and is consistently wound
//! where it is manifold. With two labels in every cell (a label and the background, say) it is
//! manifold: every pattern of two cells is tested. With more, it is manifold wherever the splits
//! below resolve every cell.
//!
//! **Pinches and bridges split** (`split`; beyond Frisken, whose net and VTK's keep one vertex
//! per cell). Where one piece carries two separate boundary loops of one label (a pinched
//! vertex), or a label's bridge across an `a, x, a, y` face would put four of its triangles on
//! one net edge, the piece gets one vertex per loop (*cap*) of the label concerned and one for
//! the rest, and each face point where a cap's sheets meet other sheets gets a wall: a triangle
//! or quad between the cap's vertex, the rest's and the vertex across the face, an interface of
//! the two labels beside the split one there (where both cells across a face of three labels
//! split different labels, two walls around a tetrahedron given to the third). Smoothing moves
//! a cap's vertex by the move of its rest's vertex (kept in the cell), so the walls keep their
//! shape instead of folding as the two follow different neighbours. A cell splits only on its
//! own pattern and its neighbours' patterns, so blocks and slabs mesh it as the whole map does.
//!
//! **Non-guarantees.** A piece where two labels pinch, two cells across a face of four labels
//! that would split different labels, and a cell whose ring rule changed its faces that would
//! put walls on a face of four labels stay as Frisken's net has them: one vertex, and that
//! label's mesh not manifold there.
//! `tests/tests/labels.rs` checks that every one-cell map whose cells are all resolved is
//! manifold for every label, and counts the maps that are not; `marching-tetrahedra`
//! ([`super::marching_tetrahedra`]) is the entry that is manifold for every map.
//!
//! **Files.** This one (the net, the triangles), `sweep` (cells in layers, quads and walls),
//! `pieces` (each cell pattern's tables, once per pattern), `split` (which pieces split, and
//! the walls) and `smoothing` (Frisken's constrained smoothing).
//!
//! **Costs.** One read of every sample (a copy of each layer, padded), work proportional to the
//! surface cells (each cell's pieces looked up by its pattern), and `iterations` passes over the
//! vertices.
//!
//! ```
//! use isolab_algorithms::labels::{self, LabelMap, LabelSurface};
//! use isolab_algorithms::Options;
//! // Two labels side by side in a 4 x 2 x 2 map: 1 on the left, 2 on the right.
//! let map: Vec<u8> = (0..16).map(|i| if i % 4 < 2 { 1 } else { 2 }).collect();
//! let nets = labels::build("surface-nets", &Options::new()).unwrap().unwrap();
//! let mut out = LabelSurface::default();
//! nets.extract_u8(LabelMap::new([4, 2, 2], &map).unwrap(), &mut out).unwrap();
//! assert_eq!(out.labels(), [1, 2]);
//! // The 1|2 interface is shared: as many triangles tagged [2, 1] in both labels' meshes.
//! let shared = out.pairs.iter().filter(|p| **p == [2, 1]).count();
//! assert!(shared > 0);
//! let one = out.label_mesh(1);
//! assert_eq!(one.triangles.len(), out.pairs.iter().filter(|p| p.contains(&1)).count());
//! ```

use glam::Vec3;

mod pieces;
mod smoothing;
pub mod split;
mod sweep;

use super::blocks::{LabelBlock, LabelFragment};
use super::{Border, Label, LabelExtractor, LabelExtractorInfo, LabelGuarantees, LabelMap, LabelSurface};
use crate::extract::ExtractError;
use crate::options::{OptionError, Options};
use smoothing::smooth;

/// One line for listings.
pub const DESCRIPTION: &str =
    "Frisken 2022: one vertex per piece of interface in a cell (pinched labels split apart), a quad per edge between two labels, smoothing that keeps junctions sharp";

/// Option names for [`from_options`].
pub const OPTION_NAMES: &[&str] = &["smoothing", "iterations", "relaxation", "border"];

/// Multi-label surface nets (Frisken 2022).
pub const INFO: LabelExtractorInfo = LabelExtractorInfo {
    name: "surface-nets",
    description: DESCRIPTION,
    options: OPTION_NAMES,
    make: from_options,
    guarantees: LabelGuarantees { closed: true, manifold: false, outward: true, dihedral: None },
};

/// How vertices move after placement.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LabelSmoothing {
    /// Vertices stay at the mean of their crossing edges' midpoints.
    None,
    /// Frisken's constrained smoothing (see the module doc).
    Constrained,
}

/// The options of [`LabelSurfaceNets`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LabelSnOptions {
    /// Smoothing (default constrained).
    pub smoothing: LabelSmoothing,
    /// Smoothing passes (default 16).
    pub iterations: usize,
    /// Step toward the neighbours' mean per pass (default 0.5).
    pub relaxation: f32,
    /// The map's border (default closed).
    pub border: Border,
}

impl Default for LabelSnOptions {
    fn default() -> Self {
        Self { smoothing: LabelSmoothing::Constrained, iterations: 16, relaxation: 0.5, border: Border::Closed }
    }
}

/// Builds multi-label surface nets from named options.
pub fn from_options(options: &Options) -> Result<Box<dyn LabelExtractor>, OptionError> {
    let d = LabelSnOptions::default();
    let mut r = options.reader(INFO.name, OPTION_NAMES);
    let o = LabelSnOptions {
        smoothing: r.choice(
            "smoothing",
            d.smoothing,
            &[("none", LabelSmoothing::None), ("constrained", LabelSmoothing::Constrained)],
        )?,
        iterations: r.count("iterations", d.iterations, 10_000)?,
        relaxation: r.number("relaxation", d.relaxation, 1e-6, 1.0)?,
        border: r.choice("border", d.border, &[("closed", Border::Closed), ("open", Border::Open)])?,
    };
    r.finish()?;
    Ok(Box::new(LabelSurfaceNets { options: o }))
}

/// Multi-label surface nets.
#[derive(Clone, Debug, Default)]
pub struct LabelSurfaceNets {
    /// Its options.
    pub options: LabelSnOptions,
}

impl LabelExtractor for LabelSurfaceNets {
    fn info(&self) -> &'static LabelExtractorInfo {
        &INFO
    }
    fn extract_u8(&self, map: LabelMap<'_, u8>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, &self.options, out)
    }
    fn extract_u16(&self, map: LabelMap<'_, u16>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, &self.options, out)
    }
    fn extract_u32(&self, map: LabelMap<'_, u32>, out: &mut LabelSurface) -> Result<(), ExtractError> {
        extract(map, &self.options, out)
    }
    fn apron(&self) -> usize {
        let o = &self.options;
        1 + if o.smoothing == LabelSmoothing::Constrained { o.iterations } else { 0 }
    }
    fn border(&self) -> Border {
        self.options.border
    }
    fn block_u8(&self, block: LabelBlock<'_, u8>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, &self.options, out);
        Ok(())
    }
    fn block_u16(&self, block: LabelBlock<'_, u16>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, &self.options, out);
        Ok(())
    }
    fn block_u32(&self, block: LabelBlock<'_, u32>, out: &mut LabelFragment) -> Result<(), ExtractError> {
        extract_block(&block, &self.options, out);
        Ok(())
    }
}

/// The net before triangulation.
#[derive(Default)]
struct Net {
    positions: Vec<Vec3>,
    /// The padded cell of each vertex (empty unless smoothing or blocks need it).
    cells: Vec<[u32; 3]>,
    /// `[cap, rest]`: each cap's vertex (`split`) and the vertex of the rest of its piece, in
    /// increasing order of the cap.
    caps: Vec<[u32; 2]>,
    /// Each vertex's labels (sorted): `labels[label_start[v]..label_start[v + 1]]` (only
    /// `[0]` unless smoothing needs them).
    label_start: Vec<u32>,
    labels: Vec<u32>,
    quads: Vec<[u32; 4]>,
    pairs: Vec<[u32; 2]>,
    /// The walls of split cells that are triangles (`split`), wound as quads are.
    tris: Vec<[u32; 3]>,
    tri_pairs: Vec<[u32; 2]>,
    /// The padded cells the net covers, per axis.
    cell_box: [std::ops::Range<u32>; 3],
}

fn extract<T: Label>(map: LabelMap<'_, T>, o: &LabelSnOptions, out: &mut LabelSurface) -> Result<(), ExtractError> {
    out.clear();
    let whole = LabelBlock {
        samples: map.labels,
        window_lo: [0; 3],
        window_dims: map.dims,
        map_dims: map.dims,
        cells: std::array::from_fn(|a| all_cells(map.dims[a], o.border)),
        apron: 0,
    };
    let (net, active_cells) = smoothed_net(&whole, o, false);
    out.active_cells = active_cells;
    triangulate(net, out);
    Ok(())
}

/// Block `block`'s fragment: the whole map's triangles on the edges the block owns.
fn extract_block<T: Label>(block: &LabelBlock<'_, T>, o: &LabelSnOptions, out: &mut LabelFragment) {
    let (net, active_cells) = smoothed_net(block, o, true);
    let owned = &block.cells;
    let owner_owned =
        |q: &[u32]| (0..3).all(|a| owned[a].contains(&(q.iter().map(|&v| net.cells[v as usize][a]).max().unwrap_or(0) as usize)));
    let sizes = block.map_dims.map(|n| n + 2);
    // Each vertex's weld key: its padded cell and its place among the cell's pieces.
    let mut keys = Vec::with_capacity(net.positions.len());
    for v in 0..net.positions.len() {
        let c = net.cells[v];
        let piece = if v > 0 && net.cells[v - 1] == c { (keys.last().copied().unwrap_or(0u128) & 0xff) as u64 + 1 } else { 0 };
        keys.push(super::blocks::key(c.map(|x| x as usize), sizes, piece));
    }
    let mut local = vec![u32::MAX; net.positions.len()];
    let surface = &mut out.surface;
    surface.active_cells = active_cells;
    let mut local_of = |v: u32, surface: &mut LabelSurface| {
        let m = &mut local[v as usize];
        if *m == u32::MAX {
            *m = surface.mesh.positions.len() as u32;
            surface.mesh.positions.push(net.positions[v as usize] - Vec3::ONE);
            out.keys.push(keys[v as usize]);
        }
        *m
    };
    for (q, pair) in net.quads.iter().zip(&net.pairs) {
        if !owner_owned(q) {
            continue;
        }
        let halves = split_quad(q.map(|v| net.positions[v as usize]));
        let q = q.map(|v| local_of(v, surface));
        surface.mesh.triangles.extend(halves.map(|t| t.map(|k| q[k])));
        surface.pairs.extend([*pair, *pair]);
    }
    for (t, pair) in net.tris.iter().zip(&net.tri_pairs) {
        if owner_owned(t) {
            let t = t.map(|v| local_of(v, surface));
            surface.mesh.triangles.push(t);
            surface.pairs.push(*pair);
        }
    }
}

/// The cells of an axis of `n` samples (padded coordinates) under `border`.
fn all_cells(n: usize, border: Border) -> std::ops::Range<usize> {
    match border {
        Border::Closed => 0..n + 1,
        Border::Open => 1..n.max(1),
    }
}

/// The net of `block`'s computed cells (its owned cells and apron), smoothed as `o` says, and
/// the number of owned surface cells; its vertices' cells kept if `cells` (or smoothing needs
/// them).
fn smoothed_net<T: Label>(block: &LabelBlock<'_, T>, o: &LabelSnOptions, cells: bool) -> (Net, usize) {
    let all: [std::ops::Range<usize>; 3] = std::array::from_fn(|a| all_cells(block.map_dims[a], o.border));
    let smoothing = o.smoothing == LabelSmoothing::Constrained;
    let needs = sweep::Needs { labels: smoothing, cells: cells || smoothing };
    let (mut net, active_cells) = sweep::net(block, &all, needs);
    if smoothing {
        smooth(&mut net, o.iterations, o.relaxation);
    }
    (net, active_cells)
}

/// Quads to triangles along their shorter diagonal, positions from padded to map coordinates.
fn triangulate(net: Net, out: &mut LabelSurface) {
    let Net { positions, quads, pairs, tris, tri_pairs, .. } = net;
    out.mesh.triangles.reserve(quads.len() * 2 + tris.len());
    out.pairs.reserve(quads.len() * 2 + tris.len());
    for (q, pair) in quads.iter().zip(&pairs) {
        let [a, b, c, d] = *q;
        let p = |v: u32| positions[v as usize];
        let halves = if shorter_first(p(a), p(b), p(c), p(d)) { [[a, b, c], [a, c, d]] } else { [[a, b, d], [b, c, d]] };
        out.mesh.triangles.push(halves[0]);
        out.mesh.triangles.push(halves[1]);
        out.pairs.push(*pair);
        out.pairs.push(*pair);
    }
    out.mesh.triangles.extend_from_slice(&tris);
    out.pairs.extend_from_slice(&tri_pairs);
    out.mesh.positions = positions.into_iter().map(|p| p - Vec3::ONE).collect();
}

/// A quad with corners at `p` as two triangles (of corner slots) along its shorter diagonal.
fn split_quad(p: [Vec3; 4]) -> [[usize; 3]; 2] {
    if shorter_first(p[0], p[1], p[2], p[3]) {
        [[0, 1, 2], [0, 2, 3]]
    } else {
        [[0, 1, 3], [1, 2, 3]]
    }
}

/// Whether quad `a, b, c, d`'s diagonal `a c` is no longer than `b d`.
#[inline]
fn shorter_first(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> bool {
    a.distance_squared(c) <= b.distance_squared(d)
}
