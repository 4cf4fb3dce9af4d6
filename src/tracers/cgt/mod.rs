//! Coherent grid traversal (Wald, Ize, Kensler, Knoll and Parker 2006, "Ray Tracing Animated
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
//!   common-origin packets the four corner rays' shaft test (`Frustum::culls`, one lane per
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
//!   most in (`Frustum::split_key`: its u or v slope, else where its rays cross the frustum's
//!   start along u or v), recursively; median halves are each narrower along that extent, where
//!   halves in batch order need not be. Camera packets stay below both limits unless they are
//!   very wide: a 32×32 packet of a 60° image spreads by 0.6 at 128² pixels and by 0.07 at 1024².
//! - **Lone rays take the 3D-DDA.** A packet split down to one ray, or so incoherent that its
//!   halves would be single rays before they are coherent (`Frustum::halvings`: the halvings
//!   its extents need, against the halvings its ray count allows), sends each ray through the
//!   single-ray 3D-DDA of `grid-dda` on the same grid: a frustum around one ray still covers up
//!   to four cells per slice, and splitting costs a march per level. Diffuse bounces mostly end
//!   here; coherent primary and shadow packets never do.
//! - **SIMD (§2.3).** The active rays of a packet live in SoA lanes (`lanes`), and each triangle
//!   is tested against `LANES` of them at a time, with hits bit for bit those of the scalar
//!   watertight test.
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

mod frustum;
mod gathered;
mod lanes;
mod mailbox;
mod traversal;

use std::sync::Arc;

use glam::Vec3;

use crate::accel::Grid;
use crate::error::{Error, Result};
use crate::geometry::{Hit, RayBoxTest, Rays};
use crate::stats::{Event, NoStats, Stats};
use crate::tracers::dda::GridDdaTracer;
use crate::tracers::{Kernel, Params};

use frustum::{Frustum, MarchFrame, MarchRays, SplitKey};
use gathered::GatheredRays;
use lanes::LaneRays;
use mailbox::Mailbox;
use traversal::{walk, SliceVisitor};

/// The tracer's own parameters (the grid's are `GridConfig`'s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CgtConfig {
    /// Packet side n: packets of n×n rays.
    pub packet: u32,
    pub mailbox: bool,
    pub cull: bool,
    pub macrocells: bool,
}

impl Default for CgtConfig {
    fn default() -> Self {
        CgtConfig {
            packet: 4,
            mailbox: true,
            cull: true,
            macrocells: true,
        }
    }
}

impl CgtConfig {
    pub const PARAMS: &'static [&'static str] = &["packet", "mailbox", "cull", "macrocells"];
    /// The packet sides the paper studies (§4.1).
    pub const PACKET_SIDES: [u32; 5] = [2, 4, 8, 16, 32];

    pub fn from_params(p: &Params) -> Result<Self> {
        let d = CgtConfig::default();
        let c = CgtConfig {
            packet: p.get_or("packet", d.packet)?,
            mailbox: p.get_or("mailbox", d.mailbox)?,
            cull: p.get_or("cull", d.cull)?,
            macrocells: p.get_or("macrocells", d.macrocells)?,
        };
        if !Self::PACKET_SIDES.contains(&c.packet) {
            return Err(Error::usage(format!(
                "parameter packet = {} must be one of {:?} (packets of n×n rays)",
                c.packet,
                Self::PACKET_SIDES
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

/// SIMD width of the ray–triangle tests (`lanes`): 16 f32 lanes fill an AVX-512 register.
const LANES: usize = 16;

/// Packets with at most this many active rays test triangles without culling them first.
const CULL_MIN_RAYS: usize = 4;

/// Something told about every cell a packet visits (`()` for tracing, a list for tests).
pub trait CellObserver {
    fn visit(&mut self, cell: [u32; 3]);
}

impl CellObserver for () {
    #[inline(always)]
    fn visit(&mut self, _: [u32; 3]) {}
}

impl CellObserver for Vec<[u32; 3]> {
    fn visit(&mut self, cell: [u32; 3]) {
        self.push(cell);
    }
}

pub struct CgtTracer {
    grid: Arc<Grid>,
    config: CgtConfig,
    /// Rounding scale of the world → grid transform (see `frustum`).
    scale: f32,
    /// Lone rays (packets split down to one ray) take the single-ray 3D-DDA.
    dda: GridDdaTracer,
}

/// Per-call scratch space, reused by every packet of a chunk.
#[derive(Default)]
struct Workspace {
    /// Chunk indices of the packet being split or traversed.
    group: Vec<u32>,
    /// The traversed packet's rays in march coordinates, and per ray its speed along s and its
    /// triangle-test form (indexed by position in the packet).
    march: MarchRays,
    d_s: Vec<f32>,
    /// The rays of the packet being marched, gathered.
    gathered: GatheredRays,
    /// Per ray of the packet being gathered: whether it can hit anything.
    inside: Vec<bool>,
    /// The rays still active, in SIMD lanes.
    lanes: LaneRays<LANES>,
    mailbox: Mailbox,
    /// Split keys with chunk indices, for the median split.
    keys: Vec<(f32, u32)>,
}

impl CgtTracer {
    pub fn new(grid: Arc<Grid>, config: CgtConfig) -> Self {
        let b = &grid.bounds;
        let world = b.min.abs().max(b.max.abs()).max_element();
        let res = grid.res.iter().copied().max().unwrap_or(1) as f32;
        let scale = res.max(world * grid.inv_cell_size.max_element());
        CgtTracer {
            dda: GridDdaTracer::new(grid.clone()),
            grid,
            config,
            scale,
        }
    }

    pub fn from_params(grid: Arc<Grid>, params: &Params) -> Result<Self> {
        Ok(CgtTracer::new(grid, CgtConfig::from_params(params)?))
    }

    /// The cells the packets of `rays` visit, packet by packet in visiting order (the closest-hit
    /// query's walk, hits written to `hits`); lone rays (DDA) add none.
    pub fn visited_cells(&self, rays: Rays<'_>, hits: &mut [Hit]) -> Vec<[u32; 3]> {
        let mut cells = vec![];
        self.trace::<NoStats, _, false>(rays, hits, &mut NoStats, &mut cells);
        cells
    }

    /// Closest hits (`ANY = false`) or any hit (`ANY = true`) of every ray of the chunk.
    fn trace<S: Stats, O: CellObserver, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        hits: &mut [Hit],
        stats: &mut S,
        observer: &mut O,
    ) {
        hits.fill(Hit::MISS);
        let mut ws = Workspace::default();
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
                self.split::<S, O, ANY>(rays, &mut group, &mut ws, hits, stats, observer);
                ws.group = group;
            }
        }
    }

    /// Traverses the packet `group` along the dominant axis of its first ray if all its rays
    /// agree in direction along it and are coherent; otherwise splits it (module doc). A lone ray
    /// takes the 3D-DDA.
    fn split<S: Stats, O: CellObserver, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        group: &mut [u32],
        ws: &mut Workspace,
        hits: &mut [Hit],
        stats: &mut S,
        observer: &mut O,
    ) {
        if group.len() == 1 {
            self.trace_alone::<S, ANY>(rays, group, hits, stats);
            return;
        }
        let inv_cell = self.grid.inv_cell_size;
        let k = dominant_axis(rays.ray(group[0] as usize).dir * inv_cell);
        let (dir_k, inv_k) = ([rays.dx, rays.dy, rays.dz][k], inv_cell[k]);
        // 0: +K, 1: −K, 2: zero along K (in grid space, as the march sees it).
        let class = |i: &u32| {
            let d = dir_k[*i as usize] * inv_k;
            (d < 0.0) as u8 + 2 * (d == 0.0) as u8
        };
        let first = class(&group[0]);
        if !group.iter().fold(true, |all, i| all & (class(i) == first)) {
            group.sort_unstable_by_key(class);
            let mut rest: &mut [u32] = group;
            while !rest.is_empty() {
                let c = class(&rest[0]);
                let n = rest.iter().take_while(|i| class(i) == c).count();
                let (part, tail) = std::mem::take(&mut rest).split_at_mut(n);
                self.split::<S, O, ANY>(rays, part, ws, hits, stats, observer);
                rest = tail;
            }
            return;
        }
        let frame = MarchFrame::new(k, first == 1, self.grid.res);
        let frustum = self.march(rays, group, &frame, ws);
        if let Some(key) = frustum.split_key(MAX_SLOPE_SPREAD, MAX_ORIGIN_SPREAD) {
            // Halves that would be single rays before they are coherent: the DDA at once.
            let halvings = frustum.halvings(MAX_SLOPE_SPREAD, MAX_ORIGIN_SPREAD);
            if (group.len() as u64) < 2u64 << halvings.min(62) {
                self.trace_alone::<S, ANY>(rays, group, hits, stats);
                return;
            }
            // §4.7: an incoherent packet would drag a wide frustum through the grid. Halve
            // it at the median of the key, so each half is narrower along the frustum's
            // widest extent.
            ws.keys.clear();
            let m = &ws.march;
            ws.keys.extend(group.iter().enumerate().map(|(p, &i)| {
                let v = match key {
                    SplitKey::SlopeU => m.a[p],
                    SplitKey::SlopeV => m.b[p],
                    SplitKey::OriginU => m.o_u[p] + (frustum.s_ref() - m.o_s[p]) * m.a[p],
                    SplitKey::OriginV => m.o_v[p] + (frustum.s_ref() - m.o_s[p]) * m.b[p],
                };
                (v, i)
            }));
            let half = group.len() / 2;
            ws.keys
                .select_nth_unstable_by(half, |x, y| x.0.total_cmp(&y.0));
            for (g, &(_, i)) in group.iter_mut().zip(&ws.keys) {
                *g = i;
            }
            let (front, back) = group.split_at_mut(half);
            self.split::<S, O, ANY>(rays, front, ws, hits, stats, observer);
            self.split::<S, O, ANY>(rays, back, ws, hits, stats, observer);
            return;
        }
        if S::ENABLED {
            stats.event(Event::Packets, 1);
        }
        self.load_lanes(ws);
        let mut packet = Packet::<S, O, ANY> {
            grid: &self.grid,
            frame: &frame,
            frustum: &frustum,
            config: &self.config,
            group,
            ws,
            hits,
            stats,
            observer,
        };
        walk(
            &self.grid,
            &frame,
            &frustum,
            self.config.macrocells,
            &mut packet,
        );
    }

    /// Each ray of `group` alone, by the 3D-DDA (a packet of one for the counters).
    fn trace_alone<S: Stats, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        group: &[u32],
        hits: &mut [Hit],
        stats: &mut S,
    ) {
        for &i in group {
            if S::ENABLED {
                stats.event(Event::Packets, 1);
            }
            hits[i as usize] = self.dda.walk::<S, ANY>(&rays.ray(i as usize), stats);
        }
    }

    /// Sets `ws.group` to the rays of `packet` that can hit anything: finite, with a non-zero
    /// direction, and meeting the grid's box. Branch-free over the packet (`&`, not `&&`), so it
    /// runs in SIMD lanes.
    fn usable_rays(&self, rays: Rays<'_>, packet: std::ops::Range<usize>, ws: &mut Workspace) {
        let bounds = &self.grid.bounds;
        let start = packet.start;
        ws.inside.resize(packet.len(), false);
        for (p, usable) in ws.inside.iter_mut().enumerate() {
            let i = start + p;
            let o = Vec3::new(rays.ox[i], rays.oy[i], rays.oz[i]);
            let d = Vec3::new(rays.dx[i], rays.dy[i], rays.dz[i]);
            *usable = o.is_finite()
                & d.is_finite()
                & (d != Vec3::ZERO)
                & RayBoxTest::new(o, d)
                    .hit(bounds, rays.tmin[i], rays.tmax[i])
                    .is_some();
        }
        ws.group.clear();
        let inside = &ws.inside;
        ws.group.extend(
            (0..inside.len())
                .filter(|&p| inside[p])
                .map(|p| (start + p) as u32),
        );
    }

    /// Fills the workspace's march coordinates for the packet `group`, whose rays all travel
    /// towards +s in `frame`, and returns its frustum.
    fn march(
        &self,
        rays: Rays<'_>,
        group: &[u32],
        frame: &MarchFrame,
        ws: &mut Workspace,
    ) -> Frustum {
        ws.gathered.gather(rays, group);
        let (grid, g, n) = (&*self.grid, &ws.gathered, group.len());
        // Per march axis s, u, v: the rays' world components, and the grid's origin, scale and
        // cells along it.
        let axes = [frame.k, frame.u, frame.v];
        let [o_k, o_u, o_v] = axes.map(|a| &g.origin[a][..n]);
        let [d_k, d_u, d_v] = axes.map(|a| &g.dir[a][..n]);
        let [lo_k, lo_u, lo_v] = axes.map(|a| grid.bounds.min[a]);
        let [inv_k, inv_u, inv_v] = axes.map(|a| grid.inv_cell_size[a]);
        let [n_k, n_u, n_v] = axes.map(|a| grid.res[a] as f32);
        let (tmin, tmax) = (&g.tmin[..n], &g.tmax[..n]);
        let m = &mut ws.march;
        m.set_len(n);
        if ws.d_s.len() < n {
            ws.d_s.resize(n, 0.0);
        }
        let (s_o, u_o, v_o) = (&mut m.o_s[..n], &mut m.o_u[..n], &mut m.o_v[..n]);
        let (slope_u, slope_v) = (&mut m.a[..n], &mut m.b[..n]);
        let (s_start, s_end, d_s) = (&mut m.s_start[..n], &mut m.s_end[..n], &mut ws.d_s[..n]);
        // The ray's stretch inside the grid box [0, N] along one axis (slabs; NaN from 0·∞ is
        // ignored by min/max, and the frustum's margin absorbs rounding).
        let slab = |g: f32, e: f32, cells: f32| {
            let inv = 1.0 / e;
            let (ta, tb) = ((0.0 - g) * inv, (cells - g) * inv);
            (ta.min(tb), ta.max(tb))
        };
        let first = [o_k[0], o_u[0], o_v[0]];
        let mut common_origin = true;
        for p in 0..n {
            common_origin &= (o_k[p] == first[0])
                & (o_u[p] == first[1])
                & (o_v[p] == first[2])
                & (tmin[p] >= 0.0);
            let (g_k, g_u, g_v) = (
                (o_k[p] - lo_k) * inv_k,
                (o_u[p] - lo_u) * inv_u,
                (o_v[p] - lo_v) * inv_v,
            );
            let (e_k, e_u, e_v) = (d_k[p] * inv_k, d_u[p] * inv_u, d_v[p] * inv_v);
            let (in_k, out_k) = slab(g_k, e_k, n_k);
            let (in_u, out_u) = slab(g_u, e_u, n_u);
            let (in_v, out_v) = slab(g_v, e_v, n_v);
            let t0 = tmin[p].max(in_k).max(in_u).max(in_v);
            let t1 = tmax[p].min(out_k).min(out_u).min(out_v);
            let (s, e_s) = if frame.flip {
                (n_k - g_k, -e_k)
            } else {
                (g_k, e_k)
            };
            s_o[p] = s;
            u_o[p] = g_u;
            v_o[p] = g_v;
            slope_u[p] = e_u / e_s;
            slope_v[p] = e_v / e_s;
            s_start[p] = s + t0.max(tmin[p]) * e_s;
            s_end[p] = s + t1.max(t0) * e_s;
            d_s[p] = e_s;
        }
        let apex = common_origin.then(|| [s_o[0], u_o[0], v_o[0]]);
        Frustum::new(&ws.march, apex, self.scale)
    }

    /// Loads the rays of the packet `group` (marched by `march`) into the lanes, all active, and
    /// empties the mailbox.
    fn load_lanes(&self, ws: &mut Workspace) {
        let g = &ws.gathered;
        ws.lanes.load(
            &g.origin,
            &g.dir,
            &g.tmin,
            &g.tmax,
            &ws.march.s_end[..g.tmin.len()],
        );
        ws.mailbox.clear();
    }
}

/// The axis of the largest |component| (the first on ties).
fn dominant_axis(d: Vec3) -> usize {
    let a = d.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

/// A packet on its walk: decides when its rays are done and tests the triangles of each cell.
struct Packet<'a, S, O, const ANY: bool> {
    grid: &'a Grid,
    frame: &'a MarchFrame,
    frustum: &'a Frustum,
    config: &'a CgtConfig,
    group: &'a [u32],
    ws: &'a mut Workspace,
    hits: &'a mut [Hit],
    stats: &'a mut S,
    observer: &'a mut O,
}

impl<S: Stats, O: CellObserver, const ANY: bool> Packet<'_, S, O, ANY> {
    /// The triangle's vertices in march coordinates (for culling).
    #[inline]
    fn march_vertices(&self, id: u32) -> [[f32; 3]; 3] {
        let g = self.grid;
        g.triangles[id as usize]
            .v
            .map(|p| self.frame.point((p - g.bounds.min) * g.inv_cell_size))
    }
}

impl<S: Stats, O: CellObserver, const ANY: bool> SliceVisitor for Packet<'_, S, O, ANY> {
    fn begin_slice(&mut self, slice: u32) -> bool {
        // A ray is done when the slab about to be entered starts past its hit or its end
        // (§2.3 early termination, per ray); the margin covers rounding of s.
        let start = slice as f32 - self.frustum.eps();
        if self.ws.lanes.any_s_limit_below(start) {
            self.ws.lanes.retain(|s_limit| s_limit >= start);
        }
        !self.ws.lanes.is_empty()
    }

    fn count(&mut self, event: Event, n: u64) {
        if S::ENABLED {
            self.stats.event(event, n);
        }
    }

    fn cell(&mut self, index: usize, cell: [u32; 3]) {
        if self.ws.lanes.is_empty() {
            return; // every ray found its occluder earlier in this slice
        }
        if S::ENABLED {
            self.stats.node(0);
        }
        self.observer.visit(cell);
        let grid = self.grid;
        let ids =
            &grid.cell_tris[grid.cell_start[index] as usize..grid.cell_start[index + 1] as usize];
        if S::ENABLED && !ids.is_empty() {
            self.stats.event(Event::LeavesVisited, 1);
            self.stats
                .event(Event::LeafActiveRays, self.ws.lanes.len() as u64);
        }
        for &id in ids {
            if self.config.mailbox && !self.ws.mailbox.insert(id) {
                if S::ENABLED {
                    self.stats.event(Event::MailboxHits, 1);
                }
                continue;
            }
            // Culling costs about a 4-ray triangle test (§2.3): it pays only for more rays.
            if self.config.cull
                && self.ws.lanes.len() > CULL_MIN_RAYS
                && self.frustum.culls(&self.march_vertices(id))
            {
                if S::ENABLED {
                    self.stats.event(Event::TrianglesCulled, 1);
                }
                continue;
            }
            let tri = &grid.triangles[id as usize];
            let ws = &mut *self.ws;
            if S::ENABLED {
                for _ in 0..ws.lanes.len() {
                    self.stats.triangle_test(0);
                }
            }
            let (hits, group, march, d_s) = (&mut *self.hits, self.group, &ws.march, &ws.d_s);
            let mut any_done = false;
            ws.lanes.intersect(tri, |lanes, slot, t, u, v| {
                let p = lanes.ray[slot] as usize;
                hits[group[p] as usize] = Hit { t, prim: id, u, v };
                if ANY {
                    lanes.s_limit[slot] = f32::NEG_INFINITY;
                    any_done = true;
                } else {
                    lanes.s_limit[slot] = lanes.s_limit[slot].min(march.o_s[p] + t * d_s[p]);
                }
            });
            if any_done {
                ws.lanes.retain(|s_limit| s_limit != f32::NEG_INFINITY);
                if ws.lanes.is_empty() {
                    return;
                }
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
