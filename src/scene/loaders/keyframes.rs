//! BART keyframe blocks and the transforms they animate:
//!
//! ```text
//! k name {
//!   transl n   (time x y z tension continuity bias) × n
//!   rot n      (time ax ay az degrees tension continuity bias) × n
//!   scale n    (time sx sy sz tension continuity bias) × n
//! }
//! ```
//!
//! Each kind is a Kochanek–Bartels spline of at least four keys (`kb_spline.rs`), and the
//! transform at time t is T(t)·R(t)·S(t) — scale first, then rotation, then translation — with
//! identity for a missing kind. The block named `camera` moves the viewer: the translation is
//! the eye, and the rotated −z and +y axes are the view direction and up (BART `GetCamera`).
//! BART also defines `visibility` keys; no BART scene uses them and hiding triangles would break
//! the fixed triangle count every frame must have, so they are refused.

use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};

use super::kb_spline::{Key, PositionSpline, RotationSpline};
use super::nff::View;
use super::tokens::Tokens;
use crate::error::Result;
use crate::scene::Camera;

#[derive(Clone, Debug, Default)]
pub struct TransformTrack {
    translation: Option<PositionSpline>,
    rotation: Option<RotationSpline>,
    scale: Option<PositionSpline>,
}

impl TransformTrack {
    /// T·R·S at BART time `t`.
    pub fn matrix(&self, t: f64) -> DMat4 {
        let r = self
            .rotation
            .as_ref()
            .map_or(DMat3::IDENTITY, |r| DMat3::from_quat(r.at(t)));
        let s = self.scale.as_ref().map_or(DVec3::ONE, |s| s.at(t));
        let translation = self.translation.as_ref().map_or(DVec3::ZERO, |p| p.at(t));
        DMat4::from_cols(
            (r.x_axis * s.x).extend(0.0),
            (r.y_axis * s.y).extend(0.0),
            (r.z_axis * s.z).extend(0.0),
            translation.extend(1.0),
        )
    }

    /// The viewer at BART time `t`, with what the track leaves out taken from the `v` block
    /// (position without `transl`, direction and up without `rot`).
    pub fn camera(&self, t: f64, view: &View) -> Camera {
        let m = self.matrix(t);
        let position = match &self.translation {
            Some(p) => p.at(t).as_vec3(),
            None => view.from,
        };
        let (direction, up) = match &self.rotation {
            Some(_) => (
                -m.z_axis.truncate().as_vec3(),
                m.y_axis.truncate().as_vec3(),
            ),
            None => (view.at - view.from, view.up),
        };
        Camera {
            position,
            target: position + direction.normalize(),
            up,
            ..view.camera()
        }
    }
}

/// After `k`: the track's name and its splines.
pub fn parse(t: &mut Tokens) -> Result<(String, TransformTrack)> {
    let name = t.word("keyframe block name")?.to_string();
    t.keyword("{")?;
    let mut track = TransformTrack::default();
    loop {
        let kind = t.word("'transl', 'rot', 'scale' or '}'")?;
        if kind == "}" {
            return Ok((name, track));
        }
        let words_each = match kind {
            "transl" | "scale" => 7,
            "rot" => 8,
            "visibility" => {
                return Err(t.error(
                    "visibility keyframes are not supported (triangle counts must stay fixed)",
                ))
            }
            _ => return Err(t.error(format!("unknown keyframe kind '{kind}' in '{name}'"))),
        };
        let n = t.count("keyframe count", words_each)?;
        if n < 4 {
            return Err(t.error(format!(
                "'{kind}' of '{name}' has {n} keys; Kochanek–Bartels splines need at least 4"
            )));
        }
        match kind {
            "rot" => {
                let mut keys = Vec::with_capacity(n);
                for _ in 0..n {
                    let time = t.number("key time")?;
                    let axis = t.vec3("rotation axis")?;
                    let degrees = t.number("rotation angle")?;
                    let axis = unit_axis(t, axis, degrees)?;
                    keys.push(tcb(t, time, (axis, f64::from(degrees).to_radians()))?);
                }
                track.rotation = Some(RotationSpline::new(&keys));
            }
            _ => {
                let mut keys = Vec::with_capacity(n);
                for _ in 0..n {
                    let time = t.number("key time")?;
                    let value = t.vec3(if kind == "scale" {
                        "scale"
                    } else {
                        "translation"
                    })?;
                    keys.push(tcb(t, time, value.as_dvec3())?);
                }
                let spline = Some(PositionSpline::new(&keys));
                if kind == "scale" {
                    track.scale = spline;
                } else {
                    track.translation = spline;
                }
            }
        }
    }
}

/// The rest of a key: tension, continuity, bias.
fn tcb<T>(t: &mut Tokens, time: f32, value: T) -> Result<Key<T>> {
    Ok(Key {
        time: time.into(),
        value,
        tension: t.number("tension")?.into(),
        continuity: t.number("continuity")?.into(),
        bias: t.number("bias")?.into(),
    })
}

/// A rotation axis as a unit vector. BART's code assumes the files give unit axes; some are off
/// by a few per cent (robots' grippers use (0.76, −0.62, −0.445)), and BART's angle–axis round
/// trip makes the keys themselves come out as rotations about the normalised axis, so that is
/// what they mean. A zero axis is only accepted with a zero angle.
pub fn unit_axis(t: &Tokens, axis: Vec3, degrees: f32) -> Result<DVec3> {
    let axis = axis.as_dvec3();
    if axis.length_squared() > 0.0 {
        Ok(axis.normalize())
    } else if degrees == 0.0 {
        Ok(DVec3::X)
    } else {
        Err(t.error(format!("rotation of {degrees}° about a zero axis")))
    }
}

/// The static transform of `xs`: T·R·S from scale, axis and angle in degrees, translation.
pub fn static_transform(scale: Vec3, axis: DVec3, degrees: f32, translation: Vec3) -> DMat4 {
    DMat4::from_scale_rotation_translation(
        scale.as_dvec3(),
        DQuat::from_axis_angle(axis, f64::from(degrees).to_radians()),
        translation.as_dvec3(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    #[test]
    fn track_composes_translation_rotation_scale() {
        // Constant keys (the rotation axis given at two lengths), so every time gives the same
        // transform.
        let text = "car { transl 4\n 0 1 2 3 0 0 0\n 1 1 2 3 0 0 0\n 2 1 2 3 0 0 0\n 3 1 2 3 0 0 0\n\
                    rot 4\n 0 0 1 0 90 0 0 0\n 1 0 2 0 90 0 0 0\n 2 0 1 0 90 0 0 0\n 3 0 1 0 90 0 0 0\n\
                    scale 4\n 0 2 1 1 0 0 0\n 1 2 1 1 0 0 0\n 2 2 1 1 0 0 0\n 3 2 1 1 0 0 0 }";
        let mut t = Tokens::new(Path::new("k.aff"), text);
        let (name, track) = parse(&mut t).unwrap();
        assert_eq!(name, "car");
        // Scale x by 2, rotate 90° about y (x → −z), translate by (1, 2, 3).
        let p = track.matrix(1.5).transform_point3(DVec3::X);
        assert!((p - DVec3::new(1.0, 2.0, 1.0)).length() < 1e-12, "{p}");
    }

    #[test]
    fn bad_blocks_are_refused_at_their_line() {
        let cases = [
            ("a {\n transl 3\n 0 0 0 0 0 0 0\n 1 0 0 0 0 0 0\n 2 0 0 0 0 0 0\n}", 2, "at least 4"),
            ("a {\n visibility 1\n 0 1 }", 2, "visibility"),
            ("a {\n spin 4 }", 2, "unknown keyframe kind"),
            (
                "a {\n rot 4\n 0 0 0 0 10 0 0 0\n 1 0 1 0 0 0 0 0\n 2 0 1 0 0 0 0 0\n 3 0 1 0 0 0 0 0\n}",
                3,
                "zero axis",
            ),
            ("a \n[", 2, "expected '{'"),
        ];
        for (text, line, what) in cases {
            let mut t = Tokens::new(Path::new("k.aff"), text);
            let err = parse(&mut t).unwrap_err().to_string();
            assert!(
                err.starts_with(&format!("k.aff:{line}:")) && err.contains(what),
                "{err}"
            );
        }
    }
}
