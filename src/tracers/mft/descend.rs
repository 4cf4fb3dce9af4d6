//! The walk and leaf-culling steps both multi-frusta traversals share, shadow blocks (`block`) and
//! primary frusta (`primary`): Benthin & Wald 2009 §4, all frusta of the block tested against a
//! child's box at once.

use glam::Vec3;

use crate::accel::{Bvh, BvhNode};
use crate::geometry::Triangle;
use crate::stats::{Event, Stats};
use crate::tracers::mft::cull::keep_mask;
use crate::tracers::mft::frusta::{Frusta, Margins};

/// Tests both children of the interior `node` against the frusta of `mask` (one SIMD box test
/// for all of them and both boxes) and counts the tests. Returns the child to visit next with the
/// frusta that may enter it, the nearer along `towards` that any frustum enters, having pushed the
/// other when some frustum enters it too; `None` when no frustum enters either.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn visit_children<S: Stats>(
    bvh: &Bvh,
    node: &BvhNode,
    mask: u64,
    frusta: &Frusta,
    margins: &Margins,
    towards: Vec3,
    stack: &mut Vec<(u32, u64)>,
    stats: &mut S,
) -> Option<(u32, u64)> {
    let (a, b) = (node.first, node.first + 1);
    // Siblings are adjacent: one bounds check for both.
    let [child_a, child_b] = &bvh.nodes[a as usize..][..2] else {
        unreachable!("a slice of two nodes")
    };
    let (box_a, box_b) = (&child_a.bounds, &child_b.bounds);
    let [mask_a, mask_b] = frusta.box_masks([box_a, box_b], mask, margins);
    if S::ENABLED {
        stats.event(Event::FrustumBoxTests, 2);
        stats.event(Event::FrustaAtNodes, mask.count_ones() as u64);
        stats.event(
            Event::BoxesCulled,
            (mask_a == 0) as u64 + (mask_b == 0) as u64,
        );
        for _ in 0..mask.count_ones() {
            stats.aabb_test(bvh.depth[a as usize] as usize);
            stats.aabb_test(bvh.depth[b as usize] as usize);
        }
    }
    let a_first = (box_a.min + box_a.max - box_b.min - box_b.max).dot(towards) <= 0.0;
    let (near, far) = if a_first {
        ((a, mask_a), (b, mask_b))
    } else {
        ((b, mask_b), (a, mask_a))
    };
    // The nearer child entered is visited next without the stack; the other waits on it.
    match (near.1 != 0, far.1 != 0) {
        (true, true) => {
            stack.push(far);
            Some(near)
        }
        (true, false) => Some(near),
        (false, true) => Some(far),
        (false, false) => None,
    }
}

/// Starts a block's walk: the root's box against the frusta of `mask`, counted, on an emptied
/// stack.
#[inline(always)]
pub fn start_at_root<S: Stats>(
    bvh: &Bvh,
    mask: u64,
    frusta: &Frusta,
    margins: &Margins,
    stack: &mut Vec<(u32, u64)>,
    stats: &mut S,
) {
    if S::ENABLED {
        stats.event(Event::FrustumBoxTests, 1);
        (0..mask.count_ones()).for_each(|_| stats.aabb_test(0));
    }
    let root = &bvh.nodes[Bvh::ROOT];
    stack.clear();
    stack.push((
        Bvh::ROOT as u32,
        frusta.box_masks([&root.bounds], mask, margins)[0],
    ));
}

/// Walks on to the next leaf some frustum of `live` may reach: pops the stack and goes straight
/// down from each popped node to the nearer child entered (`visit_children`, the farther one
/// pushed), counting every node visited. Returns the leaf and the frusta that reach it; `None`
/// when the walk is over.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn next_leaf<S: Stats>(
    bvh: &Bvh,
    live: u64,
    frusta: &Frusta,
    margins: &Margins,
    towards: Vec3,
    stack: &mut Vec<(u32, u64)>,
    stats: &mut S,
) -> Option<(u32, u64)> {
    'walk: while let Some((mut index, mask)) = stack.pop() {
        let mut mask = mask & live;
        if mask == 0 {
            continue;
        }
        loop {
            if S::ENABLED {
                stats.node(depth::<S>(bvh, index));
            }
            let node = &bvh.nodes[index as usize];
            if node.is_leaf() {
                return Some((index, mask));
            }
            match visit_children(bvh, node, mask, frusta, margins, towards, stack, stats) {
                Some(child) => (index, mask) = child,
                None => continue 'walk,
            }
        }
    }
    None
}

/// The frusta of `candidates` that must test a leaf triangle's rays: those it cannot be culled
/// for (`cull::keep_mask`), counted as the paper's #tris, kept share and #isec (Fig. 6, Table 1).
#[inline(always)]
pub fn keep_counted<S: Stats>(
    frusta: &Frusta,
    tri: &Triangle,
    candidates: u64,
    backface: bool,
    stats: &mut S,
) -> u64 {
    let keep = keep_mask(frusta, tri, candidates, backface);
    if S::ENABLED {
        stats.event(Event::TrianglesAccessed, 1);
        stats.event(Event::TrianglesKept, (keep != 0) as u64);
        stats.event(Event::FrustumTriangleTests, keep.count_ones() as u64);
        stats.event(
            Event::TrianglesCulled,
            (candidates & !keep).count_ones() as u64,
        );
    }
    keep
}

/// Node `i`'s depth for the per-depth counters (0 when nothing is counted).
#[inline(always)]
pub fn depth<S: Stats>(bvh: &Bvh, i: u32) -> usize {
    if S::ENABLED {
        bvh.depth[i as usize] as usize
    } else {
        0
    }
}
