//! The obvhs baseline structure: obvhs 0.4's compressed 8-wide BVH (CWBVH, Ylitie et al. 2017)
//! built by obvhs's own triangle builder, `build_cwbvh_from_tris`: PLOC clustering (Meister &
//! Bittner 2018), then reinsertion (Meister & Bittner 2022), then collapse to 8-wide nodes.
//!
//! Its build presets are the structure parameter `quality`. The default is `medium_build`: the
//! preset obvhs itself uses in its crate-level example and its `basic_cwbvh` and
//! `cornell_box_cwbvh` examples, and the one it describes as "around the same build time as embree but with faster
//! traversal" — the fair point to set against our Embree baseline. obvhs is built without its
//! `parallel` feature, so every preset builds on one thread.

use std::time::{Duration, Instant};

use ::obvhs::cwbvh::builder::build_cwbvh_from_tris;
use ::obvhs::cwbvh::CwBvh;
use ::obvhs::BvhBuildParams;
use glam::Vec3A;

use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::params::Params;

/// obvhs's `BvhBuildParams` presets, from cheapest build to best tree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum ObvhsQuality {
    FastestBuild,
    VeryFastBuild,
    FastBuild,
    #[default]
    MediumBuild,
    SlowBuild,
    VerySlowBuild,
}

impl ObvhsQuality {
    pub const ALL: [ObvhsQuality; 6] = [
        ObvhsQuality::FastestBuild,
        ObvhsQuality::VeryFastBuild,
        ObvhsQuality::FastBuild,
        ObvhsQuality::MediumBuild,
        ObvhsQuality::SlowBuild,
        ObvhsQuality::VerySlowBuild,
    ];
    pub const PARAMS: &'static [&'static str] = &["quality"];

    /// The preset's name in obvhs (`BvhBuildParams::<name>()`), which is also the parameter value.
    pub fn name(self) -> &'static str {
        match self {
            ObvhsQuality::FastestBuild => "fastest_build",
            ObvhsQuality::VeryFastBuild => "very_fast_build",
            ObvhsQuality::FastBuild => "fast_build",
            ObvhsQuality::MediumBuild => "medium_build",
            ObvhsQuality::SlowBuild => "slow_build",
            ObvhsQuality::VerySlowBuild => "very_slow_build",
        }
    }

    pub fn build_params(self) -> BvhBuildParams {
        match self {
            ObvhsQuality::FastestBuild => BvhBuildParams::fastest_build(),
            ObvhsQuality::VeryFastBuild => BvhBuildParams::very_fast_build(),
            ObvhsQuality::FastBuild => BvhBuildParams::fast_build(),
            ObvhsQuality::MediumBuild => BvhBuildParams::medium_build(),
            ObvhsQuality::SlowBuild => BvhBuildParams::slow_build(),
            ObvhsQuality::VerySlowBuild => BvhBuildParams::very_slow_build(),
        }
    }

    pub fn from_params(p: &Params) -> Result<Self> {
        let Some(value) = p.0.get("quality") else {
            return Ok(ObvhsQuality::default());
        };
        Self::ALL
            .into_iter()
            .find(|q| q.name() == value)
            .ok_or_else(|| {
                let known: Vec<&str> = Self::ALL.iter().map(|q| q.name()).collect();
                Error::usage(format!(
                    "parameter quality = {value:?} is not an obvhs preset (known: {})",
                    known.join(", ")
                ))
            })
    }
}

/// obvhs's traversal keeps a 32-entry stack of node groups and, when full, overwrites its last
/// slot (`faststack::StackStack::push`), silently dropping a subtree. Reaching an internal node at
/// depth `d` (root 0) pushes at most one group per level, so trees whose internal nodes are at
/// most this deep are traversed exactly; deeper ones are refused at build time.
pub const MAX_TRAVERSABLE_DEPTH: usize = 31;

#[derive(Clone, Debug)]
pub struct ObvhsBvh {
    pub cwbvh: CwBvh,
    /// `triangles[i]` is scene triangle `cwbvh.primitive_indices[i]`: obvhs's traversal hands out
    /// indices into `primitive_indices`, so the triangles are stored in that order. With spatial
    /// pre-splits (`slow_build`, `very_slow_build`) a triangle may appear more than once.
    pub triangles: Vec<Triangle>,
    /// Depth of each CWBVH node (root 0), for the per-depth counters.
    pub node_depth: Vec<u8>,
    pub quality: ObvhsQuality,
    /// Wall time of `build`: conversion to obvhs triangles, obvhs's builder, reordering.
    pub build_seconds: f64,
}

impl ObvhsBvh {
    pub fn build(triangles: &[Triangle], quality: ObvhsQuality) -> Result<ObvhsBvh> {
        let start = Instant::now();
        // obvhs's builder divides by the triangle count (pre-split average area) and cannot build
        // an empty tree; the default CwBvh has no nodes, which its traversal treats as all-miss.
        let cwbvh = if triangles.is_empty() {
            CwBvh::default()
        } else {
            let theirs: Vec<::obvhs::triangle::Triangle> = triangles
                .iter()
                .map(|t| ::obvhs::triangle::Triangle {
                    v0: Vec3A::from(t.v[0]),
                    v1: Vec3A::from(t.v[1]),
                    v2: Vec3A::from(t.v[2]),
                })
                .collect();
            build_cwbvh_from_tris(&theirs, quality.build_params(), &mut Duration::default())
        };
        let ordered = cwbvh
            .primitive_indices
            .iter()
            .map(|&i| triangles[i as usize])
            .collect();
        let node_depth = node_depths(&cwbvh)?;
        Ok(ObvhsBvh {
            cwbvh,
            triangles: ordered,
            node_depth,
            quality,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    pub fn is_empty(&self) -> bool {
        self.cwbvh.nodes.is_empty()
    }

    pub fn max_depth(&self) -> usize {
        self.node_depth.iter().copied().max().unwrap_or(0) as usize
    }
}

/// Depth of every node, walking down from the root; fails when the tree is too deep for obvhs's
/// traversal stack.
fn node_depths(bvh: &CwBvh) -> Result<Vec<u8>> {
    let mut depth = vec![0u8; bvh.nodes.len()];
    let mut pending = if bvh.nodes.is_empty() {
        vec![]
    } else {
        vec![0usize]
    };
    while let Some(index) = pending.pop() {
        let node = &bvh.nodes[index];
        if depth[index] as usize > MAX_TRAVERSABLE_DEPTH {
            return Err(Error::runtime(format!(
                "obvhs built a CWBVH deeper than {MAX_TRAVERSABLE_DEPTH} levels, more than its \
                 traversal stack holds; the scene's geometry is likely degenerate"
            )));
        }
        for slot in (0..8).filter(|&s| !node.is_child_empty(s) && !node.is_leaf(s)) {
            let child = node.child_node_index(slot) as usize;
            depth[child] = depth[index] + 1;
            pending.push(child);
        }
    }
    Ok(depth)
}
