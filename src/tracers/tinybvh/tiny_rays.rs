//! Rays in tinybvh's layout: what a tinybvh user holds before calling it. Staged untimed for a
//! timed pass (`Kernel::stage_closest`), converted on the spot for a counted one.

use crate::accel::tinybvh::ffi::TinyRay;
use crate::accel::TinyBvh;
use crate::geometry::{Hit, Rays};

/// Ray `i` as `bvh` takes it, with the tmin it was shifted by; `None` for an ill-formed ray.
#[inline(always)]
pub(super) fn tiny_ray(bvh: &TinyBvh, rays: &Rays<'_>, i: usize) -> Option<(TinyRay, f32)> {
    let r = rays.ray(i);
    if !r.is_well_formed() {
        return None;
    }
    let mut ray = if r.tmin > 0.0 {
        bvh.to_tiny(r.at(r.tmin), r.dir, r.tmax - r.tmin)
    } else {
        bvh.to_tiny(r.origin, r.dir, r.tmax)
    };
    // No triangle index is this: a ray still carrying it after tracing missed.
    ray.prim = Hit::NO_PRIM;
    Some((ray, r.tmin))
}

/// The hit tinybvh left in `ray`, handed over with its tmin shifted by `shift`.
#[inline(always)]
pub(super) fn hit_of(bvh: &TinyBvh, ray: &TinyRay, shift: f32) -> Hit {
    if ray.prim == Hit::NO_PRIM {
        return Hit::MISS;
    }
    Hit {
        t: bvh.from_tiny(ray.t) + shift,
        prim: ray.prim,
        u: ray.u,
        v: ray.v,
    }
}

/// The well-formed rays of a batch in tinybvh's layout, each with the tmin it was shifted by and
/// its index in the batch; the ill-formed ones are not handed over and miss. Tracing overwrites
/// the rays (as tinybvh's calls do): stage again for another pass.
pub(super) struct TinyRays {
    rays: Vec<TinyRay>,
    shifts: Vec<f32>,
    index: Vec<u32>,
    flags: Vec<u8>,
}

impl TinyRays {
    pub fn stage(bvh: &TinyBvh, rays: &Rays<'_>) -> Self {
        let mut staged = TinyRays {
            rays: Vec::with_capacity(rays.len()),
            shifts: Vec::with_capacity(rays.len()),
            index: Vec::with_capacity(rays.len()),
            flags: Vec::new(),
        };
        for i in 0..rays.len() {
            if let Some((ray, shift)) = tiny_ray(bvh, rays, i) {
                staged.rays.push(ray);
                staged.shifts.push(shift);
                staged.index.push(i as u32);
            }
        }
        staged.flags = vec![0; staged.rays.len()];
        staged
    }

    /// Closest hits, `hits[i]` for ray `i` of the staged batch: one `Intersect` per ray.
    pub fn intersect(&mut self, bvh: &TinyBvh, hits: &mut [Hit]) {
        hits.fill(Hit::MISS);
        bvh.intersect(&mut self.rays);
        for ((ray, &shift), &i) in self.rays.iter().zip(&self.shifts).zip(&self.index) {
            hits[i as usize] = hit_of(bvh, ray, shift);
        }
    }

    /// Occlusion, `occluded[i]` for ray `i` of the staged batch: one `IsOccluded` per ray.
    pub fn occluded(&mut self, bvh: &TinyBvh, occluded: &mut [bool]) {
        occluded.fill(false);
        bvh.occluded(&mut self.rays, &mut self.flags);
        for (&flag, &i) in self.flags.iter().zip(&self.index) {
            occluded[i as usize] = flag != 0;
        }
    }
}
