//! The tinybvh baseline structure: one of tinybvh's CPU layouts (J. Bikker, `tiny_bvh.h` 1.6.8)
//! built by tinybvh's own builders over the mesh, through raylab's C++ shim (`shim.cpp`, compiled
//! by build.rs against the header `.ci/fetch-tinybvh` caches; cfg `tinybvh`).
//!
//! - `BVH`: the 2-wide tree of 32-byte nodes (Wald's layout), its single-ray kernels and the
//!   256-ray packet kernel `Intersect256Rays`;
//! - `BVH4_CPU`: 4-wide SSE nodes; `BVH8_CPU`: 8-wide AVX2 + FMA nodes after Fuetterling et al.
//!   2017, converted by tinybvh from its binary tree.
//!
//! Parameters: `builder` = `sah` (tinybvh's binned SAH, 8 bins; `Build`) or `sbvh` (spatial
//! splits, `BuildHQ`), and `optimize` = N, tinybvh's `Optimize` (reinsertion, Meister & Bittner
//! 2018) run N times after the build (0, the default: not run). Triangles keep the mesh's order:
//! tinybvh's primitive index is the scene's.
//!
//! **Scale.** tinybvh's Möller–Trumbore tests reject a triangle as parallel to the ray when
//! |e1 · (D × e2)| — twice its area, projected — is below an absolute 1e-6 (1e-7 in the packet
//! kernel), so on a mesh of small triangles it misses most of them (dragon-202k, edges ~5e-4 scene
//! units: a fifth of the camera rays). tinybvh is handed the scene scaled by a power of two
//! (`TinyBvh::scale`) that brings the median triangle's doubled area to about 1: the scaling is
//! exact in floating point (bar under- and overflow), every distance tinybvh computes is the
//! unscaled one times the same power of two, and only those absolute thresholds move. Tracers scale
//! ray origins and far ends in and hit distances out (`TinyBvh::to_tiny`, `TinyBvh::from_tiny`).

pub mod ffi;

use std::fmt;
use std::ptr::NonNull;
use std::time::Instant;

use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::params::Params;
use ffi::TinyRay;

/// Where the header was fetched from, as build.rs found it.
pub const SOURCE: &str = env!("RAYLAB_TINYBVH_SOURCE");

/// The linked tinybvh's version, as its header states it ("1.6.8").
pub fn version() -> String {
    // SAFETY: a plain query of the linked shim.
    let v = unsafe { ffi::raylab_tinybvh_version() };
    format!("{}.{}.{}", v >> 16, (v >> 8) & 255, v & 255)
}

/// Which of tinybvh's layouts a tracer traverses (the number is its width).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum TinyLayout {
    /// `BVH`
    Binary = 2,
    /// `BVH4_CPU`
    Wide4 = 4,
    /// `BVH8_CPU`
    Wide8 = 8,
}

impl TinyLayout {
    /// The structure's name (`AccelKind::name`).
    pub fn name(self) -> &'static str {
        match self {
            TinyLayout::Binary => "tinybvh-bvh",
            TinyLayout::Wide4 => "tinybvh-bvh4-cpu",
            TinyLayout::Wide8 => "tinybvh-bvh8-cpu",
        }
    }

    /// tinybvh's name of the layout.
    pub fn class(self) -> &'static str {
        match self {
            TinyLayout::Binary => "BVH",
            TinyLayout::Wide4 => "BVH4_CPU",
            TinyLayout::Wide8 => "BVH8_CPU",
        }
    }
}

/// tinybvh's builders.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TinyBuilder {
    /// Binned SAH (`Build`).
    #[default]
    Sah = 0,
    /// Spatial splits (`BuildHQ`, Stich et al. 2009).
    Sbvh = 1,
}

/// How a tinybvh structure is built: the structure parameters `builder` and `optimize`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TinyBvhConfig {
    pub builder: TinyBuilder,
    /// Rounds of `Optimize` after the build (0: none; tinybvh's own default when called is 25).
    pub optimize: u32,
}

impl TinyBvhConfig {
    pub const PARAMS: &'static [&'static str] = &["builder", "optimize"];
    /// More rounds than this is a typo, not an experiment (each round rebuilds the tree's top).
    pub const OPTIMIZE_LIMIT: u32 = 1000;

    pub fn from_params(p: &Params) -> Result<Self> {
        let builder = match p.0.get("builder").map(String::as_str) {
            None | Some("sah") => TinyBuilder::Sah,
            Some("sbvh") => TinyBuilder::Sbvh,
            Some(other) => {
                return Err(Error::usage(format!(
                    "parameter builder = {other:?} is not a tinybvh builder (known: sah, sbvh)"
                )))
            }
        };
        let optimize = p.get_or("optimize", 0u32)?;
        if optimize > Self::OPTIMIZE_LIMIT {
            return Err(Error::usage(format!(
                "parameter optimize = {optimize} is out of range (0 to {})",
                Self::OPTIMIZE_LIMIT
            )));
        }
        Ok(TinyBvhConfig { builder, optimize })
    }
}

/// A tinybvh structure over a mesh, read-only once built.
pub struct TinyBvh {
    /// `None` for an empty mesh (tinybvh cannot build over nothing): every ray misses.
    handle: Option<NonNull<ffi::Handle>>,
    pub layout: TinyLayout,
    pub config: TinyBvhConfig,
    pub triangles: usize,
    /// The power of two tinybvh's copy of the scene is scaled by (see the module's notes).
    pub scale: f32,
    /// Wall time of `build`: copying the vertices, tinybvh's build, conversion and optimisation.
    pub build_seconds: f64,
}

// SAFETY: the shim's structure is only read after `build` returns: `Intersect`, `IsOccluded` and
// `Intersect256Rays` are `const` members of the tinybvh layouts that write only to the rays they
// are handed (tiny_bvh.h has no `mutable` member), so any number of threads may trace through
// one structure at once, and it may be dropped on any thread.
unsafe impl Send for TinyBvh {}
unsafe impl Sync for TinyBvh {}

impl fmt::Debug for TinyBvh {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("TinyBvh")
            .field("layout", &self.layout)
            .field("config", &self.config)
            .field("triangles", &self.triangles)
            .finish()
    }
}

impl Drop for TinyBvh {
    fn drop(&mut self) {
        if let Some(handle) = self.handle {
            // SAFETY: made by raylab_tinybvh_build and freed only here.
            unsafe { ffi::raylab_tinybvh_free(handle.as_ptr()) }
        }
    }
}

impl TinyBvh {
    pub fn build(
        triangles: &[Triangle],
        layout: TinyLayout,
        config: TinyBvhConfig,
    ) -> Result<TinyBvh> {
        let start = Instant::now();
        let scale = scale_for(triangles);
        let vertices: Vec<[f32; 4]> = triangles
            .iter()
            .flat_map(|t| t.v.map(|p| [p.x * scale, p.y * scale, p.z * scale, 0.0]))
            .collect();
        Self::build_from(&vertices, layout, config, scale, start)
    }

    /// The structure over `vertices`, three (x, y, z, 0) a triangle, already scaled by `scale`.
    pub(crate) fn build_from(
        vertices: &[[f32; 4]],
        layout: TinyLayout,
        config: TinyBvhConfig,
        scale: f32,
        start: Instant,
    ) -> Result<TinyBvh> {
        // SAFETY: plain queries of the linked shim.
        let (ray_size, simd) = unsafe {
            (
                ffi::raylab_tinybvh_ray_size(),
                ffi::raylab_tinybvh_has_simd(),
            )
        };
        if ray_size as usize != size_of::<TinyRay>() {
            return Err(Error::runtime(format!(
                "the tinybvh shim's Ray is {ray_size} bytes, raylab's {}",
                size_of::<TinyRay>()
            )));
        }
        if simd == 0 && layout != TinyLayout::Binary {
            return Err(Error::runtime(format!(
                "tinybvh was compiled without SSE/AVX2 + FMA here: {} is unavailable",
                layout.class()
            )));
        }
        let triangles = vertices.len() / 3;
        let count = u32::try_from(triangles)
            .map_err(|_| Error::runtime("tinybvh indexes triangles with 32 bits"))?;
        let handle = if triangles == 0 {
            None
        } else {
            // SAFETY: `vertices` holds 3 × count float4; the shim copies them.
            let raw = unsafe {
                ffi::raylab_tinybvh_build(
                    vertices.as_ptr().cast(),
                    count,
                    layout as u32,
                    config.builder as u32,
                    config.optimize,
                )
            };
            Some(NonNull::new(raw).ok_or_else(|| {
                Error::runtime(format!(
                    "tinybvh could not build {} (out of memory?)",
                    layout.class()
                ))
            })?)
        };
        Ok(TinyBvh {
            handle,
            layout,
            config,
            triangles,
            scale,
            build_seconds: start.elapsed().as_secs_f64(),
        })
    }

    /// The ray from `origin` along `dir` up to `far` (scene units) as tinybvh takes it over its
    /// scaled copy of the scene.
    #[inline(always)]
    pub fn to_tiny(&self, origin: glam::Vec3, dir: glam::Vec3, far: f32) -> TinyRay {
        TinyRay::new(
            (origin * self.scale).to_array(),
            dir.to_array(),
            far * self.scale,
        )
    }

    /// A distance tinybvh found, in scene units.
    #[inline(always)]
    pub fn from_tiny(&self, t: f32) -> f32 {
        t / self.scale
    }

    /// Closest hits: each ray's `t`, `u`, `v` and `prim` are those of its nearest triangle before
    /// `t`, and unchanged where there is none. Rays must be finite (NaN ones make tinybvh exit).
    pub fn intersect(&self, rays: &mut [TinyRay]) {
        if let Some(handle) = self.handle {
            // SAFETY: a live structure and `rays.len()` rays.
            unsafe { ffi::raylab_tinybvh_intersect(handle.as_ptr(), rays.as_mut_ptr(), rays.len()) }
        }
    }

    /// `occluded[i]` becomes whether a triangle lies on ray `i` before its `t`.
    pub fn occluded(&self, rays: &mut [TinyRay], occluded: &mut [u8]) {
        assert_eq!(rays.len(), occluded.len());
        match self.handle {
            // SAFETY: a live structure, `rays.len()` rays and as many flags.
            Some(handle) => unsafe {
                ffi::raylab_tinybvh_occluded(
                    handle.as_ptr(),
                    rays.as_mut_ptr(),
                    rays.len(),
                    occluded.as_mut_ptr(),
                )
            },
            None => occluded.fill(0),
        }
    }

    /// Closest hits of 256 rays sharing an origin, in the order `Intersect256Rays` expects
    /// (`tracers::tinybvh::tile`): its first-hit, frustum and ranged traversal (`sse`: its SSE
    /// version). False, nothing traced, on a layout other than the binary one.
    pub fn intersect256(&self, packet: &mut [TinyRay; 256], sse: bool) -> bool {
        match self.handle {
            None => self.layout == TinyLayout::Binary,
            // SAFETY: a live structure and 256 rays.
            Some(handle) => unsafe {
                ffi::raylab_tinybvh_intersect256(handle.as_ptr(), packet.as_mut_ptr(), sse as u32)
                    == 1
            },
        }
    }
}

/// The power of two that brings the median triangle's doubled area (|e1 × e2|) to about 1, kept
/// small enough that no scaled coordinate exceeds 2⁶⁰; 1 for a mesh of degenerate triangles.
pub fn scale_for(triangles: &[Triangle]) -> f32 {
    let mut doubled: Vec<f32> = triangles
        .iter()
        .map(|t| t.normal().length())
        .filter(|a| a.is_finite() && *a > 0.0)
        .collect();
    if doubled.is_empty() {
        return 1.0;
    }
    let middle = doubled.len() / 2;
    let median = *doubled.select_nth_unstable_by(middle, f32::total_cmp).1;
    let largest = triangles
        .iter()
        .flat_map(|t| t.v)
        .map(|p| p.abs().max_element())
        .fold(0.0f32, f32::max);
    // Area scales with the square of lengths: half the exponent.
    let mut exponent = (-0.5 * median.log2()).round() as i32;
    if largest > 0.0 {
        exponent = exponent.min(60 - largest.log2().ceil() as i32);
    }
    2f32.powi(exponent.clamp(-100, 100))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn triangle(edge: f32, at: Vec3) -> Triangle {
        Triangle::new(at, at + Vec3::X * edge, at + Vec3::Y * edge)
    }

    #[test]
    fn the_scale_is_a_power_of_two_bringing_triangles_to_unit_size() {
        let small: Vec<Triangle> = (0..5).map(|i| triangle(1e-3, Vec3::X * i as f32)).collect();
        let s = scale_for(&small);
        assert_eq!(s, 2f32.powi(10), "edges 1e-3: doubled area 1e-6 ≈ 2^-20");
        assert_eq!(s.log2().fract(), 0.0);
        assert_eq!(scale_for(&[triangle(1.0, Vec3::ZERO)]), 1.0);
        // Far from the origin, coordinates stay below 2^60 scaled.
        let far = [triangle(1e-3, Vec3::splat(1e17))];
        assert!(scale_for(&far) * 1e17 <= 2f32.powi(60));
        assert_eq!(scale_for(&[triangle(0.0, Vec3::ZERO)]), 1.0, "degenerate");
        assert_eq!(scale_for(&[]), 1.0);
    }

    /// A ray down onto a triangle of edge 1e-3: tinybvh's unscaled test would call it parallel
    /// (|det| = 1e-6 is not above its threshold); scaled, every layout finds it at the right
    /// distance.
    #[test]
    fn small_triangles_are_hit_at_their_distance_in_every_layout() {
        let tris = [triangle(1e-3, Vec3::ZERO)];
        for layout in [TinyLayout::Binary, TinyLayout::Wide4, TinyLayout::Wide8] {
            let bvh = TinyBvh::build(&tris, layout, TinyBvhConfig::default()).unwrap();
            let origin = Vec3::new(2e-4, 3e-4, 0.5);
            let mut rays = [bvh.to_tiny(origin, Vec3::NEG_Z, f32::INFINITY)];
            rays[0].prim = u32::MAX;
            bvh.intersect(&mut rays);
            assert_eq!(rays[0].prim, 0, "{layout:?}");
            assert!((bvh.from_tiny(rays[0].t) - 0.5).abs() < 1e-6, "{layout:?}");
            let mut flags = [0u8];
            let mut fresh = [bvh.to_tiny(origin, Vec3::NEG_Z, f32::INFINITY)];
            bvh.occluded(&mut fresh, &mut flags);
            assert_eq!(flags, [1], "{layout:?}");
        }
    }
}
