//! From scene to rays and back: camera rays, secondary-ray generation, shading, images.

pub mod assembly;
pub mod image;
pub mod offset;
pub mod raycast;
pub mod rays;
pub mod sampling;
pub mod shading;
pub mod specular;
pub mod whitted;
