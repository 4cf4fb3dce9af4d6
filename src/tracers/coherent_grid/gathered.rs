//! A packet's rays gathered from the batch into contiguous arrays (SoA, indexed by position in
//! the packet), so the per-ray setup of a packet (`march`, lane loading) runs as straight loops
//! over equal-length slices, which LLVM turns into SIMD code.

use crate::geometry::Rays;

#[derive(Default)]
pub struct GatheredRays {
    pub origin: [Vec<f32>; 3],
    pub dir: [Vec<f32>; 3],
    pub tmin: Vec<f32>,
    pub tmax: Vec<f32>,
}

impl GatheredRays {
    /// Gathers the rays `group` (batch indices, at least one) of `rays`.
    pub fn gather(&mut self, rays: Rays<'_>, group: &[u32]) {
        let [ox, oy, oz] = &mut self.origin;
        let [dx, dy, dz] = &mut self.dir;
        let columns = [
            (ox, rays.ox),
            (oy, rays.oy),
            (oz, rays.oz),
            (dx, rays.dx),
            (dy, rays.dy),
            (dz, rays.dz),
            (&mut self.tmin, rays.tmin),
            (&mut self.tmax, rays.tmax),
        ];
        // An unsplit packet is a run of consecutive rays: copied, not gathered.
        let first = group[0] as usize;
        let run = group
            .iter()
            .enumerate()
            .fold(true, |run, (p, &i)| run & (i as usize == first + p));
        for (dst, src) in columns {
            dst.clear();
            if run {
                dst.extend_from_slice(&src[first..first + group.len()]);
            } else {
                dst.extend(group.iter().map(|&i| src[i as usize]));
            }
        }
    }
}
