//! Scene file loaders, chosen by file extension: Wavefront OBJ (+ MTL), PLY (ASCII or binary,
//! optionally gzip-compressed), Eric Haines' NFF and BART's AFF (NFF plus meshes, includes,
//! transform hierarchies and keyframe animation).
//!
//! Every loader returns one `Error` naming the file and, where known, the line for bad input;
//! none panics, hangs or allocates for counts the data does not back (`tests/suite/fuzz_loaders.rs`
//! and the cargo-fuzz targets in `fuzz/` check it). Degenerate (zero-area) triangles are kept: real scenes have them (conference has
//! 52,670) and tracers must cope.

mod aff;
mod kb_spline;
mod keyframes;
mod mtl;
mod nff;
mod obj;
mod ply;
mod quadrics;
mod scene_graph;
mod tokens;
mod triangulate;

use std::path::Path;

use crate::error::{Error, Result};
use glam::Vec3;

use crate::geometry::{Aabb, LARGEST_COORDINATE};
use crate::scene::{Camera, Material, Mesh, Scene};

pub use triangulate::triangulate;

/// How to turn the NFF quadrics (spheres, cones) into triangles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LoadOptions {
    /// Longitudes of a tessellated sphere; it gets `sphere_segments / 2` latitude bands and
    /// `2 · s · (s/2 − 1)` triangles.
    pub sphere_segments: u32,
    /// Segments around a tessellated cone or cylinder (two triangles each).
    pub cone_segments: u32,
}

impl Default for LoadOptions {
    /// 12 longitudes (120 triangles a sphere) keep SPD balls' 7,381 spheres under a million
    /// triangles; 16 segments (32 triangles) make BART museum's thin stands round enough.
    fn default() -> Self {
        LoadOptions {
            sphere_segments: 12,
            cone_segments: 16,
        }
    }
}

/// Loads a scene file (`.obj`, `.ply`, `.ply.gz`, `.nff`, `.aff`) with default options.
pub fn load(path: &Path) -> Result<Scene> {
    load_with(path, &LoadOptions::default())
}

pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    check_options(options)?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if name.ends_with(".obj") {
        obj::load(path)
    } else if name.ends_with(".ply") || name.ends_with(".ply.gz") {
        ply::load(path)
    } else if name.ends_with(".nff") {
        nff::load(path, options)
    } else if name.ends_with(".aff") {
        aff::load(path, options)
    } else {
        Err(Error::input(
            path,
            None,
            "unknown scene file type (expected .obj, .ply, .ply.gz, .nff or .aff)",
        ))
    }
}

fn check_options(options: &LoadOptions) -> Result<()> {
    if options.sphere_segments < 4 || options.cone_segments < 3 {
        return Err(Error::usage(format!(
            "tessellation needs at least 4 sphere segments and 3 cone segments (got {} and {})",
            options.sphere_segments, options.cone_segments
        )));
    }
    Ok(())
}

/// Where a loader reads the files that a file names (OBJ material libraries, AFF includes):
/// the filesystem for `load`; for the `parse_*` entry points, whatever the caller provides.
pub type Files<'a> = &'a dyn Fn(&Path) -> std::io::Result<Vec<u8>>;

// In-memory entry points (fuzzing, tests): the file's contents and the path its errors name.

/// An OBJ file; its material libraries come from `files`.
pub fn parse_obj(path: &Path, bytes: &[u8], files: Files) -> Result<Scene> {
    obj::parse(path, bytes, files)
}

/// An MTL library's materials.
pub fn parse_mtl(path: &Path, bytes: &[u8]) -> Result<Vec<Material>> {
    mtl::parse(path, &String::from_utf8_lossy(bytes))
}

/// A PLY file, gzip-compressed when `path` ends in `.gz`.
pub fn parse_ply(path: &Path, bytes: &[u8]) -> Result<Scene> {
    ply::parse(path, bytes)
}

/// An NFF file.
pub fn parse_nff(path: &Path, bytes: &[u8], options: &LoadOptions) -> Result<Scene> {
    check_options(options)?;
    let no_files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
    aff::parse(path, bytes, options, aff::Dialect::Nff, no_files)
}

/// An AFF file; the files it includes come from `files`.
pub fn parse_aff(path: &Path, bytes: &[u8], options: &LoadOptions, files: Files) -> Result<Scene> {
    check_options(options)?;
    aff::parse(path, bytes, options, aff::Dialect::Aff, files)
}

/// A view for files that carry none: the bounds' centre seen from above the (+x, +y, +z)
/// diagonal, far enough that the bounding sphere fills a 45° field of view.
pub fn default_camera(bounds: &Aabb) -> Camera {
    if bounds.is_empty() {
        return Camera::default();
    }
    const FOV_Y_DEG: f32 = 45.0;
    let centre = bounds.center();
    let radius = 0.5 * bounds.extent().length();
    let radius = if radius > 0.0 { radius } else { 1.0 };
    let distance = radius / (0.5 * FOV_Y_DEG.to_radians()).sin();
    let direction = Vec3::new(1.0, 0.5, 1.0).normalize();
    Camera {
        position: centre + direction * distance,
        target: centre,
        up: Vec3::Y,
        fov_y_deg: FOV_Y_DEG,
        aperture: 0.0,
        focus_distance: distance,
    }
}

/// The scene's name: the file name without its scene extensions (`dragon.ply.gz` → `dragon`).
fn scene_name(path: &Path) -> String {
    let file = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let mut name = file.as_str();
    for ext in [".gz", ".ply", ".obj", ".nff", ".aff"] {
        if name.len() > ext.len() && name.to_lowercase().ends_with(ext) {
            name = &name[..name.len() - ext.len()];
        }
    }
    name.to_string()
}

/// Refuses a file that produced no triangles, or a vertex (after any transform) that is not
/// finite or lies beyond `LARGEST_COORDINATE`, where Embree cannot check the hits.
fn require_traceable(path: &Path, mesh: &Mesh) -> Result<()> {
    if mesh.is_empty() {
        return Err(Error::input(path, None, "the file contains no triangles"));
    }
    let out_of_range = |v: &Vec3| !(v.is_finite() && v.abs().max_element() <= LARGEST_COORDINATE);
    match (mesh.triangles.iter().enumerate())
        .find_map(|(i, t)| t.v.iter().find(|v| out_of_range(v)).map(|v| (i, v)))
    {
        Some((i, v)) => Err(Error::input(
            path,
            None,
            format!(
                "triangle {i} has a vertex at ({:e}, {:e}, {:e}), beyond ±{LARGEST_COORDINATE:e} (the largest \
                 coordinate Embree traces; scale the scene down)",
                v.x, v.y, v.z
            ),
        )),
        None => Ok(()),
    }
}

/// The scene of a file that holds geometry and materials only (OBJ, PLY): named after the file,
/// no lights, the default view, nothing moves. Refuses a file without triangles.
fn still_mesh_scene(path: &Path, mesh: Mesh, materials: Vec<Material>) -> Result<Scene> {
    require_traceable(path, &mesh)?;
    Ok(Scene {
        name: scene_name(path),
        source: path.display().to_string(),
        camera: default_camera(&mesh.bounds()),
        mesh,
        materials,
        lights: Vec::new(),
        camera_path: None,
        animation: None,
    })
}

/// Unique path for a test file under the system temp directory.
#[cfg(test)]
pub(crate) fn temp_file(name: &str, contents: &[u8]) -> std::path::PathBuf {
    use std::sync::atomic::{AtomicUsize, Ordering};
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "raylab-loaders-{}-{}",
        std::process::id(),
        COUNTER.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, contents).unwrap();
    path
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn default_camera_sees_the_whole_box() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(3.0, 2.0, 1.0));
        let cam = default_camera(&b);
        assert_eq!(cam.target, Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(cam.fov_y_deg, 45.0);
        let radius = 0.5 * b.extent().length();
        let d = (cam.position - cam.target).length();
        assert!((d * (22.5f32).to_radians().sin() - radius).abs() < 1e-4);
        assert!(cam.position.x > 1.0 && cam.position.y > 1.0 && cam.position.z > 0.0);
    }

    #[test]
    fn vertices_beyond_embree_range_or_empty_files_are_refused() {
        let no_files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
        // obvhs's builder panicked (index out of bounds) on this scene; Embree rejects its rays.
        let huge = b"v -1e19 -1e19 0\nv 1e19 -1e19 0\nv 0 1e19 0\nf 1 2 3\n";
        let err = parse_obj(Path::new("huge.obj"), huge, no_files).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(
            err.to_string().starts_with(
                "huge.obj: triangle 0 has a vertex at (-1e19, -1e19, 0e0), beyond ±1.844e18"
            ),
            "{err}"
        );
        let err = parse_nff(
            Path::new("big.nff"),
            b"s 0 0 0 1e30\n",
            &LoadOptions::default(),
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("big.nff: triangle 0 has a vertex"),
            "{err}"
        );
        // A transform overflowing finite vertices to infinity (obvhs panicked on this too).
        let scaled = b"xs 1e30 1e30 1e30 0 0 1 0 0 0 0 {\np 3\n0 0 0\n1e10 0 0\n0 1e10 0\n}\n";
        let err = parse_aff(
            Path::new("x.aff"),
            scaled,
            &LoadOptions::default(),
            no_files,
        )
        .unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(
            err.to_string()
                .starts_with("x.aff: triangle 0 has a vertex at (inf, "),
            "{err}"
        );
        let edge = b"v -1.8e18 0 0\nv 1.8e18 0 0\nv 0 1.8e18 0\nf 1 2 3\n";
        assert_eq!(
            parse_obj(Path::new("edge.obj"), edge, no_files)
                .unwrap()
                .triangle_count(),
            1
        );
    }

    #[test]
    fn unknown_extension_is_an_input_error() {
        let err = load(Path::new("/nonexistent/scene.xyz")).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert!(err.to_string().contains("scene.xyz"));
    }

    #[test]
    fn tessellation_follows_the_options() {
        let path = temp_file("one.nff", b"s 0 0 0 1\nc 0 0 0 1 0 0 1 0\n");
        let options = LoadOptions {
            sphere_segments: 8,
            cone_segments: 5,
        };
        // 2·8·(4 − 1) sphere triangles and 5 for the pointed cone.
        assert_eq!(load_with(&path, &options).unwrap().triangle_count(), 48 + 5);
        let coarse = LoadOptions {
            sphere_segments: 3,
            ..options
        };
        assert_eq!(load_with(&path, &coarse).unwrap_err().exit_code(), 2);
    }

    #[test]
    fn names_drop_scene_extensions() {
        assert_eq!(
            scene_name(Path::new("a/dragon_vrip_res2.ply.gz")),
            "dragon_vrip_res2"
        );
        assert_eq!(scene_name(Path::new("kitchen.aff")), "kitchen");
        assert_eq!(scene_name(Path::new("Toasters004.OBJ")), "Toasters004");
    }
}
