//! Stream filtering (Gribble and Ramani 2008, "Coherent Ray Tracing via Stream Filtering") over
//! the binary SAH BVH.
//!
//! - **Streams** (`stream` = S rays, or `frame` for the whole work chunk): the chunk is cut into
//!   streams of S consecutive rays (camera rays come in Morton-ordered 32×32 tiles, so S = 1024
//!   is the paper's 32×32 initial stream and 4096 its 64×64). A stream is one 32-byte record
//!   per ray (what the box filter reads) with the ray's slot, partitioned in place as it goes
//!   (§3.1 "Memory management"); the slot holds what only the intersection stage reads and the
//!   ray's index (`rays`).
//!   Explicit packets of the batch (packet assembly) play no part: streams need no packets.
//! - **SIMD width** (`width` = N ∈ 4, 8, 12, 16, 32, 64): N rays per test (§4). 4, 8 and 16 are
//!   the lane layer's widths; 12 uses 12 of 16 lanes; 32 and 64 are 2 or 4 16-lane groups
//!   processed as one (`width`).
//! - **Traversal** (§3.2, Fig. 3, `traverse`): at each node a box filter (`filter`) tests the
//!   stream N rays at a time and partitions it in place; the rays that meet the box go on to the
//!   leaf's intersection stage (`intersect`) or to both children, front to back by the
//!   sub-stream's dominant direction (the sign most of its rays have along the node's split
//!   axis; the split axis as the packet tracer's `ChildOrder` finds it).
//! - **Single-ray hand-off** (`single` = T, 0 by default): a sub-stream of at most T rays at an
//!   inner node leaves stream filtering, and each of its rays finishes the subtree depth first on
//!   its own: by the reference tracer's traversal of the binary tree (`single_tree` = 2, the
//!   default) or by single rays through the tree collapsed to 4 or 8 children per node
//!   (`single_tree` = 4 | 8: `wide_single`, one SIMD slab test of all children; the wide tree is
//!   built with the tracer, as the packet tracer's are; `handoff`, which reads each ray from the
//!   stream's own records where the filters left it, not from the chunk's columns). Not in the
//!   paper: deep in the tree the sub-streams are a few rays long (Table 4), and a box filter over
//!   them costs more than the rays' own traversal. T = 0 is the paper's stream filtering to the
//!   leaves; the lane counters count the filters only, so with T > 0 they describe the stream
//!   part of the traversal.
//! - **Exact hits**: every lane runs the reference tracer's slab and watertight tests bit for
//!   bit (with `robust = false` its plain slabs and Möller–Trumbore), so each ray gets the
//!   reference's closest hit (up to the order in which triangles at exactly equal distance are
//!   met). Occlusion rays end at their first hit and leave the stream.
//!   Rays that can hit nothing (NaN, zero direction, `tmin > tmax`) miss: `tmin > tmax` fails
//!   the root's filter, and a NaN passes slabs as in the reference tracer but no triangle.
//!
//! Counters: `ray` per ray; `node(depth)` per node a stream is filtered at; `aabb_test(depth)`
//! per ray in a box filter's stream; `triangle_test(depth)` per live ray tested against a
//! triangle. Events (Tables 2–4): `StreamBoxTests` per box filter, `TraversalLanesActive` /
//! `TraversalLanesIssued` (rays in the box filters' streams / whole N-wide groups: traversal's
//! SIMD utilisation; active ÷ box tests = mean stream length), `IntersectionLanesActive` /
//! `IntersectionLanesIssued` (live rays / N per group and triangle: intersection's utilisation),
//! `LeavesVisited` and `LeafActiveRays` (leaf streams and their rays: mean intersection stream
//! length).

mod filter;
mod handoff;
mod intersect;
mod rays;
mod traverse;
mod width;

use std::marker::PhantomData;
use std::str::FromStr;
use std::sync::Arc;

use crate::accel::{Bvh, BvhOfWidth, WideNodes};
use crate::error::{Error, Result};
use crate::geometry::robustness::robust_param;
use crate::geometry::{Fast, Hit, Rays, Robust};
use crate::lanes::triangle_block::BlockTests;
use crate::lanes::{with_width, SimdRay};
use crate::params::Params;
use crate::stats::Stats;
use crate::tracers::kernel::Kernel;
use crate::tracers::packet::{ChildOrder, PacketConfig, TreeWidth};

use handoff::Handoff;
use rays::StreamRays;
use traverse::{Answer, Walk};
use width::Width;

/// Rays per initial stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StreamSize {
    /// Streams of this many consecutive rays (≥ 1).
    Rays(usize),
    /// The whole work chunk as one stream.
    Frame,
}

impl FromStr for StreamSize {
    type Err = ();
    fn from_str(s: &str) -> std::result::Result<Self, ()> {
        match s {
            "frame" => Ok(StreamSize::Frame),
            _ => match s.parse() {
                Ok(n) if n > 0 => Ok(StreamSize::Rays(n)),
                _ => Err(()),
            },
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamConfig {
    pub stream: StreamSize,
    /// SIMD width N: rays per box or triangle test.
    pub width: usize,
    /// Sub-streams of at most this many rays finish their subtree one ray at a time, depth
    /// first (0: never — the paper's stream filtering all the way to the leaves).
    pub single: usize,
    /// Children per node of the tree the hand-off's single rays walk (2: the binary tree, by the
    /// reference's traversal; 4 or 8: a wide tree collapsed from it, by `wide_single`).
    pub single_tree: TreeWidth,
    /// The tests every lane and hand-off ray runs (`robust`, set by the registry;
    /// `geometry::robustness`).
    pub robust: bool,
}

impl Default for StreamConfig {
    fn default() -> Self {
        StreamConfig {
            stream: StreamSize::Rays(4096),
            width: 16,
            single: 0,
            single_tree: TreeWidth::Binary,
            robust: true,
        }
    }
}

impl StreamConfig {
    pub const PARAMS: &'static [&'static str] = &["stream", "width", "single", "single_tree"];
    pub const WIDTHS: [usize; 6] = [4, 8, 12, 16, 32, 64];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = StreamConfig::default();
        let c = StreamConfig {
            stream: p.get_or("stream", d.stream).map_err(|_| {
                Error::usage(format!(
                    "stream tracer: stream must be a number of rays ≥ 1 or \"frame\" (got {:?})",
                    p.0.get("stream").map_or("", String::as_str)
                ))
            })?,
            width: p.get_or("width", d.width)?,
            single: p.get_or("single", d.single)?,
            single_tree: TreeWidth::of(p.get_or("single_tree", 2usize)?).map_err(|_| {
                Error::usage(format!(
                    "stream tracer: single_tree must be one of {:?} (children per node of the hand-off's tree)",
                    PacketConfig::WIDTHS
                ))
            })?,
            robust: robust_param(p)?,
        };
        if !Self::WIDTHS.contains(&c.width) {
            return Err(Error::usage(format!(
                "stream tracer: width must be one of {:?} (got {})",
                Self::WIDTHS,
                c.width
            )));
        }
        Ok(c)
    }
}

pub struct StreamTracer {
    bvh: Arc<Bvh>,
    order: ChildOrder,
    handoff: Handoff,
    config: StreamConfig,
}

impl StreamTracer {
    /// Over `tree`: the binary BVH, or the wide tree the run built for the hand-off's
    /// `single_tree`, which the hand-off then walks.
    pub fn new(tree: impl Into<BvhOfWidth>, config: StreamConfig) -> Self {
        let tree = tree.into();
        debug_assert!(
            config.single == 0
                || tree.wide().map_or(2, WideNodes::children) == config.single_tree.children(),
            "the tree of the configured hand-off width"
        );
        let handoff = Handoff::new(&tree, config.single);
        let bvh = tree.bvh().clone();
        let order = ChildOrder::new(&bvh);
        StreamTracer {
            bvh,
            order,
            handoff,
            config,
        }
    }

    /// The tracer over a static `tree` (it has no motion blur).
    pub fn over_static(tree: impl Into<BvhOfWidth>, config: StreamConfig) -> Result<Self> {
        let tree = tree.into();
        if tree.bvh().motion_end.is_some() {
            return Err(Error::usage(
                "stream tracer: no motion blur (a moving BVH was given)",
            ));
        }
        Ok(Self::new(tree, config))
    }

    pub fn config(&self) -> StreamConfig {
        self.config
    }

    /// Traces `rays` stream by stream with width `N` on `L` lanes and the tests `R`, recording
    /// each ray's answer.
    fn run<const L: usize, const N: usize, R: BlockTests, S: Stats, A: Answer>(
        &self,
        rays: Rays<'_>,
        answers: &mut [A],
        stats: &mut S,
    ) {
        if S::ENABLED {
            (0..rays.len()).for_each(|_| stats.ray());
        }
        if self.bvh.is_empty() || rays.is_empty() {
            return;
        }
        let size = match self.config.stream {
            StreamSize::Rays(n) => n.min(rays.len()),
            StreamSize::Frame => rays.len(),
        };
        let mut stream = StreamRays::<L>::default();
        let mut groups = vec![SimdRay::<L>::default(); Width::<L, N>::GROUPS];
        for first in (0..rays.len()).step_by(size) {
            let n = size.min(rays.len() - first);
            let len = stream.load(&rays, first, n);
            let mut walk = Walk::<L, N, A, R> {
                bvh: &self.bvh,
                order: &self.order,
                input: rays,
                single: self.config.single,
                handoff: &self.handoff,
                rays: &mut stream,
                groups: &mut groups,
                answers,
                tests: PhantomData,
            };
            walk.visit(Bvh::ROOT as u32, len, stats);
        }
    }

    fn trace<S: Stats, A: Answer>(&self, rays: Rays<'_>, answers: &mut [A], stats: &mut S) {
        with_width!(self.config.width, N in [4, 8, 12, 16, 32, 64] => {
            match self.config.robust {
                true => self.run::<{ width::lanes_for(N) }, N, Robust, S, A>(rays, answers, stats),
                false => self.run::<{ width::lanes_for(N) }, N, Fast, S, A>(rays, answers, stats),
            }
        })
    }
}

impl Kernel for StreamTracer {
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        hits.fill(Hit::MISS);
        self.trace(rays, hits, stats);
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        occluded.fill(false);
        self.trace(rays, occluded, stats);
    }
}
