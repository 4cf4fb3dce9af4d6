//! Rays, boxes and triangles: the geometric primitives every tracer shares.

pub mod aabb;
pub mod camera_grid;
pub mod moller;
pub mod ray;
pub mod ray_file;
pub mod ray_slots;
pub mod robustness;
pub mod triangle;

pub use aabb::{Aabb, RayBoxTest};
pub use camera_grid::CameraGrid;
pub use ray::{Hit, Ray, RayBatch, RayKind, Rays, LARGEST_COORDINATE};
pub use robustness::{Fast, RayTests, Robust};
pub use triangle::{Triangle, WatertightRay};
