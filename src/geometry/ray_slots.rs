//! A ray batch sized up front and cut into disjoint writable parts, so that parallel generators
//! fill it in place: no per-part batches to join afterwards, and a batch refilled pass after pass
//! keeps its memory (a renderer's ray buffers are not fresh pages every frame).

use super::ray::{Ray, RayBatch, RayKind};

/// Rays `start..start + len` of a batch, writable: each of them set exactly once with `set`.
pub struct RaySlots<'a> {
    origin: [&'a mut [f32]; 3],
    dir: [&'a mut [f32]; 3],
    tmin: &'a mut [f32],
    tmax: &'a mut [f32],
    pixel: &'a mut [u32],
    /// Empty when the batch has no explicit packets.
    packet_start: &'a mut [bool],
    /// Empty when the batch has no ray times.
    time: &'a mut [f32],
}

impl RaySlots<'_> {
    /// Ray `k` of the part: `ray` from `pixel`, beginning an explicit packet when
    /// `packet_start` (ignored by a batch without explicit packets).
    #[inline(always)]
    pub fn set(&mut self, k: usize, ray: &Ray, pixel: u32, packet_start: bool) {
        for axis in 0..3 {
            self.origin[axis][k] = ray.origin[axis];
            self.dir[axis][k] = ray.dir[axis];
        }
        self.tmin[k] = ray.tmin;
        self.tmax[k] = ray.tmax;
        self.pixel[k] = pixel;
        if let Some(start) = self.packet_start.get_mut(k) {
            *start = packet_start;
        }
        if let Some(time) = self.time.get_mut(k) {
            *time = ray.time;
        }
    }
}

/// `values` cut into consecutive parts of `lens`.
fn cut<'a, T>(mut values: &'a mut [T], lens: &[usize]) -> Vec<&'a mut [T]> {
    lens.iter()
        .map(|&n| {
            let (part, rest) = std::mem::take(&mut values).split_at_mut(n);
            values = rest;
            part
        })
        .collect()
}

impl RayBatch {
    /// The batch resized to `lens`' sum rays of `kind`, with explicit packets when `packets` and
    /// ray times when `timed`, and cut into parts of `lens` rays, in order. Its memory is reused;
    /// what the rays held before is left to the parts to overwrite, every ray of them.
    pub fn slots(
        &mut self,
        kind: RayKind,
        lens: &[usize],
        packets: bool,
        timed: bool,
    ) -> Vec<RaySlots<'_>> {
        let total: usize = lens.iter().sum();
        self.kind = Some(kind);
        self.camera = None;
        for v in self.columns_mut() {
            v.resize(total, 0.0);
        }
        self.pixel.resize(total, 0);
        self.packet_start
            .resize(if packets { total } else { 0 }, false);
        self.time.resize(if timed { total } else { 0 }, 0.0);
        let packet_lens: Vec<usize> = lens.iter().map(|&n| n * packets as usize).collect();
        let time_lens: Vec<usize> = lens.iter().map(|&n| n * timed as usize).collect();
        let mut ox = cut(&mut self.ox, lens).into_iter();
        let mut oy = cut(&mut self.oy, lens).into_iter();
        let mut oz = cut(&mut self.oz, lens).into_iter();
        let mut dx = cut(&mut self.dx, lens).into_iter();
        let mut dy = cut(&mut self.dy, lens).into_iter();
        let mut dz = cut(&mut self.dz, lens).into_iter();
        let mut tmin = cut(&mut self.tmin, lens).into_iter();
        let mut tmax = cut(&mut self.tmax, lens).into_iter();
        let mut pixel = cut(&mut self.pixel, lens).into_iter();
        let mut packet_start = cut(&mut self.packet_start, &packet_lens).into_iter();
        let mut time = cut(&mut self.time, &time_lens).into_iter();
        let next = move || -> Option<RaySlots<'_>> {
            Some(RaySlots {
                origin: [ox.next()?, oy.next()?, oz.next()?],
                dir: [dx.next()?, dy.next()?, dz.next()?],
                tmin: tmin.next()?,
                tmax: tmax.next()?,
                pixel: pixel.next()?,
                packet_start: packet_start.next()?,
                time: time.next()?,
            })
        };
        std::iter::from_fn(next).collect()
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::test_util::batch_fields;

    #[test]
    fn parts_filled_in_any_order_make_the_batch_pushes_make() {
        let ray = |i: usize| {
            Ray::new(Vec3::splat(i as f32), Vec3::X, 0.5, 10.0 + i as f32).at_time(i as f32 / 8.0)
        };
        let mut pushed = RayBatch::new(RayKind::SoftShadow);
        for i in 0..7 {
            match i % 3 == 0 {
                true => pushed.push_packet_start(ray(i), 100 + i as u32),
                false => pushed.push(ray(i), 100 + i as u32),
            }
        }
        // A batch that held other rays before, more of them: its memory is reused.
        let mut filled = RayBatch::new(RayKind::Primary);
        for i in 0..20 {
            filled.push(ray(50 + i), 7);
        }
        let lens = [3, 0, 4];
        let mut parts = filled.slots(RayKind::SoftShadow, &lens, true, true);
        for (part, start) in parts.iter_mut().zip([0, 3, 3]).rev() {
            for k in (0..part.pixel.len()).rev() {
                let i = start + k;
                part.set(k, &ray(i), 100 + i as u32, i % 3 == 0);
            }
        }
        assert_eq!(batch_fields(&filled), batch_fields(&pushed));
    }
}
