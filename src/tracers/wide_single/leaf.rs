//! The wide single-ray walk's leaf stage: a leaf's triangles four at a time, one ray against a
//! whole `TriangleBlock` (`lanes::triangle_block`), as Embree's and tinybvh's single-ray kernels
//! test their 4-triangle leaf blocks. Each block's hitting lanes are taken in lane order against
//! the segment as the earlier ones shortened it, so the hit is the scalar leaf's
//! (`reference::intersect_leaf`) bit for bit. A moving mesh's triangles are tested where they are
//! at the ray's time, one at a time, by the scalar leaf.

use crate::accel::{Bvh, WideBvh};
use crate::geometry::Hit;
use crate::lanes::prefetch::{self, Level};
use crate::lanes::triangle_block::{used_lanes, BlockTests, BLOCK};
use crate::stats::Stats;
use crate::tracers::reference::{intersect_leaf, LeafRange, LeafRay};

/// A leaf of the wide tree: `count` triangles in the blocks from `block`, at `depth` (counters).
#[derive(Clone, Copy)]
pub struct WideLeaf {
    pub block: u32,
    pub count: u32,
    pub depth: usize,
}

/// Asks for the cache lines of the leaf's first block: three, wherever it lies (160 bytes at
/// 32-byte alignment, `TriangleBlock`).
#[inline(always)]
pub fn prefetch<const W: usize>(wide: &WideBvh<W>, block: u32) {
    let base = wide.blocks.as_ptr().wrapping_add(block as usize) as *const u8;
    for line in 0..3 {
        prefetch::line(base.wrapping_add(line * prefetch::LINE), Level::Near);
    }
}

/// The leaf's triangles (module doc), counted as a node at its depth: the closest hit within
/// `[ray.tmin, tmax]` becomes `best` and shortens `tmax`. Returns whether to stop (`ANY` and
/// something was hit).
#[inline(always)]
pub fn visit<const W: usize, R: BlockTests, S: Stats, const ANY: bool>(
    bvh: &Bvh,
    wide: &WideBvh<W>,
    ray: &LeafRay<R>,
    leaf: WideLeaf,
    tmax: &mut f32,
    best: &mut Hit,
    stats: &mut S,
) -> bool {
    if S::ENABLED {
        stats.node(leaf.depth);
    }
    if bvh.motion_end.is_some() {
        let range = LeafRange {
            first: wide.triangles(leaf.block, leaf.count).start as u32,
            count: leaf.count,
            depth: leaf.depth,
        };
        return intersect_leaf::<R, S, ANY>(bvh, ray, range, tmax, best, stats);
    }
    if S::ENABLED {
        (0..leaf.count).for_each(|_| stats.triangle_test(leaf.depth));
    }
    let blocks = &wide.blocks[leaf.block as usize..];
    let mut left = leaf.count;
    for block in blocks {
        let (mut lanes, found) = R::candidates(&ray.tris, block, used_lanes(left), ray.tmin, *tmax);
        while lanes != 0 {
            let l = lanes.trailing_zeros() as usize;
            lanes &= lanes - 1;
            if let Some((t, u, v)) = R::finish(&ray.tris, block, &found, l, ray.tmin, *tmax) {
                *best = Hit {
                    t,
                    prim: block.prim[l],
                    u,
                    v,
                };
                if ANY {
                    return true;
                }
                *tmax = t;
            }
        }
        if left <= BLOCK as u32 {
            break;
        }
        left -= BLOCK as u32;
    }
    false
}
