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
        let count = u32::try_from(triangles.len())
            .map_err(|_| Error::runtime("tinybvh indexes triangles with 32 bits"))?;
        let handle = if triangles.is_empty() {
            None
        } else {
            let vertices: Vec<[f32; 4]> = triangles
                .iter()
                .flat_map(|t| t.v.map(|p| [p.x, p.y, p.z, 0.0]))
                .collect();
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
            triangles: triangles.len(),
            build_seconds: start.elapsed().as_secs_f64(),
        })
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
