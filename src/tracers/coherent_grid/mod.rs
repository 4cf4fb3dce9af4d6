//! Coherent grid traversal (CGT, registry name `cgt`; Wald, Ize, Kensler, Knoll and Parker 2006, "Ray Tracing Animated
//! Scenes using Coherent Grid Traversal"): packets of n×n rays walk a uniform grid slice by slice
//! inside their bounding frustum (§2.2), test the triangles of every overlapped cell with mailboxing
//! and SIMD frustum culling (§2.3), and skip empty space with macrocells (§2.4).
//!
//! - **Packets.** Consecutive groups of n² rays of the chunk (parameter `packet` = n;
//!   `Rays::packets`: an explicit packet of the batch is never merged with the next). The runner
//!   orders camera rays in 32×32 tiles with Morton order inside, so each group of camera rays is
//!   an n×n screen block; shadow and diffuse batches are grouped the same way (consecutive rays
//!   descend from neighbouring pixels). The last group of a chunk may be partial.
//! - **Major axis and direction signs (§2.2).** The march axis K is the dominant grid-space axis
//!   of the packet's first ray, and every ray must travel the same way along it. When they do
//!   not, the packet is **split**: rays going +K, rays going −K and rays with a zero K component
//!   become sub-packets, each choosing its own axis from its first ray, recursively (a split
//!   always shrinks the packet, and a single ray always agrees with itself). Coherent packets
//!   never split.
//! - **Frustum (§2.2).** Bounds every ray of the packet (see `frustum`): for camera and other
//!   common-origin packets it is the paper's corner-ray pyramid; for general packets the
//!   interval of origins and directions.
//! - **Exact closest hits.** A hit found in a cell is final only once the walk has left the slice
//!   holding it: a ray stays active, taking part in every later cell's tests with its interval
//!   clipped to its closest hit so far, until the slice about to be entered starts beyond its hit
//!   (or its segment's end); the packet stops when no ray is active (§2.3 early termination).
//! - **Mailboxing (§2.3).** Per packet (`mailbox`): a triangle met again in another cell is
//!   skipped. Sound because the packet tests a triangle against every ray still active, and a ray
//!   only ever leaves the active set.
//! - **Culling (§2.3).** Per packet and triangle (`cull`): the frustum's side planes, and for
//!   common-origin packets the four corner rays' shaft test (`MarchFrustum::culls`, one lane per
//!   corner and triangle edge). A cull costs
//!   about as much as testing four rays (§2.3), so packets with at most `CULL_MIN_RAYS` active
//!   rays (split shadow and diffuse packets, ends of walks) test directly.
//! - **Macrocells (§2.4).** `macrocells` uses the grid's M³ macrocells (`macro_size`).
//! - **Shadow rays (§4.7).** Occlusion uses the same walk; a ray is done at its first hit. The
//!   batch's shadow rays leave the surface points towards the light, so they share an end point,
//!   not an origin: we trace them as given, with the general frustum, rather than reversed from
//!   the light. Its second anchor at the packet's last `s` makes it the paper's light pyramid near
//!   the light (`frustum`: both pyramids bound the rays, and the walk uses their intersection).
//!   Reversed rays would be other rays — the watertight test is not symmetric in the ray's
//!   direction, so at edges they could disagree with the rays every other tracer answers.
//! - **Incoherent packets are split (§4.7).** The paper splits shadow packets whose hit points
//!   lie too far apart. We measure that on the frustum: a packet whose rays start more than
//!   `MAX_ORIGIN_SPREAD` cells apart, or whose frustum widens by more than `MAX_SLOPE_SPREAD`
//!   cells per slice (diffuse bounces), is split in two at the median of the quantity it spreads
//!   most in (`MarchFrustum::split_key`: its u or v slope, else where its rays cross the frustum's
//!   start along u or v), recursively; median halves are each narrower along that extent, where
//!   halves in batch order need not be. Camera packets stay below both limits unless they are
//!   very wide: a 32×32 packet of a 60° image spreads by 0.6 at 128² pixels and by 0.07 at 1024².
//! - **Lone rays take the 3D-DDA.** A packet split down to one ray, or so incoherent that its
//!   halves would be single rays before they are coherent (`MarchFrustum::halvings`: the halvings
//!   its extents need, against the halvings its ray count allows), sends each ray through the
//!   single-ray 3D-DDA of `grid-dda` on the same grid: a frustum around one ray still covers up
//!   to four cells per slice, and splitting costs a march per level. Diffuse bounces mostly end
//!   here; coherent primary and shadow packets never do.
//! - **SIMD (§2.3).** The active rays of a packet live in SoA lanes (`lanes`), and each triangle
//!   is tested against `lanes` = L of them at a time (4, 8 or 16: the lane layer's width), with
//!   hits bit for bit those of the scalar watertight test (with `robust = false`, of
//!   Möller–Trumbore).
//!
//! Counters: `ray` per ray; `node(0)` per grid cell visited (per packet, and per cell a lone
//! ray's DDA visits); `triangle_test(0)` per ray–triangle test (one per active ray of a packet for
//! each triangle neither mailboxed nor culled, and the DDA's tests). Events: `Packets` per packet
//! walked (each sub-packet of a split; a packet that is split is not walked itself) and per lone
//! ray; `MailboxHits` per triangle reference a packet skips because it tested (or culled) the
//! triangle before (and the DDA's own mailbox hits); `TrianglesCulled` per triangle a packet
//! culls; `LeavesVisited` per visited cell holding triangles and `LeafActiveRays` the active rays
//! there; `SlicesStepped` and `MacrocellsSkipped` as in `traversal` (and the DDA's skipped
//! macrocells). So with culling off, every triangle reference met by a packet with r active rays
//! is either r tests or one mailbox hit. Rays whose direction is zero or not finite, or whose
//! origin is not finite, hit nothing.

mod cell;
mod frustum;
mod gathered;
mod lanes;
mod mailbox;
mod setup;
mod traversal;

use std::sync::Arc;

use crate::accel::Grid;
use crate::error::{Error, Result};
use crate::geometry::robustness::robust_param;
use crate::geometry::{Fast, Hit, RayTests, Rays, Robust};
use crate::lanes::{with_lanes, WIDTHS};
use crate::params::Params;
use crate::stats::{NoStats, Stats};
use crate::tracers::kernel::Kernel;

pub use cell::CellObserver;
use setup::Workspace;

/// The tracer's own parameters (the grid's are `GridConfig`'s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CgtConfig {
    /// Packet side n: packets of n×n rays.
    pub packet: u32,
    /// SIMD width L of the ray–triangle tests and the frustum's extremes (`lanes::WIDTHS`).
    pub lanes: usize,
    pub mailbox: bool,
    pub cull: bool,
    pub macrocells: bool,
    /// The triangle tests every lane runs (`robust`; `geometry::robustness`): watertight, or
    /// Möller–Trumbore.
    pub robust: bool,
}

impl Default for CgtConfig {
    fn default() -> Self {
        CgtConfig {
            packet: 4,
            // 16 f32 lanes fill an AVX-512 register.
            lanes: 16,
            mailbox: true,
            cull: true,
            macrocells: true,
            robust: true,
        }
    }
}

impl CgtConfig {
    pub const PARAMS: &'static [&'static str] =
        &["packet", "lanes", "mailbox", "cull", "macrocells"];
    /// The packet sides the paper studies (§4.1).
    pub const PACKET_SIDES: [u32; 5] = [2, 4, 8, 16, 32];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = CgtConfig::default();
        let c = CgtConfig {
            packet: p.get_or("packet", d.packet)?,
            lanes: p.get_or("lanes", d.lanes)?,
            mailbox: p.get_or("mailbox", d.mailbox)?,
            cull: p.get_or("cull", d.cull)?,
            macrocells: p.get_or("macrocells", d.macrocells)?,
            robust: robust_param(p)?,
        };
        if !Self::PACKET_SIDES.contains(&c.packet) {
            return Err(Error::usage(format!(
                "parameter packet = {} must be one of {:?} (packets of n×n rays)",
                c.packet,
                Self::PACKET_SIDES
            )));
        }
        if !WIDTHS.contains(&c.lanes) {
            return Err(Error::usage(format!(
                "parameter lanes = {} must be one of {WIDTHS:?} (SIMD width)",
                c.lanes
            )));
        }
        Ok(c)
    }
}

/// Packets whose overlap box grows by more than this many cells per slice (u + v) are split in
/// halves (module doc).
const MAX_SLOPE_SPREAD: f32 = 1.0;
/// Packets whose rays start more than this many cells apart (u + v) are split in halves (§4.7:
/// shadow rays from hit points on both sides of a silhouette).
const MAX_ORIGIN_SPREAD: f32 = 4.0;

/// Packets with at most this many active rays test triangles without culling them first.
const CULL_MIN_RAYS: usize = 4;

pub struct CgtTracer {
    grid: Arc<Grid>,
    config: CgtConfig,
    /// Rounding scale of the local → grid transform (see `frustum`).
    scale: f32,
}

impl CgtTracer {
    pub fn new(grid: Arc<Grid>, config: CgtConfig) -> Self {
        // The grid's local coordinates: the world's magnitude no longer enters (`Grid::local`).
        let b = &grid.bounds;
        let world = b.min.abs().max(b.max.abs()).max_element();
        let res = grid.res.iter().copied().max().unwrap_or(1) as f32;
        let scale = res.max(world * grid.inv_cell_size.max_element());
        CgtTracer {
            grid,
            config,
            scale,
        }
    }

    /// The cells the packets of `rays` visit, packet by packet in visiting order (the closest-hit
    /// query's walk, hits written to `hits`); lone rays (DDA) add none.
    pub fn visited_cells(&self, rays: Rays<'_>, hits: &mut [Hit]) -> Vec<[u32; 3]> {
        let mut cells = vec![];
        self.trace::<NoStats, _, false>(rays, hits, &mut NoStats, &mut cells);
        cells
    }

    /// Closest hits (`ANY = false`) or any hit (`ANY = true`) of every ray of the chunk, at the
    /// configured lane width.
    fn trace<S: Stats, O: CellObserver, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        hits: &mut [Hit],
        stats: &mut S,
        observer: &mut O,
    ) {
        // The triangle tests are a type parameter of the whole walk, so each `robust` value is
        // built with only its own tests inline.
        with_lanes!(self.config.lanes, L => match self.config.robust {
            true => self.trace_lanes::<L, Robust, S, O, ANY>(rays, hits, stats, observer),
            false => self.trace_lanes::<L, Fast, S, O, ANY>(rays, hits, stats, observer),
        })
    }

    fn trace_lanes<const L: usize, R: RayTests, S: Stats, O: CellObserver, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        hits: &mut [Hit],
        stats: &mut S,
        observer: &mut O,
    ) {
        hits.fill(Hit::MISS);
        let mut ws = Workspace::<L, R>::default();
        let size = (self.config.packet * self.config.packet) as usize;
        for packet in rays.packets(size) {
            if S::ENABLED {
                for _ in packet.clone() {
                    stats.ray();
                }
            }
            self.usable_rays(rays, packet, &mut ws);
            if !ws.group.is_empty() {
                let mut group = std::mem::take(&mut ws.group);
                self.split::<L, R, S, O, ANY>(rays, &mut group, &mut ws, hits, stats, observer);
                ws.group = group;
            }
        }
    }
}

impl Kernel for CgtTracer {
    fn intersect_with<S: Stats>(&self, rays: Rays<'_>, hits: &mut [Hit], stats: &mut S) {
        self.trace::<S, (), false>(rays, hits, stats, &mut ());
    }

    fn occluded_with<S: Stats>(&self, rays: Rays<'_>, occluded: &mut [bool], stats: &mut S) {
        let mut hits = vec![Hit::MISS; rays.len()];
        self.trace::<S, (), true>(rays, &mut hits, stats, &mut ());
        for (o, h) in occluded.iter_mut().zip(&hits) {
            *o = h.is_hit();
        }
    }
}
