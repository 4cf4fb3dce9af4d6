//! Error against run time for distribution ray tracing (issue item 9) and path tracing (Gribble &
//! Ramani 2008 §4): each sample count's image is compared with a high-sample reference image of
//! the same integrator by RMSE, next to the time it took.
//!
//! The reference (`REFERENCE_SPP` samples per pixel, reference tracer) is expensive, so it is
//! rendered once and cached on disk under `<results root>/cache/drt-reference/`. The cache key is
//! a hash of everything the image depends on: the triangles at both ends of the shutter, materials,
//! lights, camera, resolution, renderer settings and `RENDERER_VERSION` — so an edited scene file
//! or a changed setting never reads a stale image. The file name also carries the scene name,
//! frame and resolution for people browsing the directory. Delete the directory to drop the cache.
//! Interleaved soft shadows (Benthin & Wald 2009) are compared with their own unfiltered,
//! unretraced estimate at `REFERENCE_SPP` light samples per pixel: filter and retrace are what is
//! measured against it.

use std::fs;
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::random::mix64;
use crate::render::distribution::{render_sampled, DrtFrame, DrtSettings, FrameGeometry};
use crate::render::image::Image;
use crate::render::motion::MovingMesh;
use crate::render::path::ShadeStreams;
use crate::render::wavefront::Tracing;
use crate::scene::{Frame, Mesh, Scene};
use crate::tracers::{Params, Role, Tracer, TracerInfo};

/// Samples per pixel of the reference image.
pub const REFERENCE_SPP: u32 = 1024;
/// Part of every cache key: raise it whenever the renderer's output changes for the same inputs.
pub const RENDERER_VERSION: u64 = 1;
/// Where reference images live, under the results root.
pub const CACHE_DIR: &str = "cache/drt-reference";
const MAGIC: &str = "raylab-drt-reference";

/// One measured sample count.
#[derive(Clone, Debug, PartialEq)]
pub struct ErrorPoint {
    pub tracer: String,
    pub spp: u32,
    /// Wall time of the whole frame (sampling, shading, tracing).
    pub seconds: f64,
    /// Wall time inside the tracer.
    pub trace_seconds: f64,
    pub rays: u64,
    pub rmse: f64,
}

/// Hash of everything the reference image of this frame depends on.
pub fn reference_key(
    scene: &Scene,
    frame: &Frame,
    motion: Option<&MovingMesh>,
    settings: &DrtSettings,
) -> u64 {
    let mut h = mix64(RENDERER_VERSION);
    match motion {
        Some(moving) => {
            hash_mesh(&mut h, &moving.open);
            hash_mesh(&mut h, &moving.mesh_at(1.0));
        }
        None => hash_mesh(&mut h, &frame.mesh),
    }
    // Materials, lights and camera through their Debug forms: every field, exactly printed.
    let described = format!(
        "{:?}{:?}{:?}{:?}",
        scene.materials,
        scene.lights,
        frame.camera,
        DrtSettings {
            shade: ShadeStreams::default(),
            ..reference_settings(settings)
        }
    );
    for chunk in described.as_bytes().chunks(8) {
        let mut word = [0u8; 8];
        word[..chunk.len()].copy_from_slice(chunk);
        hash_word(&mut h, u64::from_le_bytes(word));
    }
    h
}

fn hash_word(h: &mut u64, bits: u64) {
    *h = mix64(*h ^ bits);
}

fn hash_mesh(h: &mut u64, mesh: &Mesh) {
    hash_word(h, mesh.len() as u64);
    for (tri, m) in mesh.triangles.iter().zip(&mesh.material_ids) {
        for p in tri.v {
            hash_word(h, ((p.x.to_bits() as u64) << 32) | p.y.to_bits() as u64);
            hash_word(h, p.z.to_bits() as u64);
        }
        hash_word(h, *m as u64);
    }
}

/// The cache file of a reference image.
pub fn reference_path(
    results_root: &Path,
    scene: &Scene,
    frame: &Frame,
    settings: &DrtSettings,
    key: u64,
) -> PathBuf {
    let name: String = scene
        .name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    results_root.join(CACHE_DIR).join(format!(
        "{name}-f{}-{}x{}-{key:016x}.rgbf32",
        frame.index, settings.width, settings.height
    ))
}

/// The reference image of this frame at `settings` (its `spp` replaced by `REFERENCE_SPP`),
/// from the cache under `results_root` or rendered with the reference tracer and cached.
/// Returns the image and whether it came from the cache.
pub fn reference_image(
    scene: &Scene,
    frame: &Frame,
    motion: Option<&MovingMesh>,
    settings: &DrtSettings,
    results_root: &Path,
) -> Result<(Image, bool)> {
    let key = reference_key(scene, frame, motion, settings);
    let path = reference_path(results_root, scene, frame, settings, key);
    if let Some(image) = read_cached(&path, key, settings)? {
        return Ok((image, true));
    }
    let geometry = FrameGeometry::of(frame, motion);
    let tracer = geometry.tracer(TracerInfo::of_role(Role::Reference)?.name, &Params::new())?;
    let reference = reference_settings(settings);
    let image = render_sampled(
        scene,
        frame,
        geometry,
        tracer.as_ref(),
        &reference,
        Tracing::Timed,
    )?
    .image;
    write_cached(&path, key, &image)?;
    Ok((image, false))
}

/// The reference's settings: `settings` at `REFERENCE_SPP`, and interleaved soft shadows
/// without filter and retrace (the reference is the plain estimate the refinements approximate).
pub fn reference_settings(settings: &DrtSettings) -> DrtSettings {
    DrtSettings {
        spp: REFERENCE_SPP,
        soft_shadows: settings.soft_shadows.map(|mode| mode.unrefined()),
        ..*settings
    }
}

fn header(key: u64, width: u32, height: u32) -> String {
    format!("{MAGIC} {key:016x} {width} {height}\n")
}

/// The cached image at `path`, or `None` when there is none; a file that is not the image it
/// should be (other key or size, cut short) is an error naming the file.
fn read_cached(path: &Path, key: u64, settings: &DrtSettings) -> Result<Option<Image>> {
    let bytes = match fs::read(path) {
        Ok(b) => b,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => return Err(Error::input(path, None, format!("cannot read: {e}"))),
    };
    let expected = header(key, settings.width, settings.height);
    let pixels = (settings.width * settings.height) as usize;
    if !bytes.starts_with(expected.as_bytes()) || bytes.len() != expected.len() + pixels * 12 {
        return Err(Error::input(
            path,
            None,
            "not the cached reference image its name promises (delete it to render it again)",
        ));
    }
    let floats: Vec<f32> = bytes[expected.len()..]
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
        .collect();
    let mut image = Image::new(settings.width, settings.height);
    for (p, c) in image.pixels.iter_mut().zip(floats.chunks_exact(3)) {
        *p = glam::Vec3::new(c[0], c[1], c[2]);
    }
    Ok(Some(image))
}

/// Writes the image beside its final name and renames it into place, so a reader never sees half
/// a file.
fn write_cached(path: &Path, key: u64, image: &Image) -> Result<()> {
    let io = |e: std::io::Error| Error::runtime(format!("{}: cannot write: {e}", path.display()));
    if let Some(dir) = path.parent() {
        fs::create_dir_all(dir).map_err(io)?;
    }
    let partial = path.with_extension("partial");
    let mut bytes = header(key, image.width, image.height).into_bytes();
    for c in &image.pixels {
        for x in c.to_array() {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
    fs::File::create(&partial)
        .and_then(|mut f| f.write_all(&bytes))
        .map_err(io)?;
    fs::rename(&partial, path).map_err(io)
}

/// Renders the frame with `tracer` at each of `spps` and measures each image's RMSE against
/// `reference`. `tracer` must have been built over the frame's geometry (or `motion`).
#[allow(clippy::too_many_arguments)]
pub fn error_against_time(
    scene: &Scene,
    frame: &Frame,
    motion: Option<&MovingMesh>,
    tracer_name: &str,
    tracer: &dyn Tracer,
    settings: &DrtSettings,
    spps: &[u32],
    reference: &Image,
) -> Result<Vec<(ErrorPoint, DrtFrame)>> {
    spps.iter()
        .map(|&spp| {
            let run = DrtSettings { spp, ..*settings };
            let rendered = render_sampled(
                scene,
                frame,
                FrameGeometry::of(frame, motion),
                tracer,
                &run,
                Tracing::Timed,
            )?;
            let point = ErrorPoint {
                tracer: tracer_name.to_string(),
                spp,
                seconds: rendered.seconds,
                trace_seconds: rendered.trace_seconds(),
                rays: rendered.rays(),
                rmse: rendered.image.rmse(reference),
            };
            Ok((point, rendered))
        })
        .collect()
}

/// `error_vs_time.csv`: one row per tracer and sample count.
pub fn write_error_csv(path: &Path, points: &[ErrorPoint]) -> Result<()> {
    let io = |e: &dyn std::fmt::Display| {
        Error::runtime(format!("{}: cannot write: {e}", path.display()))
    };
    let mut w = csv::Writer::from_path(path).map_err(|e| io(&e))?;
    w.write_record(["tracer", "spp", "seconds", "trace_seconds", "rays", "rmse"])
        .map_err(|e| io(&e))?;
    for p in points {
        w.write_record([
            p.tracer.clone(),
            p.spp.to_string(),
            format!("{:.6}", p.seconds),
            format!("{:.6}", p.trace_seconds),
            p.rays.to_string(),
            format!("{:.6e}", p.rmse),
        ])
        .map_err(|e| io(&e))?;
    }
    w.flush().map_err(|e| io(&e))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::library::load_scene;

    struct TempDir(PathBuf);
    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = fs::remove_dir_all(&self.0);
        }
    }

    #[test]
    fn reference_is_rendered_once_then_read_from_the_cache() {
        let dir =
            TempDir(std::env::temp_dir().join(format!("raylab-drt-cache-{}", std::process::id())));
        let scene = load_scene("room", None).unwrap();
        let frame = scene.frame(0, 1);
        let settings = DrtSettings {
            width: 16,
            height: 12,
            max_depth: 1,
            ..DrtSettings::default()
        };
        let (first, cached) = reference_image(&scene, &frame, None, &settings, &dir.0).unwrap();
        assert!(!cached);
        let (second, cached) = reference_image(&scene, &frame, None, &settings, &dir.0).unwrap();
        assert!(cached);
        assert_eq!(first, second);
        // The key ignores the run's own spp but not the lens, and not the geometry.
        let key = reference_key(&scene, &frame, None, &settings);
        let other_spp = DrtSettings { spp: 4, ..settings };
        assert_eq!(key, reference_key(&scene, &frame, None, &other_spp));
        let lens = DrtSettings {
            aperture: Some(0.1),
            ..settings
        };
        assert_ne!(key, reference_key(&scene, &frame, None, &lens));
        let mut moved = scene.clone();
        moved.mesh.triangles[0].v[0].x += 1e-3;
        assert_ne!(
            key,
            reference_key(&moved, &moved.frame(0, 1), None, &settings)
        );
        // A damaged cache file is an error naming it, not a wrong image.
        let path = reference_path(&dir.0, &scene, &frame, &settings, key);
        fs::write(&path, b"junk").unwrap();
        let err = reference_image(&scene, &frame, None, &settings, &dir.0).unwrap_err();
        assert!(
            err.to_string().contains(&path.display().to_string()),
            "{err}"
        );
    }
}
