//! Cameras (pinhole and thin lens) and camera paths: keyframes interpolated over the frames of a run.

use glam::Vec3;

use crate::geometry::CameraGrid;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub fov_y_deg: f32,
    /// Lens radius; 0 is a pinhole.
    pub aperture: f32,
    /// Distance to the plane in focus (thin lens only).
    pub focus_distance: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            position: Vec3::new(0.0, 0.0, 5.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            fov_y_deg: 45.0,
            aperture: 0.0,
            focus_distance: 1.0,
        }
    }
}

impl Camera {
    /// Orthonormal basis (right, up, forward) of the view.
    pub fn basis(&self) -> (Vec3, Vec3, Vec3) {
        let forward = (self.target - self.position).normalize();
        let mut right = forward.cross(self.up);
        if right.length_squared() < 1e-12 {
            // `up` parallel to the view direction: pick any perpendicular.
            right = forward.any_orthonormal_vector();
        }
        let right = right.normalize();
        (right, right.cross(forward), forward)
    }

    /// The grid of rays through the pixel centres of a `width` × `height` image, from the
    /// camera's position (a pinhole's rays; a thin lens aims through the plane in focus along them).
    pub fn grid(&self, width: u32, height: u32) -> CameraGrid {
        let (right, up, forward) = self.basis();
        let half_height = (self.fov_y_deg.to_radians() * 0.5).tan();
        CameraGrid {
            origin: self.position,
            forward,
            right,
            up,
            half_width: half_height * width as f32 / height as f32,
            half_height,
            width,
            height,
        }
    }

    pub fn lerp(&self, other: &Camera, s: f32) -> Camera {
        Camera {
            position: self.position.lerp(other.position, s),
            target: self.target.lerp(other.target, s),
            up: self.up.lerp(other.up, s),
            fov_y_deg: self.fov_y_deg + (other.fov_y_deg - self.fov_y_deg) * s,
            aperture: self.aperture + (other.aperture - self.aperture) * s,
            focus_distance: self.focus_distance + (other.focus_distance - self.focus_distance) * s,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraKey {
    /// Seconds from the start of the path.
    pub time: f32,
    pub camera: Camera,
}

/// Keyframed camera motion, linearly interpolated between keys. Loaders with spline paths (BART)
/// sample their spline densely into keys, so interpolation is exact at every frame.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraPath {
    pub keys: Vec<CameraKey>,
}

impl CameraPath {
    pub fn duration(&self) -> f32 {
        self.keys.last().map_or(0.0, |k| k.time)
    }

    pub fn camera_at(&self, time: f32) -> Option<Camera> {
        let first = self.keys.first()?;
        if time <= first.time {
            return Some(first.camera);
        }
        for pair in self.keys.windows(2) {
            let (a, b) = (&pair[0], &pair[1]);
            if time <= b.time {
                let span = b.time - a.time;
                let s = if span > 0.0 {
                    (time - a.time) / span
                } else {
                    1.0
                };
                return Some(a.camera.lerp(&b.camera, s));
            }
        }
        self.keys.last().map(|k| k.camera)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_interpolates_between_keys_and_clamps() {
        let a = Camera::default();
        let b = Camera {
            position: Vec3::new(10.0, 0.0, 5.0),
            ..a
        };
        let path = CameraPath {
            keys: vec![
                CameraKey {
                    time: 0.0,
                    camera: a,
                },
                CameraKey {
                    time: 2.0,
                    camera: b,
                },
            ],
        };
        assert_eq!(
            path.camera_at(1.0).unwrap().position,
            Vec3::new(5.0, 0.0, 5.0)
        );
        assert_eq!(path.camera_at(-1.0).unwrap().position, a.position);
        assert_eq!(path.camera_at(9.0).unwrap().position, b.position);
        assert_eq!(path.duration(), 2.0);
    }

    #[test]
    fn basis_is_orthonormal_even_when_up_is_parallel() {
        let cam = Camera {
            position: Vec3::new(0.0, 5.0, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            ..Camera::default()
        };
        let (r, u, f) = cam.basis();
        assert!((r.length() - 1.0).abs() < 1e-5 && (u.length() - 1.0).abs() < 1e-5);
        assert!(r.dot(f).abs() < 1e-5 && u.dot(f).abs() < 1e-5 && r.dot(u).abs() < 1e-5);
    }
}
