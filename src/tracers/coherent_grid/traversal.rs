//! The slice walk of coherent grid traversal (Wald et al. 2006, §2.2): the frustum marches slice by
//! slice along its major axis, and in each slice every cell its overlap box covers is handed to
//! the packet. Macrocells (§2.4) skip whole layers of M slices whose overlapped macrocells are
//! all empty, and within a slice skip the M×M blocks of cells of empty macrocells.
//!
//! Events told to the visitor: `SlicesStepped` per slice the walk enters and does not skip with
//! its macrocell layer; `MacrocellsSkipped` per empty macrocell the frustum overlaps in
//! a skipped layer, plus per empty macrocell block passed over in a visited slice (so a macrocell
//! can count once for each of its slices the packet visits).

use crate::accel::Grid;
use crate::stats::Event;

use super::frustum::{cell_range, MarchFrame, MarchFrustum};

/// What the walk drives: the packet's rays, told where the walk is.
pub trait SliceVisitor {
    /// The walk is about to enter march slice `slice`; `false` ends the walk (every ray done).
    fn begin_slice(&mut self, slice: u32) -> bool;
    /// Cell `index` of the grid (coordinates `cell`) lies in the frustum.
    fn cell(&mut self, index: usize, cell: [u32; 3]);
    /// `n` occurrences of a walk event (see the module doc).
    fn count(&mut self, event: Event, n: u64);
}

/// Walks `frustum` through `grid` front to back in `frame`; `macrocells` enables §2.4.
pub fn walk(
    grid: &Grid,
    frame: &MarchFrame,
    frustum: &MarchFrustum,
    macrocells: bool,
    visitor: &mut impl SliceVisitor,
) {
    let [slices, res_u, res_v] = frame.res;
    let Some((first, last)) = frustum.slice_range(slices) else {
        return;
    };
    let m = grid.config.macro_size;
    // Layers before this march slice have had their macrocells checked.
    let mut checked_to = first;
    let mut slice = first;
    while slice <= last {
        if !visitor.begin_slice(slice) {
            return;
        }
        if macrocells && slice >= checked_to {
            // §2.4: one slice of macrocells first; if every macrocell the frustum overlaps in it
            // is empty, the packet skips the whole layer.
            let (_, layer_end) = frame.macro_layer(slice, m);
            checked_to = layer_end + 1;
            let cells = frustum
                .overlap(slice as f32, (layer_end + 1) as f32)
                .and_then(|b| cell_range(b, res_u, res_v));
            let occupied =
                cells.is_some_and(|cells| any_macro_occupied(grid, frame, slice, cells, m));
            if !occupied {
                if let Some([i0, i1, j0, j1]) = cells {
                    let blocks = (i1 / m - i0 / m + 1) * (j1 / m - j0 / m + 1);
                    visitor.count(Event::MacrocellsSkipped, blocks as u64);
                }
                slice = layer_end + 1;
                continue;
            }
        }
        visitor.count(Event::SlicesStepped, 1);
        if let Some(cells) = frustum
            .overlap(slice as f32, (slice + 1) as f32)
            .and_then(|b| cell_range(b, res_u, res_v))
        {
            if macrocells {
                visit_by_macro_block(grid, frame, slice, cells, m, visitor);
            } else {
                visit_cells(grid, frame, slice, cells, visitor);
            }
        }
        slice += 1;
    }
}

/// The cells `[i0, i1] × [j0, j1]` of march slice `slice`.
fn visit_cells(
    grid: &Grid,
    frame: &MarchFrame,
    slice: u32,
    [i0, i1, j0, j1]: [u32; 4],
    visitor: &mut impl SliceVisitor,
) {
    for j in j0..=j1 {
        for i in i0..=i1 {
            let c = frame.cell(slice, i, j);
            visitor.cell(grid.cell_index(c[0], c[1], c[2]), c);
        }
    }
}

/// The cells of `[i0, i1] × [j0, j1]` in march slice `slice`, skipping the blocks of cells that
/// lie in empty macrocells.
fn visit_by_macro_block(
    grid: &Grid,
    frame: &MarchFrame,
    slice: u32,
    [i0, i1, j0, j1]: [u32; 4],
    m: u32,
    visitor: &mut impl SliceVisitor,
) {
    for mj in j0 / m..=j1 / m {
        for mi in i0 / m..=i1 / m {
            if macro_empty(grid, frame, slice, mi, mj, m) {
                visitor.count(Event::MacrocellsSkipped, 1);
                continue;
            }
            let cells = [
                i0.max(mi * m),
                i1.min(mi * m + m - 1),
                j0.max(mj * m),
                j1.min(mj * m + m - 1),
            ];
            visit_cells(grid, frame, slice, cells, visitor);
        }
    }
}

fn any_macro_occupied(
    grid: &Grid,
    frame: &MarchFrame,
    slice: u32,
    [i0, i1, j0, j1]: [u32; 4],
    m: u32,
) -> bool {
    (j0 / m..=j1 / m)
        .any(|mj| (i0 / m..=i1 / m).any(|mi| !macro_empty(grid, frame, slice, mi, mj, m)))
}

/// Whether the macrocell holding march slice `slice` and macro column `(mi, mj)` is empty.
#[inline]
fn macro_empty(grid: &Grid, frame: &MarchFrame, slice: u32, mi: u32, mj: u32, m: u32) -> bool {
    let mut c = [0; 3];
    c[frame.k] = frame.grid_slice(slice) / m;
    c[frame.u] = mi;
    c[frame.v] = mj;
    grid.macro_is_empty(c[0], c[1], c[2])
}
