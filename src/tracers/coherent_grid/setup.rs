//! Packet set-up for coherent grid traversal (Wald et al. 2006 §2.2, §4.7): which rays of a
//! packet can hit anything, splitting packets whose rays disagree in direction along the march
//! axis or spread too wide, the march coordinates and frustum of a coherent packet, and loading
//! its rays into the lanes. Lone rays go to the 3D-DDA.

use glam::Vec3;

use super::cell::{CellObserver, Packet};
use super::frustum::{MarchFrame, MarchFrustum, MarchRays, SplitKey};
use super::gathered::GatheredRays;
use super::lanes::LaneRays;
use super::mailbox::Mailbox;
use super::traversal::walk;
use super::{CgtTracer, MAX_ORIGIN_SPREAD, MAX_SLOPE_SPREAD};
use crate::geometry::{Hit, RayBoxTest, RayTests, Rays};
use crate::stats::{Event, Stats};
use crate::tracers::grid_dda;

/// Per-call scratch space, reused by every packet of a chunk.
#[derive(Default)]
pub(super) struct Workspace<const L: usize, R: RayTests> {
    /// Chunk indices of the packet being split or traversed.
    pub(super) group: Vec<u32>,
    /// The traversed packet's rays in march coordinates, and per ray its speed along s and its
    /// triangle-test form (indexed by position in the packet).
    pub(super) march: MarchRays,
    pub(super) d_s: Vec<f32>,
    /// The rays of the packet being marched, gathered.
    pub(super) gathered: GatheredRays,
    /// Per ray of the packet being gathered: whether it can hit anything.
    pub(super) inside: Vec<bool>,
    /// The rays still active, in SIMD lanes.
    pub(super) lanes: LaneRays<L, R>,
    pub(super) mailbox: Mailbox,
    /// Split keys with chunk indices, for the median split.
    pub(super) keys: Vec<(f32, u32)>,
}

impl CgtTracer {
    /// Traverses the packet `group` along the dominant axis of its first ray if all its rays
    /// agree in direction along it and are coherent; otherwise splits it (module doc). A lone ray
    /// takes the 3D-DDA.
    pub(super) fn split<const L: usize, R: RayTests, S: Stats, O: CellObserver, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        group: &mut [u32],
        ws: &mut Workspace<L, R>,
        hits: &mut [Hit],
        stats: &mut S,
        observer: &mut O,
    ) {
        if group.len() == 1 {
            self.trace_alone::<R, S, ANY>(rays, group, hits, stats);
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
                self.split::<L, R, S, O, ANY>(rays, part, ws, hits, stats, observer);
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
                self.trace_alone::<R, S, ANY>(rays, group, hits, stats);
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
            self.split::<L, R, S, O, ANY>(rays, front, ws, hits, stats, observer);
            self.split::<L, R, S, O, ANY>(rays, back, ws, hits, stats, observer);
            return;
        }
        if S::ENABLED {
            stats.event(Event::Packets, 1);
        }
        self.load_lanes(ws);
        let mut packet = Packet::<L, R, S, O, ANY> {
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
    fn trace_alone<R: RayTests, S: Stats, const ANY: bool>(
        &self,
        rays: Rays<'_>,
        group: &[u32],
        hits: &mut [Hit],
        stats: &mut S,
    ) {
        for &i in group {
            if S::ENABLED {
                stats.event(Event::Packets, 1);
                stats.charge_ray(i as usize);
            }
            let ray = rays.ray(i as usize);
            hits[i as usize] = grid_dda::walk::<R, S, ANY>(&self.grid, &ray, stats);
        }
    }

    /// Sets `ws.group` to the rays of `packet` that can hit anything: well formed (finite, a
    /// non-zero direction, a non-empty interval from tmin ≥ 0) and meeting the grid's box. Branch-free over the packet (`&`, not `&&`), so it
    /// runs in SIMD lanes.
    pub(super) fn usable_rays<const L: usize, R: RayTests>(
        &self,
        rays: Rays<'_>,
        packet: std::ops::Range<usize>,
        ws: &mut Workspace<L, R>,
    ) {
        let bounds = &self.grid.bounds;
        let start = packet.start;
        ws.inside.resize(packet.len(), false);
        for (p, usable) in ws.inside.iter_mut().enumerate() {
            let i = start + p;
            let o = Vec3::new(rays.ox[i], rays.oy[i], rays.oz[i]);
            let d = Vec3::new(rays.dx[i], rays.dy[i], rays.dz[i]);
            let (tmin, tmax) = (rays.tmin[i], rays.tmax[i]);
            // `Ray::is_well_formed`, written branch-free, then the grid's box (in its local frame;
            // the box is padded far beyond the translation's rounding).
            *usable = o.is_finite()
                & d.is_finite()
                & (d != Vec3::ZERO)
                & tmin.is_finite()
                & (tmin >= 0.0)
                & (tmin < tmax)
                & RayBoxTest::new(self.grid.local(o), d)
                    .hit(bounds, tmin, tmax)
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
    fn march<const L: usize, R: RayTests>(
        &self,
        rays: Rays<'_>,
        group: &[u32],
        frame: &MarchFrame,
        ws: &mut Workspace<L, R>,
    ) -> MarchFrustum {
        ws.gathered.gather(rays, group);
        let (grid, g, n) = (&*self.grid, &ws.gathered, group.len());
        // Per march axis s, u, v: the rays' world components, and the grid's origin, scale and
        // cells along it.
        let axes = [frame.k, frame.u, frame.v];
        let [o_k, o_u, o_v] = axes.map(|a| &g.origin[a][..n]);
        let [d_k, d_u, d_v] = axes.map(|a| &g.dir[a][..n]);
        let [lo_k, lo_u, lo_v] = axes.map(|a| grid.bounds.min[a]);
        // Ray origins go to the grid's local frame first (`Grid::local`): one rounding of at most
        // 2⁻²⁴ of the local coordinate, far inside the frustum's margin.
        let [at_k, at_u, at_v] = axes.map(|a| grid.origin[a]);
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
                ((o_k[p] - at_k) - lo_k) * inv_k,
                ((o_u[p] - at_u) - lo_u) * inv_u,
                ((o_v[p] - at_v) - lo_v) * inv_v,
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
        MarchFrustum::new::<L>(&ws.march, apex, self.scale)
    }

    /// Loads the rays of the packet `group` (marched by `march`) into the lanes, all active, and
    /// empties the mailbox.
    fn load_lanes<const L: usize, R: RayTests>(&self, ws: &mut Workspace<L, R>) {
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
