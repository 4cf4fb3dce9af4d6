//! The C interface of `shim.cpp`, and tinybvh's `Ray` as Rust lays it out. The shim asserts the
//! same sizes and offsets with `static_assert`; the tests below hold this side to them, and
//! `TinyBvh::build` refuses to run against a shim whose `Ray` is another size.

/// tinybvh's `BVH_FAR`: the far end it gives a ray with no end. Far ends beyond it are clamped to
/// it: tinybvh checks each ray for NaN by summing its components, and an infinite far end could
/// make that sum +∞ − ∞ (and the process exits).
pub const BVH_FAR: f32 = 1e30;

/// tinybvh's `RAY_MASK_INTERSECT_ALL`, which its `Ray` constructor sets.
const MASK_ALL: u32 = 0xFFFF;

/// tinybvh's `Ray` (tinybvh 1.6.8 with `INST_IDX_BITS == 32`): 128 bytes, 64-byte aligned: `O`,
/// `mask`, `D`, `instIdx`, `rD`, then the `Intersection` (`inst`, `t`, `u`, `v`, `prim`, and 64
/// bytes of user data).
#[repr(C, align(64))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TinyRay {
    pub origin: [f32; 3],
    mask: u32,
    pub dir: [f32; 3],
    inst_idx: u32,
    /// `rD`, the reciprocal direction: set by the shim as tinybvh's own `Ray` constructor does.
    recip: [f32; 3],
    hit_inst: u32,
    /// The far end before tracing, the nearest hit's distance after (smaller only on a hit).
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub prim: u32,
    user: [u32; 16],
}

impl TinyRay {
    /// A ray from `origin` along `dir` (not normalised: tinybvh's distances are then in units of
    /// `dir`, as ours are) up to `far`, clamped to `BVH_FAR`.
    #[inline(always)]
    pub fn new(origin: [f32; 3], dir: [f32; 3], far: f32) -> TinyRay {
        TinyRay {
            origin,
            mask: MASK_ALL,
            dir,
            inst_idx: 0,
            recip: [0.0; 3],
            hit_inst: 0,
            t: far.min(BVH_FAR),
            u: 0.0,
            v: 0.0,
            prim: 0,
            user: [0; 16],
        }
    }
}

/// The shim's opaque structure (`struct raylab_tinybvh`).
#[repr(C)]
pub struct Handle {
    _private: [u8; 0],
}

extern "C" {
    pub fn raylab_tinybvh_version() -> u32;
    pub fn raylab_tinybvh_has_simd() -> u32;
    pub fn raylab_tinybvh_ray_size() -> u32;
    pub fn raylab_tinybvh_build(
        triangles: *const f32,
        count: u32,
        layout: u32,
        builder: u32,
        iterations: u32,
    ) -> *mut Handle;
    pub fn raylab_tinybvh_free(bvh: *mut Handle);
    pub fn raylab_tinybvh_intersect(bvh: *const Handle, rays: *mut TinyRay, count: usize);
    pub fn raylab_tinybvh_occluded(
        bvh: *const Handle,
        rays: *mut TinyRay,
        count: usize,
        occluded: *mut u8,
    );
    pub fn raylab_tinybvh_intersect256(bvh: *const Handle, packet: *mut TinyRay, sse: u32) -> u32;
}

#[cfg(test)]
mod tests {
    use std::mem::{align_of, offset_of, size_of};

    use super::*;

    #[test]
    fn the_ray_is_laid_out_as_tinybvh_lays_it_out() {
        assert_eq!((size_of::<TinyRay>(), align_of::<TinyRay>()), (128, 64));
        assert_eq!(size_of::<TinyRay>() as u32, unsafe {
            raylab_tinybvh_ray_size()
        });
        assert_eq!(
            [
                offset_of!(TinyRay, origin),
                offset_of!(TinyRay, dir),
                offset_of!(TinyRay, recip),
                offset_of!(TinyRay, hit_inst),
                offset_of!(TinyRay, t),
                offset_of!(TinyRay, u),
                offset_of!(TinyRay, v),
                offset_of!(TinyRay, prim),
                offset_of!(TinyRay, user),
            ],
            [0, 16, 32, 44, 48, 52, 56, 60, 64]
        );
    }

    #[test]
    fn the_shim_is_tinybvh_1_6_8_with_its_simd_kernels() {
        assert_eq!(
            unsafe { raylab_tinybvh_version() },
            (1 << 16) | (6 << 8) | 8
        );
        assert_eq!(unsafe { raylab_tinybvh_has_simd() }, 1);
    }
}
