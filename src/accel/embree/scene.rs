//! An Embree scene over our `Mesh`: one triangle geometry whose primitive `i` is our triangle `i`,
//! committed once and then traversed concurrently by any number of tracers. Built the same way by
//! Embree 3 and Embree 4 (`EmbreeApi`).

use std::fmt;
use std::sync::Arc;
use std::time::Instant;

use super::api::{Embree3, EmbreeApi};
use super::ffi::{self, RTCBufferType::*, RTCFormat::*};
use super::{Device, EmbreeConfig};
use crate::error::{Error, Result};
use crate::scene::Mesh;

pub struct EmbreeScene<A: EmbreeApi = Embree3> {
    device: Arc<Device<A>>,
    raw: ffi::RTCScene,
    /// The triangle geometry (geomID 0), kept to update its vertices; `None` for an empty mesh,
    /// which Embree takes as a committed scene without geometry that every ray misses.
    geometry: Option<ffi::RTCGeometry>,
    triangle_count: usize,
    /// Two time steps (shutter open and close, `build_moving`): rays are traced at their time.
    moving: bool,
    pub config: EmbreeConfig,
    /// Wall time of the last build or refit: buffer fill plus commit.
    pub build_seconds: f64,
    /// Refits since the scene was built (its tree keeps the build's topology).
    pub refits: u32,
}

// SAFETY: Embree allows rtcIntersect*/rtcOccluded* on a committed scene from many threads at
// once; everything that changes the scene (`refit`) takes `&mut self`.
unsafe impl<A: EmbreeApi> Send for EmbreeScene<A> {}
unsafe impl<A: EmbreeApi> Sync for EmbreeScene<A> {}

impl<A: EmbreeApi> EmbreeScene<A> {
    pub fn build(device: Arc<Device<A>>, mesh: &Mesh, config: EmbreeConfig) -> Result<Self> {
        Self::build_timed(device, mesh, None, config)
    }

    /// A scene whose triangles move linearly from `open` to `close` (same count and order) over
    /// the shutter interval: Embree's motion blur with two time steps
    /// (`rtcSetGeometryTimeStepCount`, one vertex buffer per step); each ray is traced at its
    /// `time` in [0, 1].
    pub fn build_moving(
        device: Arc<Device<A>>,
        open: &Mesh,
        close: &Mesh,
        config: EmbreeConfig,
    ) -> Result<Self> {
        if open.len() != close.len() {
            return Err(Error::runtime(format!(
                "a moving Embree scene needs the same triangles at both ends: {} and {}",
                open.len(),
                close.len()
            )));
        }
        Self::build_timed(device, open, Some(close), config)
    }

    fn build_timed(
        device: Arc<Device<A>>,
        mesh: &Mesh,
        close: Option<&Mesh>,
        config: EmbreeConfig,
    ) -> Result<Self> {
        let start = Instant::now();
        // Vertex indices are 32-bit: three per triangle.
        if mesh.len() > (u32::MAX / 3) as usize {
            return Err(Error::runtime(format!(
                "{} cannot index {} triangles with 32-bit vertex ids",
                A::NAME,
                mesh.len()
            )));
        }
        // SAFETY: a live device.
        let raw = unsafe { A::new_scene(device.raw()) };
        // Owned from here on, so Drop releases it on every error path (a null one is skipped).
        let mut scene = EmbreeScene {
            device,
            raw,
            geometry: None,
            triangle_count: mesh.len(),
            moving: close.is_some(),
            config,
            build_seconds: 0.0,
            refits: 0,
        };
        created(&scene.device, raw, "creating a scene")?;
        // SAFETY: a live scene, not yet committed.
        unsafe {
            A::set_scene_flags(raw, config.scene_flags());
            A::set_scene_build_quality(raw, config.quality.scene());
        }
        if !mesh.is_empty() {
            scene.attach_triangles(mesh, close)?;
        }
        scene.commit("building a scene")?;
        scene.build_seconds = start.elapsed().as_secs_f64();
        Ok(scene)
    }

    fn attach_triangles(&mut self, mesh: &Mesh, close: Option<&Mesh>) -> Result<()> {
        let n = mesh.len();
        let device = self.device.raw();
        // SAFETY: a live device.
        let geometry =
            unsafe { A::new_geometry(device, ffi::RTCGeometryType::RTC_GEOMETRY_TYPE_TRIANGLE) };
        // Owned by `self` as soon as it exists, so Drop releases it on every error path below.
        self.geometry = (!geometry.is_null()).then_some(geometry);
        created(&self.device, geometry, "creating the triangle geometry")?;
        // SAFETY: a live geometry. Embree allocates both buffers (padding the vertex buffer for
        // its 16-byte loads) and owns them. Three vertices per triangle, none shared: triangle i
        // reads vertices 3i, 3i+1, 3i+2 and keeps primitive id i.
        // With motion, one vertex buffer per time step (slot 0: open, slot 1: close).
        let steps = if close.is_some() { 2 } else { 1 };
        let indices = unsafe {
            A::set_geometry_build_quality(geometry, self.config.quality.geometry());
            A::set_geometry_time_step_count(geometry, steps);
            for slot in 0..steps {
                A::set_new_geometry_buffer(
                    geometry,
                    RTC_BUFFER_TYPE_VERTEX,
                    slot,
                    RTC_FORMAT_FLOAT3,
                    12,
                    3 * n,
                );
            }
            A::set_new_geometry_buffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, n)
        };
        created(
            &self.device,
            indices,
            "allocating the vertex and index buffers",
        )?;
        // SAFETY: a buffer of n UINT3 items.
        let indices = unsafe { std::slice::from_raw_parts_mut(indices as *mut [u32; 3], n) };
        for (i, index) in indices.iter_mut().enumerate() {
            let first = 3 * i as u32;
            *index = [first, first + 1, first + 2];
        }
        self.write_vertices(mesh, 0);
        if let Some(close) = close {
            self.write_vertices(close, 1);
        }
        // SAFETY: live geometry and scene; the scene takes its own reference to the geometry.
        let id = unsafe {
            A::commit_geometry(geometry);
            A::attach_geometry(self.raw, geometry)
        };
        self.device.check("attaching the triangle geometry")?;
        debug_assert_eq!(id, 0, "the only geometry gets id 0");
        Ok(())
    }

    /// Copies the mesh's vertices into the geometry's vertex buffer of time step `slot`.
    fn write_vertices(&mut self, mesh: &Mesh, slot: u32) {
        let Some(geometry) = self.geometry else {
            return;
        };
        // SAFETY: the vertex buffer `slot` set in `attach_triangles` holds 3 · triangle_count
        // FLOAT3 items, and `mesh` has triangle_count triangles (checked by callers).
        let vertices = unsafe {
            let data =
                A::geometry_buffer_data(geometry, RTC_BUFFER_TYPE_VERTEX, slot) as *mut [f32; 3];
            std::slice::from_raw_parts_mut(data, 3 * self.triangle_count)
        };
        for (corners, tri) in vertices.chunks_exact_mut(3).zip(&mesh.triangles) {
            for (corner, v) in corners.iter_mut().zip(tri.v) {
                *corner = v.to_array();
            }
        }
    }

    fn commit(&mut self, what: &str) -> Result<()> {
        // SAFETY: a live scene; no traversal runs while we hold `&mut self`.
        unsafe { A::commit_scene(self.raw) };
        self.device.check(what)
    }

    /// Moves the vertices to those of `mesh` (same triangle count and order) and recommits. With
    /// quality `refit` Embree refits the existing tree's boxes; with the other qualities it
    /// rebuilds the tree. `build_seconds` becomes the time of this update.
    pub fn refit(&mut self, mesh: &Mesh) -> Result<()> {
        if self.moving {
            return Err(Error::runtime(
                "a moving Embree scene is built per shutter interval, not refitted",
            ));
        }
        if mesh.len() != self.triangle_count {
            return Err(Error::runtime(format!(
                "Embree refit needs the same {} triangles, got {}",
                self.triangle_count,
                mesh.len()
            )));
        }
        let start = Instant::now();
        self.write_vertices(mesh, 0);
        if let Some(geometry) = self.geometry {
            // SAFETY: a live geometry whose vertex buffer was just rewritten.
            unsafe {
                A::update_geometry_buffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0);
                A::commit_geometry(geometry);
            }
        }
        self.commit("refitting a scene")?;
        self.build_seconds = start.elapsed().as_secs_f64();
        self.refits += 1;
        Ok(())
    }

    pub fn triangle_count(&self) -> usize {
        self.triangle_count
    }

    /// Whether it has two time steps (`build_moving`).
    pub fn is_moving(&self) -> bool {
        self.moving
    }

    /// The committed scene handle, for the tracers.
    /// Whether packets of `width` rays run natively on the scene's device (`Device::native_packets`).
    #[inline(always)]
    pub fn native_packets(&self, width: usize) -> bool {
        self.device.native_packets(width)
    }

    pub(crate) fn raw(&self) -> ffi::RTCScene {
        self.raw
    }
}

/// `Ok` when Embree reported no error while `what` and returned a non-null `ptr`.
fn created<A: EmbreeApi, T>(device: &Device<A>, ptr: *mut T, what: &str) -> Result<()> {
    device.check(what)?;
    if ptr.is_null() {
        return Err(Error::runtime(format!(
            "Embree returned nothing while {what}"
        )));
    }
    Ok(())
}

impl<A: EmbreeApi> Drop for EmbreeScene<A> {
    fn drop(&mut self) {
        // SAFETY: handles created by rtcNewGeometry / rtcNewScene, each released once; a null
        // scene (failed creation) is skipped.
        unsafe {
            if let Some(geometry) = self.geometry {
                A::release_geometry(geometry);
            }
            if !self.raw.is_null() {
                A::release_scene(self.raw);
            }
        }
    }
}

impl<A: EmbreeApi> fmt::Debug for EmbreeScene<A> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("EmbreeScene")
            .field("library", &A::NAME)
            .field("triangles", &self.triangle_count)
            .field("config", &self.config)
            .field("build_seconds", &self.build_seconds)
            .field("refits", &self.refits)
            .finish()
    }
}
