//! The multi-frusta walk over a `W`-wide BVH (`width` = 4 or 8; our addition, not the paper's):
//! at a wide node all frusta of the mask it was entered with meet its `W` child boxes, four per
//! `Frusta::box_masks` call, where the binary walk needs `W − 1` calls of two boxes; the nearest
//! child entered is visited next and the others are pushed far to near. The leaves are the binary
//! tree's (`WideBvh::collapse`), so the leaf stage is unchanged.
//!
//! A walk position is a child slot, `1 + W · node + slot` (its box and reference are in the parent
//! node's lanes, and a leaf's box is needed by the leaf stage), or 0 for the root node.

use glam::Vec3;

use crate::accel::{WideBvh, WideChild};
use crate::geometry::Aabb;
use crate::stats::Stats;
use crate::tracers::multi_frusta::descend::{count_child_tests, depth, FrustumTree, Leaf, Step};
use crate::tracers::multi_frusta::frusta::{Frusta, Margins};

/// The walk position of `node`'s child slot `slot`.
#[inline(always)]
fn position<const W: usize>(node: u32, slot: usize) -> u32 {
    1 + node * W as u32 + slot as u32
}

impl<const W: usize> FrustumTree for WideBvh<W> {
    const ROOT: u32 = 0;

    #[inline(always)]
    fn open<S: Stats>(&self, at: u32) -> Step {
        let depth = |node: u32| depth::<S>(&self.depth, node);
        if at == Self::ROOT {
            return Step::Inner {
                node: 0,
                depth: depth(0),
            };
        }
        let (parent, slot) = ((at - 1) as usize / W, (at - 1) as usize % W);
        let node = &self.nodes[parent];
        match node.child(slot) {
            WideChild::Node(child) => Step::Inner {
                node: child,
                depth: depth(child),
            },
            WideChild::Leaf { block, count } => {
                let (lo, hi) = node.child_box(slot);
                Step::Leaf(Leaf {
                    first: self.triangles(block, count).start as u32,
                    count,
                    bounds: Aabb {
                        min: lo.into(),
                        max: hi.into(),
                    },
                    depth: depth(parent as u32) + S::ENABLED as usize,
                })
            }
            WideChild::Empty => unreachable!("an empty slot is never entered"),
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
        let wide = &self.nodes[node as usize];
        let boxes: [Aabb; W] = std::array::from_fn(|c| {
            let (lo, hi) = wide.child_box(c);
            Aabb {
                min: lo.into(),
                max: hi.into(),
            }
        });
        const {
            assert!(
                W.is_multiple_of(4),
                "the frusta walk wide trees of 4 or 8 children"
            )
        };
        // Four boxes per `box_masks` call: eight at once keep 48 running-bound vectors live, more
        // than AVX-512's 32 registers, and the spills made width 8 8–11 % slower (same-run
        // sanity A/B, loaded machine).
        let mut masks = [0u64; W];
        for base in (0..W).step_by(4) {
            let chunk: [&Aabb; 4] = std::array::from_fn(|i| &boxes[base + i]);
            masks[base..base + 4].copy_from_slice(&frusta.box_masks(chunk, mask, margins));
        }
        let used = wide.used();
        // The children entered, nearest first along `towards` (by twice their centres; ties in
        // slot order, as the binary walk takes its first child on a tie).
        let mut entered = [(0.0f32, 0u32, 0u64); W];
        let mut len = 0;
        for (c, &child_mask) in masks.iter().enumerate() {
            // An unused slot's empty box is never entered; the mask says so whatever the
            // arithmetic on its infinities gave.
            if used & 1 << c == 0 || child_mask == 0 {
                continue;
            }
            let key = (boxes[c].min + boxes[c].max).dot(towards);
            let mut i = len;
            while i > 0 && entered[i - 1].0 > key {
                entered[i] = entered[i - 1];
                i -= 1;
            }
            entered[i] = (key, position::<W>(node, c), child_mask);
            len += 1;
        }
        if S::ENABLED {
            let depth = self.depth[node as usize] as usize + 1;
            count_child_tests(stats, mask, used.count_ones() as u64, len as u64, depth);
        }
        let (&(_, nearest, nearest_mask), others) = entered[..len].split_first()?;
        // The nearest is visited next without the stack; the others wait on it, nearer on top.
        stack.extend(others.iter().rev().map(|&(_, at, m)| (at, m)));
        Some((nearest, nearest_mask))
    }
}
