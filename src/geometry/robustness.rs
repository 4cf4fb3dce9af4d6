//! The `robust` switch of our tracers, as a type parameter of their kernels: which ray–box and
//! ray–triangle tests they run. It means what Embree's `robust` (`RTC_SCENE_FLAG_ROBUST`) means,
//! so a table can compare robust with robust and fast with fast:
//!
//! - `Robust` (`robust = true`, our default): the conservative slab test (Ize 2013 §3: far
//!   distances scaled by `FAR_SCALE`) and the watertight triangle test (Woop et al. 2013).
//! - `Fast` (`robust = false`, Embree's default): plain slabs (no conservative rounding of the
//!   t-interval) and the Möller–Trumbore triangle test, as Embree's non-robust mode
//!   (`TriangleMIntersector1Moeller` with its non-conservative node test). Not watertight: rays
//!   through shared edges and vertices may leak.

use glam::Vec3;

use super::aabb::FAR_SCALE;
use super::moller::MollerRay;
use super::{Triangle, WatertightRay};
use crate::error::Result;
use crate::params::Params;

/// The parameter that picks the tests, named and meant as Embree's `robust`: accepted by every
/// tracer of ours.
pub const PARAM: &str = "robust";

/// The `robust` parameter of `params` (default `true`).
pub fn robust_param(params: &Params) -> Result<bool> {
    params.get_or(PARAM, true)
}

/// The pair of tests a kernel runs (`Robust` or `Fast`).
pub trait RayTests: Copy + Default + Send + Sync + 'static {
    /// The `robust` parameter's value that picks these tests.
    const ROBUST: bool;
    /// What a slab test multiplies each far distance by.
    const FAR_SCALE: f32;
    /// A ray prepared for many triangle tests.
    type TriangleRay: Copy + Send + Sync;
    fn triangle_ray(origin: Vec3, dir: Vec3) -> Self::TriangleRay;
    /// `triangle_ray` of a ray whose watertight frame (`WatertightRay::parts`: axes, shear) is
    /// already known, so the watertight test needs nothing more; `dir` is asked for only by a
    /// test that reads the direction.
    fn triangle_ray_in_frame(
        origin: [f32; 3],
        frame: ([usize; 3], [f32; 3]),
        dir: impl FnOnce() -> Vec3,
    ) -> Self::TriangleRay;
    /// `(t, u, v)` if `ray` hits `tri` with `tmin ≤ t ≤ tmax` (`u` weights v1, `v` weights v2).
    fn intersect(
        ray: &Self::TriangleRay,
        tri: &Triangle,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)>;
}

/// Conservative slabs and watertight triangles (`robust = true`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Robust;

/// Plain slabs and Möller–Trumbore triangles (`robust = false`).
#[derive(Clone, Copy, Debug, Default)]
pub struct Fast;

impl RayTests for Robust {
    const ROBUST: bool = true;
    const FAR_SCALE: f32 = FAR_SCALE;
    type TriangleRay = WatertightRay;
    #[inline(always)]
    fn triangle_ray(origin: Vec3, dir: Vec3) -> WatertightRay {
        WatertightRay::new(origin, dir)
    }
    #[inline(always)]
    fn triangle_ray_in_frame(
        origin: [f32; 3],
        (k, shear): ([usize; 3], [f32; 3]),
        _: impl FnOnce() -> Vec3,
    ) -> WatertightRay {
        WatertightRay::from_parts(origin, k, shear)
    }
    #[inline(always)]
    fn intersect(
        ray: &WatertightRay,
        tri: &Triangle,
        tmin: f32,
        tmax: f32,
    ) -> Option<(f32, f32, f32)> {
        ray.intersect(tri, tmin, tmax)
    }
}

impl RayTests for Fast {
    const ROBUST: bool = false;
    const FAR_SCALE: f32 = 1.0;
    type TriangleRay = MollerRay;
    #[inline(always)]
    fn triangle_ray(origin: Vec3, dir: Vec3) -> MollerRay {
        MollerRay::new(origin, dir)
    }
    #[inline(always)]
    fn triangle_ray_in_frame(
        origin: [f32; 3],
        _: ([usize; 3], [f32; 3]),
        dir: impl FnOnce() -> Vec3,
    ) -> MollerRay {
        MollerRay::new(Vec3::from(origin), dir())
    }
    #[inline(always)]
    fn intersect(ray: &MollerRay, tri: &Triangle, tmin: f32, tmax: f32) -> Option<(f32, f32, f32)> {
        ray.intersect(tri, tmin, tmax)
    }
}
