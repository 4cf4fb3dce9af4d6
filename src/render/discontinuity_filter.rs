//! The discontinuity filter of Benthin & Wald 2009 §4.5 ("a simple irradiance filtering pass over
//! the image, filtering the illumination in a 4×4 neighborhood around every pixel. Each pixel
//! needs therefore additional information such as normal, depth, and irradiance"), after Keller &
//! Heidrich 2001: with 4×4 interleaved sample sets, any 4×4 window of pixels holds each set once,
//! so averaging a window combines the 16 sets into all 256 samples — but only across pixels that
//! see the same surface, or shadows would bleed over silhouettes and creases.
//!
//! What is filtered is the light's visible fraction, the irradiance over the unshadowed
//! irradiance from the light's centre (the shading sample, §4.5): the shading's own gradients
//! (distance and angle to the light) stay sharp, only the sampled visibility is averaged.
//!
//! Each pixel's filtered value is the mean over the pixels of the 4×4 window
//! `[x − 1, x + 2] × [y − 1, y + 2]` (clipped to the image) that lie on the pixel's surface: within
//! `depth_tolerance` × the pixel's depth of its tangent plane (a depth discontinuity measured
//! along the normal, so that a plane seen at a grazing angle stays whole while a table top and the
//! floor below it do not mix), and with a normal within `normal_cos` (cosine) of its normal.
//! Pixels without a surface (background) keep their value and take no part.

use glam::Vec3;

/// Side of the filter window: the tile side of the interleaved sample sets.
pub const WINDOW: u32 = crate::render::interleaved::K;

/// What the filter knows about the surface a pixel sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelSurface {
    /// The hit point.
    pub position: Vec3,
    /// Distance along the camera ray.
    pub depth: f32,
    /// Unit shading normal.
    pub normal: Vec3,
}

/// When two pixels see the same surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiscontinuityFilter {
    /// Largest distance from the centre pixel's tangent plane, relative to its depth.
    pub depth_tolerance: f32,
    /// Smallest cosine between the two normals.
    pub normal_cos: f32,
}

impl Default for DiscontinuityFilter {
    /// 1% of the depth off the tangent plane (15 units at the conference room's 1,500) and 25°
    /// (cos 0.9) between normals: a step to another object or a crease is a discontinuity.
    fn default() -> Self {
        DiscontinuityFilter {
            depth_tolerance: 0.01,
            normal_cos: 0.9,
        }
    }
}

impl DiscontinuityFilter {
    fn same_surface(&self, centre: &PixelSurface, other: &PixelSurface) -> bool {
        let off_plane = centre.normal.dot(other.position - centre.position).abs();
        off_plane <= self.depth_tolerance * centre.depth
            && centre.normal.dot(other.normal) >= self.normal_cos
    }

    /// The filtered `values` of a `width`-wide image, row-major, with `surfaces` its pixels'
    /// surfaces (`None`: background).
    pub fn apply(&self, width: u32, values: &[f32], surfaces: &[Option<PixelSurface>]) -> Vec<f32> {
        assert_eq!(values.len(), surfaces.len());
        let (w, h) = (width as i64, (values.len() / width.max(1) as usize) as i64);
        let half = (WINDOW / 2) as i64;
        let mut out = values.to_vec();
        for y in 0..h {
            for x in 0..w {
                let centre = (y * w + x) as usize;
                let Some(surface) = &surfaces[centre] else {
                    continue;
                };
                // f64 sums: a window of equal values averages back to exactly that value.
                let (mut sum, mut count) = (0.0f64, 0u32);
                let rows = (y - half + 1).max(0)..(y + half + 1).min(h);
                for ny in rows {
                    for nx in (x - half + 1).max(0)..(x + half + 1).min(w) {
                        let n = (ny * w + nx) as usize;
                        if surfaces[n].is_some_and(|s| self.same_surface(surface, &s)) {
                            sum += values[n] as f64;
                            count += 1;
                        }
                    }
                }
                out[centre] = (sum / count as f64) as f32;
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: u32 = 12;
    const H: u32 = 8;

    /// Pixel `i` on the plane z = `depth` facing the camera at the origin (pixels 0.01 apart).
    fn flat(i: u32, depth: f32) -> Option<PixelSurface> {
        Some(PixelSurface {
            position: Vec3::new((i % W) as f32 * 0.01, (i / W) as f32 * 0.01, depth),
            depth,
            normal: Vec3::Z,
        })
    }

    #[test]
    fn a_constant_image_is_left_as_it_is() {
        let irradiance = vec![0.3f32; (W * H) as usize];
        // A tilted plane whose depth doubles across the image (far beyond the tolerance, but
        // every pixel on the others' tangent plane), and one pixel of background.
        let normal = Vec3::new(-0.1, 0.0, 1.0).normalize();
        let mut surfaces: Vec<_> = (0..W * H)
            .map(|i| {
                let depth = 1.0 + (i % W) as f32 / W as f32;
                let position = Vec3::new(10.0 * depth, (i / W) as f32 * 0.01, depth);
                Some(PixelSurface {
                    position,
                    depth,
                    normal,
                })
            })
            .collect();
        surfaces[17] = None;
        let out = DiscontinuityFilter::default().apply(W, &irradiance, &surfaces);
        assert_eq!(out, irradiance);
    }

    #[test]
    fn a_window_averages_the_sixteen_interleaved_sets() {
        // A 4×4-periodic pattern on one plane: every full window holds each value once.
        let value = |x: u32, y: u32| ((x % 4) + 4 * (y % 4)) as f32;
        let irradiance: Vec<f32> = (0..W * H).map(|i| value(i % W, i / W)).collect();
        let surfaces: Vec<_> = (0..W * H).map(|i| flat(i, 3.0)).collect();
        let out = DiscontinuityFilter::default().apply(W, &irradiance, &surfaces);
        for y in 1..H - 2 {
            for x in 1..W - 2 {
                assert_eq!(out[(y * W + x) as usize], 7.5, "({x},{y})");
            }
        }
        // A corner pixel's window is clipped to 3×3 of the pattern: values {0,1,2}+{0,4,8}.
        assert_eq!(out[0], 5.0);
    }

    #[test]
    fn nothing_is_blurred_across_a_depth_step_or_a_crease() {
        // Left half at depth 1 in shadow, right half at depth 1.1 lit: the step stays sharp.
        let lit = |x: u32| if x < W / 2 { 0.0 } else { 1.0 };
        let irradiance: Vec<f32> = (0..W * H).map(|i| lit(i % W)).collect();
        let step: Vec<_> = (0..W * H)
            .map(|i| flat(i, if i % W < W / 2 { 1.0 } else { 1.1 }))
            .collect();
        let filter = DiscontinuityFilter::default();
        assert_eq!(filter.apply(W, &irradiance, &step), irradiance);
        // The same depth, but the right half's normal turned by 90°.
        let crease: Vec<_> = (0..W * H)
            .map(|i| {
                let normal = if i % W < W / 2 { Vec3::Z } else { Vec3::X };
                Some(PixelSurface {
                    normal,
                    ..flat(i, 1.0).unwrap()
                })
            })
            .collect();
        assert_eq!(filter.apply(W, &irradiance, &crease), irradiance);
        // One plane: the edge is blurred (the control: the filter does filter here).
        let plane: Vec<_> = (0..W * H).map(|i| flat(i, 1.0)).collect();
        let blurred = filter.apply(W, &irradiance, &plane);
        assert_eq!(blurred[(W / 2 - 1) as usize], 0.5);
    }
}
