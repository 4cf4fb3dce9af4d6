//! From scene to rays and back: camera rays, secondary-ray generation, shading, images.

pub mod area_light;
pub mod assembly;
pub mod convergence;
pub mod cost_map;
pub mod discontinuity_filter;
pub mod distribution;
pub mod glossy;
pub mod image;
pub mod interleaved;
pub mod interleaved_shadows;
pub mod light_query;
pub mod motion;
pub mod offset;
pub mod path;
pub mod qmc;
pub mod raycast;
pub mod rays;
pub mod renderers;
pub mod sampling;
pub mod shading;
pub mod specular;
pub mod wavefront;
pub mod whitted;
