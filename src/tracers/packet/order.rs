//! Front-to-back child order for a packet (Overbeck et al. 2008, Fig. 2 `nearChild(R)` /
//! `farChild(R)`, which the paper leaves open). Our BVH does not store split planes, so each
//! interior node gets the axis along which its children's centres lie farthest apart; a packet
//! visits first the child whose centre is lower on that axis when the packet's summed direction
//! is positive along it, else the other. One byte per node, computed once per tracer.

use crate::accel::Bvh;

pub struct ChildOrder {
    /// Per node: split axis in bits 0–1, bit 2 set when the left child's centre is the lower.
    code: Vec<u8>,
}

impl ChildOrder {
    pub fn new(bvh: &Bvh) -> Self {
        let code = bvh
            .nodes
            .iter()
            .map(|n| {
                // An empty tree's root is neither leaf nor parent: it has no children to order.
                if n.is_leaf() || bvh.is_empty() {
                    return 0;
                }
                let (l, r) = (
                    bvh.nodes[n.first as usize].bounds.center(),
                    bvh.nodes[n.first as usize + 1].bounds.center(),
                );
                let gap = r - l;
                let axis = gap.abs().max_position();
                axis as u8 | (((gap[axis] >= 0.0) as u8) << 2)
            })
            .collect();
        ChildOrder { code }
    }

    /// `(near, far)` children of interior node `node` whose first child is `first`, for a packet
    /// whose summed direction has the sign bits `negative`.
    #[inline(always)]
    pub fn near_far(&self, node: usize, first: u32, negative: [bool; 3]) -> (u32, u32) {
        let c = self.code[node];
        let left_low = c & 4 != 0;
        if left_low != negative[(c & 3) as usize] {
            (first, first + 1)
        } else {
            (first + 1, first)
        }
    }
}
