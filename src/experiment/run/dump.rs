//! What `raylab run --dump-rays` writes into the results directory's `rays/`, so that another
//! program can replay a run's exact work (`tools/embree-direct.c` calls Embree directly on it):
//! every generated ray batch as a binary ray file (`geometry::ray_file`) — the soft-shadow query's
//! shadow rays too (`<…>-soft_shadow.rays`, the batch every tracer but a native one traces) — the
//! frame's triangles, and the soft-shadow query's shading points with their quad light.
//!
//! Both extra files are little-endian, a 24-byte header then f32 records:
//!
//! | file                                 | magic      | u32 | u32                 | u64 | then                              |
//! |--------------------------------------|------------|-----|---------------------|-----|-----------------------------------|
//! | `<scene>[-s<size>]-f<frame>.tris`    | `RAYLABTR` | 1   | 0                   | n   | n × 9: the corners a b c          |
//! | `<scene>[-s<size>]-f<frame>.points`  | `RAYLABSP` | 1   | samples per point   | n   | 9: the light's corner, edge u, edge v; then n × 9: position, normal, ray origin |

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::ray_file::{write_rays, RayFileFormat};
use crate::geometry::{RayBatch, RayKind, Triangle};
use crate::tracers::visibility::{QuadLight, ShadingPoints};

use crate::experiment::plan::config::SceneSpec;

/// The stem of every dump file of `spec`'s frame `frame`.
fn stem(spec: &SceneSpec, frame: usize) -> String {
    let size = spec.size.map_or(String::new(), |s| format!("-s{s}"));
    let scene = spec.name.replace(['/', '\\'], "_");
    format!("{scene}{size}-f{frame}")
}

/// The ray file of one batch: `<scene>[-s<size>]-f<frame>-<kind>.rays`.
pub fn rays_name(spec: &SceneSpec, frame: usize, kind: RayKind) -> String {
    format!("{}-{}.rays", stem(spec, frame), kind.name())
}

/// The triangle file of a frame: `<scene>[-s<size>]-f<frame>.tris`.
pub fn triangles_name(spec: &SceneSpec, frame: usize) -> String {
    format!("{}.tris", stem(spec, frame))
}

/// The soft-shadow points file of a frame: `<scene>[-s<size>]-f<frame>.points`.
pub fn points_name(spec: &SceneSpec, frame: usize) -> String {
    format!("{}.points", stem(spec, frame))
}

fn header(magic: &[u8; 8], word: u32, count: usize, floats: usize) -> Vec<u8> {
    let mut bytes = Vec::with_capacity(24 + floats * 4);
    bytes.extend_from_slice(magic);
    bytes.extend_from_slice(&1u32.to_le_bytes());
    bytes.extend_from_slice(&word.to_le_bytes());
    bytes.extend_from_slice(&(count as u64).to_le_bytes());
    bytes
}

fn push(bytes: &mut Vec<u8>, vectors: &[Vec3]) {
    for v in vectors {
        for x in v.to_array() {
            bytes.extend_from_slice(&x.to_le_bytes());
        }
    }
}

fn write(path: &Path, bytes: Vec<u8>) -> Result<()> {
    std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
}

/// The frame's triangles, in primitive order (Embree's `primID` is the index).
pub fn write_triangles(path: &Path, triangles: &[Triangle]) -> Result<()> {
    let mut bytes = header(b"RAYLABTR", 0, triangles.len(), triangles.len() * 9);
    for t in triangles {
        push(&mut bytes, &t.v);
    }
    write(path, bytes)
}

/// The soft-shadow query's shading points, the quad light and the samples per point.
pub fn write_points(
    path: &Path,
    points: &ShadingPoints,
    light: QuadLight,
    samples_per_point: usize,
) -> Result<()> {
    let n = points.len();
    let mut bytes = header(b"RAYLABSP", samples_per_point as u32, n, 9 + n * 9);
    push(&mut bytes, &[light.corner, light.edge_u, light.edge_v]);
    for p in &points.points {
        push(&mut bytes, &[p.position, p.normal, p.origin]);
    }
    write(path, bytes)
}

/// A binary ray file of `batch`.
pub fn write_batch(path: &Path, batch: &RayBatch) -> Result<()> {
    write_rays(path, batch.view(), RayFileFormat::Binary)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f32s(bytes: &[u8]) -> Vec<f32> {
        bytes
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    }

    #[test]
    fn triangle_and_point_files_hold_their_header_and_every_float() {
        let dir = std::env::temp_dir().join(format!("raylab-dump-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let t = Triangle::new(Vec3::X, Vec3::Y, Vec3::new(1.0, 2.0, -3.5));
        let path = dir.join("a.tris");
        write_triangles(&path, &[t, t]).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"RAYLABTR");
        assert_eq!(u64::from_le_bytes(bytes[16..24].try_into().unwrap()), 2);
        assert_eq!(bytes.len(), 24 + 2 * 36);
        assert_eq!(f32s(&bytes[24 + 36..])[6..], [1.0, 2.0, -3.5]);

        let mut points = ShadingPoints::default();
        let point = crate::tracers::visibility::ShadingPoint {
            position: Vec3::ONE,
            normal: Vec3::Z,
            origin: Vec3::new(1.0, 1.0, 1.5),
            time: 0.0,
            set: 0,
        };
        points.push(point, true);
        let light = QuadLight {
            corner: Vec3::new(-1.0, 4.0, 0.0),
            edge_u: Vec3::X,
            edge_v: Vec3::Z,
        };
        let path = dir.join("a.points");
        write_points(&path, &points, light, 16).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_eq!(&bytes[..8], b"RAYLABSP");
        assert_eq!(u32::from_le_bytes(bytes[12..16].try_into().unwrap()), 16);
        assert_eq!(
            f32s(&bytes[24..]),
            [
                -1.0, 4.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 1.0, 1.0,
                1.0, 1.5
            ]
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
