//! The walk and leaf-culling steps both multi-frusta traversals share, shadow blocks (`block`) and
//! primary frusta (`primary`): Benthin & Wald 2009 §4, all frusta of the block tested against a
//! node's child boxes at once. The walk is generic over the tree (`FrustumTree`): the binary BVH
//! here, a wide one in `wide_walk`.

use glam::Vec3;

use crate::accel::Bvh;
use crate::geometry::{Aabb, Triangle};
use crate::stats::{Event, Owners, Stats};
use crate::tracers::multi_frusta::cull::keep_mask;
use crate::tracers::multi_frusta::frusta::{Frusta, Margins};

/// A leaf a walk reached: a triangle range of the binary tree's `triangles`, its box, and its
/// depth for the per-depth counters (0 when nothing is counted).
#[derive(Clone, Copy, Debug)]
pub struct Leaf {
    pub first: u32,
    pub count: u32,
    pub bounds: Aabb,
    pub depth: usize,
}

/// What a walk position holds: a leaf, or an interior node whose children are tested next.
pub enum Step {
    Leaf(Leaf),
    Inner { node: u32, depth: usize },
}

/// A tree the frusta walk: the binary BVH (the paper's) or a wide one collapsed from it
/// (`wide_walk`), which tests all of a node's children in one `Frusta::box_masks` call. A walk
/// position is a `u32` (on the stack with the frusta that entered it), `ROOT` the root's; the
/// leaves are the binary tree's either way, so the leaf stage is the same.
pub trait FrustumTree {
    const ROOT: u32;

    /// The node or leaf at walk position `at`, its depth counted only when `S` counts.
    fn open<S: Stats>(&self, at: u32) -> Step;

    /// Tests the children of the interior `node` against the frusta of `mask` (one SIMD box
    /// test for all of them and all children) and counts the tests. Returns the child to visit
    /// next with the frusta that may enter it, the nearest along `towards` that any frustum
    /// enters, having pushed the others entered far to near; `None` when no frustum enters any.
    #[allow(clippy::too_many_arguments)]
    fn visit_children<S: Stats>(
        &self,
        node: u32,
        mask: u64,
        frusta: &Frusta,
        margins: &Margins,
        towards: Vec3,
        stack: &mut Vec<(u32, u64)>,
        stats: &mut S,
    ) -> Option<(u32, u64)>;
}

impl FrustumTree for Bvh {
    const ROOT: u32 = Bvh::ROOT as u32;

    #[inline(always)]
    fn open<S: Stats>(&self, at: u32) -> Step {
        let node = &self.nodes[at as usize];
        let depth = depth::<S>(&self.depth, at);
        if node.is_leaf() {
            Step::Leaf(Leaf {
                first: node.first,
                count: node.count,
                bounds: node.bounds,
                depth,
            })
        } else {
            Step::Inner { node: at, depth }
        }
    }

    #[inline(always)]
    fn visit_children<S: Stats>(
        &self,
        node: u32,
        mask: u64,
        frusta: &Frusta,
        margins: &Margins,
        towards: Vec3,
        stack: &mut Vec<(u32, u64)>,
        stats: &mut S,
    ) -> Option<(u32, u64)> {
        let (a, b) = {
            let first = self.nodes[node as usize].first;
            (first, first + 1)
        };
        // Siblings are adjacent: one bounds check for both.
        let [child_a, child_b] = &self.nodes[a as usize..][..2] else {
            unreachable!("a slice of two nodes")
        };
        let (box_a, box_b) = (&child_a.bounds, &child_b.bounds);
        let [mask_a, mask_b] = frusta.box_masks([box_a, box_b], mask, margins);
        if S::ENABLED {
            let entered = (mask_a != 0) as u64 + (mask_b != 0) as u64;
            // Siblings share a depth.
            count_child_tests(stats, mask, 2, entered, self.depth[a as usize] as usize);
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
}

/// Counts one node's child tests: `children` boxes at `depth`, each met by the frusta of `mask`,
/// `entered` of them entered by some frustum.
#[inline(always)]
pub fn count_child_tests<S: Stats>(
    stats: &mut S,
    mask: u64,
    children: u64,
    entered: u64,
    depth: usize,
) {
    stats.event(Event::FrustumBoxTests, children);
    stats.event(Event::FrustaAtNodes, mask.count_ones() as u64);
    stats.event(Event::BoxesCulled, children - entered);
    // Frusta are the rays here (`relabelled` by the caller spreads them over their pixels).
    (0..children).for_each(|_| {
        stats.aabb_tests(
            depth,
            Owners::Bits {
                base: 0,
                bits: mask,
            },
            Frusta::lanes_issued(mask),
        )
    });
}

/// Starts a block's walk: the root's box (`bvh`'s, the binary tree `tree` was made from) against
/// the frusta of `mask`, counted, on an emptied stack.
#[inline(always)]
pub fn start_at_root<T: FrustumTree, S: Stats>(
    bvh: &Bvh,
    mask: u64,
    frusta: &Frusta,
    margins: &Margins,
    stack: &mut Vec<(u32, u64)>,
    stats: &mut S,
) {
    if S::ENABLED {
        stats.event(Event::FrustumBoxTests, 1);
        stats.aabb_tests(
            0,
            Owners::Bits {
                base: 0,
                bits: mask,
            },
            Frusta::lanes_issued(mask),
        );
    }
    let root = &bvh.nodes[Bvh::ROOT];
    stack.clear();
    stack.push((T::ROOT, frusta.box_masks([&root.bounds], mask, margins)[0]));
}

/// Walks on to the next leaf some frustum of `live` may reach: pops the stack and goes straight
/// down from each popped position to the nearest child entered (`visit_children`, the others
/// pushed), counting every node and leaf visited. Returns the leaf and the frusta that reach it;
/// `None` when the walk is over.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub fn next_leaf<T: FrustumTree, S: Stats>(
    tree: &T,
    live: u64,
    frusta: &Frusta,
    margins: &Margins,
    towards: Vec3,
    stack: &mut Vec<(u32, u64)>,
    stats: &mut S,
) -> Option<(Leaf, u64)> {
    'walk: while let Some((mut at, mask)) = stack.pop() {
        let mut mask = mask & live;
        if mask == 0 {
            continue;
        }
        loop {
            match tree.open::<S>(at) {
                Step::Leaf(leaf) => {
                    if S::ENABLED {
                        stats.node_shared(
                            leaf.depth,
                            Owners::Bits {
                                base: 0,
                                bits: mask,
                            },
                        );
                    }
                    return Some((leaf, mask));
                }
                Step::Inner { node, depth } => {
                    if S::ENABLED {
                        stats.node_shared(
                            depth,
                            Owners::Bits {
                                base: 0,
                                bits: mask,
                            },
                        );
                    }
                    match tree.visit_children(node, mask, frusta, margins, towards, stack, stats) {
                        Some(child) => (at, mask) = child,
                        None => continue 'walk,
                    }
                }
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

/// Node `i`'s depth (of a tree's per-node `depths`) for the per-depth counters (0 when nothing
/// is counted).
#[inline(always)]
pub fn depth<S: Stats>(depths: &[u8], i: u32) -> usize {
    if S::ENABLED {
        depths[i as usize] as usize
    } else {
        0
    }
}
