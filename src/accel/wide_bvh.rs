//! A `W`-wide BVH (W = 4 or 8) collapsed from the binary SAH tree (`Bvh`), for packet traversals
//! that test all of a node's children against a whole packet in one SIMD operation (Wald, Benthin
//! and Boulos 2008, "Getting rid of packets"; Fuetterling et al. 2015 over large packets).
//!
//! Collapse: each wide node starts from a binary interior node's two children and repeatedly
//! replaces the interior child of largest surface area by its two children until it has `W`
//! children or only leaves are left (the usual greedy collapse). Leaves are the binary tree's
//! leaves, their triangles also copied into runs of 4-triangle blocks (`TriangleBlock`, Embree's
//! `Triangle4`), each leaf's run allocated as its wide node is made, so a node's leaf blocks lie
//! together: the wide single-ray walk tests a block's four triangles at once, and the tracers that
//! test triangles one at a time read the leaf's range of the binary tree's `triangles`
//! (`WideBvh::triangles`), which the tree records per block.
//!
//! Layout: child boxes in structure-of-arrays lanes (`lo[axis][child]`, `hi[axis][child]`), so a
//! slab test of one ray interval against all children is a handful of W-wide vector operations.
//! Each child's reference is two u32 lanes, `first` and `count` (`WideNode::child`), and whether a
//! slot is in use follows from them, so a node is its boxes and references and nothing else:
//! W = 4 is 128 bytes (two cache lines), W = 8 is 256 (four), as Embree's 4- and 8-wide nodes;
//! the walks are bound by these loads. Unused child slots hold an empty box (`lo = +∞`,
//! `hi = −∞`), which no slab test and no interval test can hit.
//!
//! Entry points (`entry`): where each binary node sits in the wide tree — the wide node whose
//! collapse took it in and the child slots below it — so a traversal that reached a binary node
//! (the stream tracer's single-ray hand-off) can go on in the wide tree from there.

use std::ops::Range;

use super::bvh::Bvh;
use crate::lanes::triangle_block::{TriangleBlock, BLOCK};

/// One child slot: an interior wide node, a leaf, or nothing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WideChild {
    Node(u32),
    /// `count` triangles in blocks `block .. block + ⌈count / 4⌉` of the wide tree's `blocks`
    /// (`WideBvh::triangles`: their range of the binary tree's `triangles`).
    Leaf {
        block: u32,
        count: u32,
    },
    Empty,
}

/// A wide node: its children's boxes in structure-of-arrays lanes and their references.
///
/// A child's reference is `(first, count)`: a leaf is `(first block, count ≥ 1)`, an interior
/// child `(node index, 0)`, an empty slot `(0, 0)`. Node 0 is the root, nobody's child, so an
/// interior child's index is never 0 and the three kinds never meet. Both lanes are u32: a leaf
/// is usually at most `BvhConfig::max_leaf_size` triangles, but one cut at `max_depth` holds
/// whatever reached it, so a narrower count could overflow.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct WideNode<const W: usize> {
    pub lo: [[f32; W]; 3],
    pub hi: [[f32; W]; 3],
    pub first: [u32; W],
    pub count: [u32; W],
}

// Exactly Embree's node sizes: no padding line (module doc).
const _: () = assert!(std::mem::size_of::<WideNode<4>>() == 128);
const _: () = assert!(std::mem::size_of::<WideNode<8>>() == 256);

impl<const W: usize> WideNode<W> {
    const EMPTY: Self = WideNode {
        lo: [[f32::INFINITY; W]; 3],
        hi: [[f32::NEG_INFINITY; W]; 3],
        first: [0; W],
        count: [0; W],
    };

    #[inline(always)]
    pub fn child(&self, c: usize) -> WideChild {
        match (self.first[c], self.count[c]) {
            (0, 0) => WideChild::Empty,
            (node, 0) => WideChild::Node(node),
            (block, count) => WideChild::Leaf { block, count },
        }
    }

    /// Makes slot `c` the child `child` with box `(lo, hi)` (an empty slot: the empty box,
    /// whatever is passed). Panics on `Node(0)`, the root, which is nobody's child.
    pub fn set_child(&mut self, c: usize, child: WideChild, lo: [f32; 3], hi: [f32; 3]) {
        (self.first[c], self.count[c]) = match child {
            WideChild::Node(node) => {
                assert_ne!(node, 0, "the root is nobody's child");
                (node, 0)
            }
            WideChild::Leaf { block, count } => {
                assert_ne!(count, 0, "a leaf holds at least one triangle");
                (block, count)
            }
            WideChild::Empty => (0, 0),
        };
        let (lo, hi) = match child {
            WideChild::Empty => ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]),
            _ => (lo, hi),
        };
        for a in 0..3 {
            (self.lo[a][c], self.hi[a][c]) = (lo[a], hi[a]);
        }
    }

    /// The children's box planes as six rows: `lo[0..3]` then `hi[0..3]` (row `a`: the low
    /// planes of axis `a`; row `3 + a`: its high planes), so that a traversal picks a ray's near
    /// and far planes by a row index computed once per ray rather than by a choice per node.
    #[inline(always)]
    pub fn planes(&self) -> &[[f32; W]; 6] {
        // SAFETY: `repr(C)`: `hi` directly follows `lo` (both `[[f32; W]; 3]`, f32-aligned, so
        // no padding between them), and six rows of `[f32; W]` are exactly their bytes.
        unsafe { &*(self.lo.as_ptr() as *const [[f32; W]; 6]) }
    }

    /// Bit `c` set when slot `c` holds a child.
    #[inline(always)]
    pub fn used(&self) -> u32 {
        let mut used = 0;
        for c in 0..W {
            used |= u32::from(self.first[c] | self.count[c] != 0) << c;
        }
        used
    }

    /// Child `c`'s box as `(lo, hi)`.
    #[inline(always)]
    pub fn child_box(&self, c: usize) -> ([f32; 3], [f32; 3]) {
        (
            [self.lo[0][c], self.lo[1][c], self.lo[2][c]],
            [self.hi[0][c], self.hi[1][c], self.hi[2][c]],
        )
    }
}

/// Where a binary node's subtree is in the wide tree: child slots `slots` (bit `c`: slot `c`) of
/// wide node `node`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WideEntry {
    pub node: u32,
    pub slots: u32,
}

/// The wide tree over a binary `Bvh`'s leaves. Node 0 is the root; an empty binary tree gives an
/// empty wide tree (no nodes).
#[derive(Clone, Debug)]
pub struct WideBvh<const W: usize> {
    pub nodes: Vec<WideNode<W>>,
    /// Depth of each wide node (root 0), for the per-depth counters.
    pub depth: Vec<u8>,
    /// Indexed like the binary tree's nodes: where each one's subtree is (`WideEntry`). A binary
    /// node a wide node was made from (the root among them) is all of that node's slots, so its
    /// box is not tested again; any other is the slots it was opened into, or its own slot.
    pub entry: Vec<WideEntry>,
    /// The leaves' triangles, four to a block, each leaf's run of blocks starting a new block.
    pub blocks: Vec<TriangleBlock>,
    /// Each block's first triangle in the binary tree's `triangles`: where the tracers that read
    /// a leaf's triangles one at a time find its range (`triangles`), 4 bytes a block beside the
    /// 160-byte blocks they never load.
    first_triangle: Vec<u32>,
}

impl<const W: usize> WideBvh<W> {
    const WIDTH_OK: () = assert!(W >= 2 && W <= 32, "a wide node has 2 to 32 children");

    pub fn collapse(bvh: &Bvh) -> Self {
        let () = Self::WIDTH_OK;
        let mut wide = WideBvh {
            nodes: Vec::new(),
            depth: Vec::new(),
            entry: vec![WideEntry::default(); bvh.nodes.len()],
            blocks: Vec::new(),
            first_triangle: Vec::new(),
        };
        if bvh.is_empty() {
            return wide;
        }
        wide.nodes.push(WideNode::EMPTY);
        wide.depth.push(0);
        // (wide node to fill, the binary node it is made from)
        let mut pending = vec![(0usize, Bvh::ROOT)];
        while let Some((index, root)) = pending.pop() {
            let children = wide_children::<W>(bvh, root);
            enter_subtree(bvh, root, &children, index as u32, &mut wide.entry);
            let mut node = WideNode::EMPTY;
            for (c, &b) in children.iter().enumerate() {
                let binary = &bvh.nodes[b];
                let child = if binary.is_leaf() {
                    WideChild::Leaf {
                        block: wide.add_blocks(bvh, binary.first, binary.count),
                        count: binary.count,
                    }
                } else {
                    // Never 0: the root was pushed first.
                    let child = wide.nodes.len();
                    wide.nodes.push(WideNode::EMPTY);
                    wide.depth.push(wide.depth[index] + 1);
                    pending.push((child, b));
                    WideChild::Node(child as u32)
                };
                let bounds = binary.bounds;
                node.set_child(c, child, bounds.min.into(), bounds.max.into());
            }
            wide.nodes[index] = node;
        }
        wide
    }

    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The range of the binary tree's `triangles` that the leaf of `count` triangles in blocks
    /// from `block` holds.
    #[inline(always)]
    pub fn triangles(&self, block: u32, count: u32) -> Range<usize> {
        let first = self.first_triangle[block as usize] as usize;
        first..first + count as usize
    }

    /// Appends the blocks of `bvh`'s triangles `first .. first + count`; returns the first's index.
    fn add_blocks(&mut self, bvh: &Bvh, first: u32, count: u32) -> u32 {
        let at = self.blocks.len() as u32;
        let range = first as usize..(first + count) as usize;
        let (tris, prims) = (&bvh.triangles[range.clone()], &bvh.prim_ids[range]);
        for (i, (tris, prims)) in tris.chunks(BLOCK).zip(prims.chunks(BLOCK)).enumerate() {
            let index = first + (i * BLOCK) as u32;
            self.blocks.push(TriangleBlock::new(tris, prims));
            self.first_triangle.push(index);
        }
        at
    }
}

/// Records the entry of binary node `b` and of every binary node between it and the wide node
/// `node`'s `children` (the binary nodes in its slots) into `entry`; returns `b`'s slots.
fn enter_subtree(
    bvh: &Bvh,
    b: usize,
    children: &[usize],
    node: u32,
    entry: &mut [WideEntry],
) -> u32 {
    let slots = match children.iter().position(|&c| c == b) {
        Some(c) => 1 << c,
        None => {
            let first = bvh.nodes[b].first as usize;
            enter_subtree(bvh, first, children, node, entry)
                | enter_subtree(bvh, first + 1, children, node, entry)
        }
    };
    entry[b] = WideEntry { node, slots };
    slots
}

/// The binary nodes that become the children of the wide node made from binary node `root`: its
/// two children, then greedily the interior one of largest surface area replaced by its two
/// children until there are `W` or no interior one is left. A binary leaf at the root (a tree of
/// one leaf) is the wide root's only child.
fn wide_children<const W: usize>(bvh: &Bvh, root: usize) -> Vec<usize> {
    let node = &bvh.nodes[root];
    if node.is_leaf() {
        return vec![root];
    }
    let mut children = vec![node.first as usize, node.first as usize + 1];
    while children.len() < W {
        let largest = children
            .iter()
            .enumerate()
            .filter(|(_, &c)| !bvh.nodes[c].is_leaf())
            .max_by(|(_, &a), (_, &b)| {
                let area = |i: usize| bvh.nodes[i].bounds.surface_area();
                area(a).total_cmp(&area(b))
            })
            .map(|(slot, _)| slot);
        let Some(slot) = largest else { break };
        let split = children.swap_remove(slot);
        let first = bvh.nodes[split].first as usize;
        children.extend([first, first + 1]);
    }
    children
}

/// `n` evenly spaced one-triangle leaves along x (no presplitting); for `n = 8` SAH splits them
/// 4|4, 2|2, 1|1, a balanced binary tree that collapses into one 8-wide node. For tests of wide
/// nodes.
#[cfg(test)]
pub(crate) fn spaced_leaves(n: usize) -> Bvh {
    use crate::accel::BvhConfig;
    use crate::geometry::Triangle;
    use glam::Vec3;
    let tris: Vec<Triangle> = (0..n)
        .map(|i| {
            let p = Vec3::new(i as f32 * 10.0, 0.0, 0.0);
            Triangle::new(p, p + Vec3::X, p + Vec3::Y)
        })
        .collect();
    let config = BvhConfig {
        max_leaf_size: 1,
        presplit: 0.0,
        spatial: 0.0,
        ..BvhConfig::default()
    };
    Bvh::build(&tris, config)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::accel::BvhConfig;
    use crate::geometry::{Aabb, Triangle};
    use crate::random::SplitMix64;

    fn random_triangles(n: usize) -> Vec<Triangle> {
        let mut rng = SplitMix64::new(3);
        (0..n)
            .map(|_| {
                let p = rng.vec3(0.0, 10.0);
                Triangle::new(p, p + rng.vec3(0.0, 0.5), p + rng.vec3(0.0, 0.5))
            })
            .collect()
    }

    /// The box of everything below child slot `c` of `node`, and the leaf ranges reached.
    fn subtree<const W: usize>(
        wide: &WideBvh<W>,
        bvh: &Bvh,
        child: WideChild,
        ranges: &mut Vec<(u32, u32)>,
    ) -> Aabb {
        match child {
            WideChild::Empty => Aabb::EMPTY,
            WideChild::Leaf { block, count } => {
                let first = wide.triangles(block, count).start as u32;
                ranges.push((first, count));
                // Its blocks hold its triangles, in order, with their ids.
                for (i, t) in wide.triangles(block, count).enumerate() {
                    let b = &wide.blocks[block as usize + i / BLOCK];
                    assert_eq!(b.triangle(i % BLOCK), bvh.triangles[t]);
                    assert_eq!(b.prim[i % BLOCK], bvh.prim_ids[t]);
                }
                // The binary leaf's box: with early split clipping or spatial splits a triangle may
                // stick out of it (only its clipped piece is inside), so the triangles' own boxes
                // are checked only on unsplit trees.
                let leaf = bvh
                    .nodes
                    .iter()
                    .find(|n| n.is_leaf() && (n.first, n.count) == (first, count))
                    .expect("a binary leaf");
                if bvh.config.presplit == 0.0 && bvh.config.spatial == 0.0 {
                    for i in first..first + count {
                        assert!(leaf.bounds.contains(&bvh.triangles[i as usize].bounds()));
                    }
                }
                leaf.bounds
            }
            WideChild::Node(n) => {
                let node = &wide.nodes[n as usize];
                let mut total = Aabb::EMPTY;
                for c in 0..W {
                    let inner = subtree(wide, bvh, node.child(c), ranges);
                    if node.child(c) != WideChild::Empty {
                        let (lo, hi) = node.child_box(c);
                        let b = Aabb::new(Vec3::from(lo), Vec3::from(hi));
                        assert!(b.contains(&inner), "a child box misses part of its subtree");
                        if let WideChild::Node(m) = node.child(c) {
                            assert_eq!(wide.depth[m as usize], wide.depth[n as usize] + 1);
                        }
                        total = total.union(b);
                    }
                }
                total
            }
        }
    }

    fn binary_leaves(bvh: &Bvh, b: usize, ranges: &mut Vec<(u32, u32)>) {
        let node = &bvh.nodes[b];
        if node.is_leaf() {
            ranges.push((node.first, node.count));
        } else {
            binary_leaves(bvh, node.first as usize, ranges);
            binary_leaves(bvh, node.first as usize + 1, ranges);
        }
    }

    fn check<const W: usize>(bvh: &Bvh) {
        let wide = WideBvh::<W>::collapse(bvh);
        let mut ranges = Vec::new();
        subtree(&wide, bvh, WideChild::Node(0), &mut ranges);
        // Exactly the binary tree's leaves, each reached once: every triangle reference once.
        let mut binary: Vec<(u32, u32)> = bvh
            .nodes
            .iter()
            .filter(|n| n.is_leaf())
            .map(|n| (n.first, n.count))
            .collect();
        ranges.sort_unstable();
        binary.sort_unstable();
        assert_eq!(ranges, binary, "W = {W}");
        // Every binary node's entry reaches exactly the leaves below it.
        for b in 0..bvh.nodes.len() {
            let WideEntry { node, slots } = wide.entry[b];
            let mut reached = Vec::new();
            for c in (0..W).filter(|&c| slots & (1 << c) != 0) {
                subtree(&wide, bvh, wide.nodes[node as usize].child(c), &mut reached);
            }
            let mut below = Vec::new();
            binary_leaves(bvh, b, &mut below);
            reached.sort_unstable();
            below.sort_unstable();
            assert_eq!(reached, below, "W = {W}, binary node {b}");
        }
        let root = wide.entry[Bvh::ROOT];
        assert_eq!((root.node, root.slots), (0, wide.nodes[0].used()));
        let refs: u32 = ranges.iter().map(|r| r.1).sum();
        assert_eq!(refs as usize, bvh.triangles.len());
        // A node is full unless every child is a leaf (nothing left to open).
        for node in &wide.nodes {
            let used = node.used().count_ones() as usize;
            let interior = (0..W).any(|c| matches!(node.child(c), WideChild::Node(_)));
            assert!((2..=W).contains(&used), "W = {W}: {used} children");
            assert!(
                used == W || !interior,
                "W = {W}: a partial node with interior children"
            );
            // Unused slots hold the empty box.
            for c in (0..W).filter(|&c| node.used() & (1 << c) == 0) {
                let (lo, hi) = node.child_box(c);
                assert!(lo.iter().all(|&x| x == f32::INFINITY));
                assert!(hi.iter().all(|&x| x == f32::NEG_INFINITY));
            }
        }
    }

    #[test]
    fn wide_trees_nest_and_reach_every_leaf_once() {
        let tris = random_triangles(4000);
        for config in [
            BvhConfig::default(),
            BvhConfig {
                max_leaf_size: 1,
                presplit: 0.0,
                spatial: 0.0,
                ..BvhConfig::default()
            },
        ] {
            let bvh = Bvh::build(&tris, config);
            check::<4>(&bvh);
            check::<8>(&bvh);
        }
    }

    /// Every kind of child, at the ends of its ranges, reads back as written, in every slot, and
    /// leaves the other slots alone; an empty slot gets the empty box whatever box is passed.
    #[test]
    fn every_child_kind_round_trips_through_the_compact_node() {
        let kinds = [
            WideChild::Node(1),
            WideChild::Node(u32::MAX),
            WideChild::Leaf { block: 0, count: 1 },
            WideChild::Leaf {
                block: 7,
                count: BvhConfig::default().max_leaf_size as u32,
            },
            // Beyond any u8 or u16 count: a leaf cut at `max_depth` may hold this many.
            WideChild::Leaf {
                block: u32::MAX - 70_000,
                count: 70_000,
            },
            WideChild::Empty,
        ];
        let (lo, hi) = ([1.0, -2.0, 3.0], [4.0, 5.0, 6.5]);
        for kind in kinds {
            for c in 0..8 {
                let mut node = WideNode::<8>::EMPTY;
                node.set_child(c, kind, lo, hi);
                assert_eq!(node.child(c), kind);
                let used = if kind == WideChild::Empty { 0 } else { 1 << c };
                assert_eq!(node.used(), used);
                let want = if kind == WideChild::Empty {
                    ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3])
                } else {
                    (lo, hi)
                };
                assert_eq!(node.child_box(c), want);
                for other in (0..8).filter(|&o| o != c) {
                    assert_eq!(node.child(other), WideChild::Empty);
                }
            }
        }
        // A full node of mixed kinds keeps each one.
        let mut node = WideNode::<4>::EMPTY;
        for (c, kind) in kinds[..4].iter().enumerate() {
            node.set_child(c, *kind, lo, hi);
        }
        assert_eq!(node.used(), 0b1111);
        assert_eq!(
            (0..4).map(|c| node.child(c)).collect::<Vec<_>>(),
            kinds[..4]
        );
    }

    #[test]
    #[should_panic(expected = "the root is nobody's child")]
    fn the_root_is_refused_as_a_child() {
        let mut node = WideNode::<4>::EMPTY;
        node.set_child(0, WideChild::Node(0), [0.0; 3], [1.0; 3]);
    }

    /// Leaves cut at `max_depth` far beyond `max_leaf_size` (and beyond 255 triangles) keep their
    /// whole counts through the collapse.
    #[test]
    fn leaves_cut_at_max_depth_keep_their_counts() {
        let tris = random_triangles(4000);
        let config = BvhConfig {
            max_depth: 3,
            presplit: 0.0,
            spatial: 0.0,
            ..BvhConfig::default()
        };
        let bvh = Bvh::build(&tris, config);
        let largest = bvh.nodes.iter().map(|n| n.count).max().unwrap();
        assert!(largest > 255, "{largest}");
        check::<4>(&bvh);
        check::<8>(&bvh);
        let eight = WideBvh::<8>::collapse(&bvh);
        assert_eq!(
            eight.nodes.len(),
            1,
            "a depth-3 tree of 8 leaves is one 8-wide node"
        );
        let counts: u32 = (0..8)
            .map(|c| match eight.nodes[0].child(c) {
                WideChild::Leaf { count, .. } => count,
                other => panic!("slot {c}: {other:?}"),
            })
            .sum();
        assert_eq!(counts, 4000);
    }

    #[test]
    fn a_complete_binary_tree_of_eight_leaves_collapses_by_hand_count() {
        // Eight evenly spaced single-triangle leaves: SAH splits them 4|4, 2|2, 1|1, a balanced
        // binary tree of 7 interior nodes. 8-wide: one node of all 8 leaves. 4-wide: the root
        // opens both halves into their four quarters, each a node of 2 leaves: 5 nodes.
        let bvh = spaced_leaves(8);
        assert_eq!(bvh.leaf_count(), 8);
        assert_eq!(bvh.nodes.len(), 15);
        let eight = WideBvh::<8>::collapse(&bvh);
        assert_eq!(eight.nodes.len(), 1);
        // Every binary node enters the one wide node: the root all 8 slots, each half 4.
        assert!(eight.entry.iter().all(|e| e.node == 0));
        let halves = [bvh.nodes[0].first as usize, bvh.nodes[0].first as usize + 1];
        let slots = halves.map(|h| eight.entry[h].slots);
        assert_eq!(slots.map(u32::count_ones), [4, 4]);
        assert_eq!(slots[0] | slots[1], 0xff);
        assert_eq!(eight.nodes[0].used().count_ones(), 8);
        let four = WideBvh::<4>::collapse(&bvh);
        assert_eq!(four.nodes.len(), 5);
        assert_eq!(four.nodes[0].used().count_ones(), 4);
        assert!(four.nodes[1..].iter().all(|n| n.used().count_ones() == 2));
        let two = WideBvh::<2>::collapse(&bvh);
        assert_eq!(two.nodes.len(), 7, "a 2-wide collapse is the binary tree");
        // A single triangle: one leaf under the root.
        let one = spaced_leaves(1);
        let wide = WideBvh::<4>::collapse(&one);
        assert_eq!(wide.nodes.len(), 1);
        assert_eq!(
            wide.nodes[0].child(0),
            WideChild::Leaf { block: 0, count: 1 }
        );
        assert!(WideBvh::<4>::collapse(&spaced_leaves(0)).is_empty());
    }
}
