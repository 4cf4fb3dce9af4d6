//! The pinhole camera's grid of rays: what a batch of camera rays carries so that a tracer can
//! regenerate any of its rays from the pixel alone (multi-frusta tracing makes primary rays on
//! demand, Benthin & Wald 2009 §4). `render::rays::CameraProjection` makes its pinhole rays
//! through `ray_through`, so a regenerated ray is the batch's ray bit for bit.

use glam::Vec3;

use crate::geometry::Ray;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraGrid {
    pub origin: Vec3,
    /// The camera basis: `forward` through the image centre, `right` and `up` along the image.
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    /// Half the image's extent at unit distance along `forward`.
    pub half_width: f32,
    pub half_height: f32,
    /// The image in pixels; pixel id = y · width + x.
    pub width: u32,
    pub height: u32,
}

impl CameraGrid {
    /// The unnormalized direction through image position `(x, y)` in pixels (pixel centres at
    /// +0.5): `forward + right·sx + up·sy`, affine in `(x, y)`, so the directions of a pixel
    /// rectangle are convex combinations of those through its corners. Its length is ≥ 1
    /// (`forward` is a unit vector orthogonal to `right` and `up`).
    #[inline(always)]
    pub fn through(&self, x: f32, y: f32) -> Vec3 {
        let sx = (2.0 * x / self.width as f32 - 1.0) * self.half_width;
        let sy = (1.0 - 2.0 * y / self.height as f32) * self.half_height;
        self.forward + self.right * sx + self.up * sy
    }

    /// The camera ray through image position `(x, y)`.
    #[inline(always)]
    pub fn ray_through(&self, x: f32, y: f32) -> Ray {
        Ray::new(
            self.origin,
            self.through(x, y).normalize(),
            0.0,
            f32::INFINITY,
        )
    }

    /// The image position `(x, y)` of pixel id `pixel`.
    #[inline(always)]
    pub fn pixel_xy(&self, pixel: u32) -> (u32, u32) {
        (pixel % self.width, pixel / self.width)
    }

    /// The camera ray through the centre of pixel id `pixel`.
    #[inline(always)]
    pub fn pixel_ray(&self, pixel: u32) -> Ray {
        let (x, y) = self.pixel_xy(pixel);
        self.ray_through(x as f32 + 0.5, y as f32 + 0.5)
    }
}
