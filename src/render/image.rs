//! Images: linear RGB buffers, PNG output with a deterministic auto-exposure, and RMSE.

use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// Linear RGB, row-major, `y·width + x`.
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Self {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; (width * height) as usize],
        }
    }

    /// Scale that maps the 95th-percentile luminance to 0.8: scenes come with lights in their own
    /// units, and a fixed rule keeps every image viewable and every run of it identical.
    pub fn auto_exposure(&self) -> f32 {
        let mut lum: Vec<f32> = self
            .pixels
            .iter()
            .map(|c| c.dot(Vec3::new(0.2126, 0.7152, 0.0722)))
            .filter(|l| *l > 0.0 && l.is_finite())
            .collect();
        if lum.is_empty() {
            return 1.0;
        }
        let k = ((lum.len() as f32 * 0.95) as usize).min(lum.len() - 1);
        let (_, p95, _) = lum.select_nth_unstable_by(k, f32::total_cmp);
        0.8 / *p95
    }

    /// 8-bit sRGB bytes after scaling by `exposure`.
    pub fn to_srgb8(&self, exposure: f32) -> Vec<u8> {
        let encode = |x: f32| {
            let x = (x * exposure).clamp(0.0, 1.0);
            let s = if x <= 0.003_130_8 {
                12.92 * x
            } else {
                1.055 * x.powf(1.0 / 2.4) - 0.055
            };
            (s * 255.0 + 0.5) as u8
        };
        self.pixels
            .iter()
            .flat_map(|c| [encode(c.x), encode(c.y), encode(c.z)])
            .collect()
    }

    pub fn save_png(&self, path: &Path) -> Result<()> {
        let bytes = self.to_srgb8(self.auto_exposure());
        image::save_buffer(
            path,
            &bytes,
            self.width,
            self.height,
            image::ColorType::Rgb8,
        )
        .map_err(|e| Error::runtime(format!("{}: cannot write PNG: {e}", path.display())))
    }

    /// Root-mean-square error over all channels against `reference` (same size).
    pub fn rmse(&self, reference: &Image) -> f64 {
        assert_eq!(
            (self.width, self.height),
            (reference.width, reference.height)
        );
        let sum: f64 = self
            .pixels
            .iter()
            .zip(&reference.pixels)
            .map(|(a, b)| (*a - *b).length_squared() as f64)
            .sum();
        (sum / (3 * self.pixels.len()) as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_encoding_endpoints_and_midpoint() {
        let mut img = Image::new(3, 1);
        img.pixels = vec![Vec3::ZERO, Vec3::splat(0.214_041_14), Vec3::ONE];
        let bytes = img.to_srgb8(1.0);
        assert_eq!(&bytes[0..3], &[0, 0, 0]);
        assert_eq!(bytes[3], 128); // linear 0.214 is sRGB 0.5
        assert_eq!(&bytes[6..9], &[255, 255, 255]);
    }

    #[test]
    fn rmse_of_known_difference() {
        let a = Image::new(2, 2);
        let mut b = Image::new(2, 2);
        b.pixels[0] = Vec3::new(2.0, 0.0, 0.0);
        // One channel of 12 differs by 2: sqrt(4 / 12).
        assert!((a.rmse(&b) - (4.0f64 / 12.0).sqrt()).abs() < 1e-12);
        assert_eq!(a.rmse(&a), 0.0);
    }

    #[test]
    fn auto_exposure_maps_p95_to_0_8() {
        let mut img = Image::new(100, 1);
        for (i, p) in img.pixels.iter_mut().enumerate() {
            *p = Vec3::splat(i as f32 + 1.0);
        }
        // 95th of 1..=100 (index 95) is 96.
        assert!((img.auto_exposure() - 0.8 / 96.0).abs() < 1e-6);
    }
}
