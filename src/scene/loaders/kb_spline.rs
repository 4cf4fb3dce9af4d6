//! Kochanek–Bartels splines (Kochanek and Bartels, "Interpolating Splines with Local Tension,
//! Continuity, and Bias Control", SIGGRAPH 1984), evaluated exactly as BART does: BART animates
//! with Dave Eberly's `kbsplpos.c` (positions, scales) and `kbsplrot.c` (rotations, as squad
//! quaternion splines), and the motion the benchmark defines is the motion those produce.
//!
//! With n keys there are n − 3 pieces: the first and the last key only shape the end tangents,
//! so the curve runs from key 1 to key n − 2 and is clamped outside. Each key carries its own
//! tension T, continuity C and bias B; the tangents at key i for the piece (i, i+1) are
//!
//! ```text
//! out_i = adj · ½(1−T)[(1+C)(1+B)(P_i − P_{i−1}) + (1−C)(1−B)(P_{i+1} − P_i)],
//!         adj = 2(t_{i+1} − t_i)/(t_{i+1} − t_{i−1})   (uneven key spacing, KB §5)
//! in_{i+1} = adj' · ½(1−T)[(1−C)(1+B)(P_{i+1} − P_i) + (1+C)(1−B)(P_{i+2} − P_{i+1})],
//!         adj' = 2(t_{i+1} − t_i)/(t_{i+2} − t_i)
//! ```
//!
//! and the piece is the cubic Hermite curve between them. Rotations use the same weights on
//! quaternion logarithms and interpolate with squad (Shoemake 1987).

use glam::{DQuat, DVec3};

/// One key: value at `time` with its tension, continuity and bias.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Key<T> {
    pub time: f64,
    pub value: T,
    pub tension: f64,
    pub continuity: f64,
    pub bias: f64,
}

/// Tangent weights of the piece from key 1 to key 2 of four consecutive keys:
/// `(out0, out1, in0, in1)` as in Eberly's code (see the module comment).
fn tangent_weights<T>(k: [&Key<T>; 4]) -> (f64, f64, f64, f64) {
    let span = k[2].time - k[1].time;
    // Keys that share a time give a zero denominator; the C code would produce inf/NaN in a
    // piece it never evaluates (its span is zero), so any finite weight is equivalent there.
    let ratio = |d: f64| if d != 0.0 { 2.0 * span / d } else { 0.0 };
    let (adj0, adj1) = (ratio(k[2].time - k[0].time), ratio(k[3].time - k[1].time));
    let (t1, c1, b1) = (k[1].tension, k[1].continuity, k[1].bias);
    let (t2, c2, b2) = (k[2].tension, k[2].continuity, k[2].bias);
    (
        0.5 * adj0 * (1.0 - t1) * (1.0 + c1) * (1.0 + b1),
        0.5 * adj0 * (1.0 - t1) * (1.0 - c1) * (1.0 - b1),
        0.5 * adj1 * (1.0 - t2) * (1.0 - c2) * (1.0 + b2),
        0.5 * adj1 * (1.0 - t2) * (1.0 + c2) * (1.0 - b2),
    )
}

/// The piece holding time `t` and the parameter in it, clamped to the curve's ends. The search
/// is the C code's linear one: the first piece that ends after `t`. Real files have keys out of
/// order (robots' `gun_rot1` jumps back from 48 to 42); this rule defines what they mean.
fn locate(spans: impl ExactSizeIterator<Item = (f64, f64)> + Clone, t: f64) -> (usize, f64) {
    let n = spans.len();
    let first_start = spans.clone().next().map_or(0.0, |s| s.0);
    let last_end = spans.clone().last().map_or(0.0, |s| s.1);
    if t <= first_start {
        return (0, 0.0);
    }
    if t >= last_end {
        return (n - 1, 1.0);
    }
    let (i, (t0, t1)) = spans
        .enumerate()
        .find(|(_, (_, end))| t < *end)
        .unwrap_or((n - 1, (0.0, 1.0)));
    let u = if t1 > t0 { (t - t0) / (t1 - t0) } else { 0.0 };
    (i, u)
}

/// A curve through 3D points (translations and scales).
#[derive(Clone, Debug)]
pub struct PositionSpline {
    /// Per piece: the cubic's coefficients and its time span.
    pieces: Vec<([DVec3; 4], f64, f64)>,
}

impl PositionSpline {
    /// `keys.len() >= 4` (the caller checks and reports it).
    pub fn new(keys: &[Key<DVec3>]) -> Self {
        let pieces = keys
            .windows(4)
            .map(|k| {
                let (out0, out1, in0, in1) = tangent_weights([&k[0], &k[1], &k[2], &k[3]]);
                let d = k[2].value - k[1].value;
                let t_out = out1 * d + out0 * (k[1].value - k[0].value);
                let t_in = in1 * (k[3].value - k[2].value) + in0 * d;
                let c = [
                    k[1].value,
                    t_out,
                    3.0 * d - 2.0 * t_out - t_in,
                    -2.0 * d + t_out + t_in,
                ];
                (c, k[1].time, k[2].time)
            })
            .collect();
        PositionSpline { pieces }
    }

    pub fn at(&self, t: f64) -> DVec3 {
        let (i, u) = locate(self.pieces.iter().map(|p| (p.1, p.2)), t);
        let c = &self.pieces[i].0;
        c[0] + u * (c[1] + u * (c[2] + u * c[3]))
    }
}

/// A curve through rotations: per piece, squad between the keys' quaternions with inner control
/// points built from the KB tangents of their logarithms.
#[derive(Clone, Debug)]
pub struct RotationSpline {
    /// Per piece: squad's p, a, b, q and the time span.
    pieces: Vec<([DQuat; 4], f64, f64)>,
}

/// Below this, angles and sines count as zero (Eberly's `epsilon`).
const EPSILON: f64 = 1e-6;

impl RotationSpline {
    /// Keys hold (unit axis, angle in radians); `keys.len() >= 4`.
    pub fn new(keys: &[Key<(DVec3, f64)>]) -> Self {
        let mut q: Vec<DQuat> = keys
            .iter()
            .map(|k| from_angle_axis(k.value.1, k.value.0))
            .collect();
        let mut pieces = Vec::with_capacity(keys.len().saturating_sub(3));
        for i in 0..keys.len().saturating_sub(3) {
            // As in kbsplrot.c: key i+2 is negated when needed to make an acute angle with key
            // i+1, in place and piece by piece, so a piece sees its fourth key before that key
            // was (possibly) negated for the next piece.
            if q[i + 1].dot(q[i + 2]) < 0.0 {
                q[i + 2] = -q[i + 2];
            }
            let (q0, q1, q2, q3) = (q[i], q[i + 1], q[i + 2], q[i + 3]);
            let (out0, out1, in0, in1) =
                tangent_weights([&keys[i], &keys[i + 1], &keys[i + 2], &keys[i + 3]]);
            let log_dq = log(q1.conjugate() * q2);
            let t_out = log_dq * out1 + log(q0.conjugate() * q1) * out0;
            let t_in = log_dq * in0 + log(q2.conjugate() * q3) * in1;
            let a = q1 * exp((t_out - log_dq) * 0.5);
            let b = q2 * exp((log_dq - t_in) * 0.5);
            pieces.push(([q1, a, b, q2], keys[i + 1].time, keys[i + 2].time));
        }
        RotationSpline { pieces }
    }

    /// The unit rotation at time `t`. Like BART, the squad result goes through angle–axis form
    /// (`ToAngleAxis`, then `FromAngleAxis` when the matrix is built), which renormalises it.
    pub fn at(&self, t: f64) -> DQuat {
        let (i, s) = locate(self.pieces.iter().map(|p| (p.1, p.2)), t);
        let [p, a, b, q] = self.pieces[i].0;
        let squad = slerp(2.0 * s * (1.0 - s), slerp(s, p, q), slerp(s, a, b));
        let v = DVec3::new(squad.x, squad.y, squad.z);
        if v.length_squared() > 0.0 {
            from_angle_axis(2.0 * squad.w.clamp(-1.0, 1.0).acos(), v.normalize())
        } else {
            DQuat::IDENTITY
        }
    }
}

fn from_angle_axis(angle: f64, axis: DVec3) -> DQuat {
    let (s, c) = (0.5 * angle).sin_cos();
    DQuat::from_xyzw(s * axis.x, s * axis.y, s * axis.z, c)
}

/// Quaternion logarithm (a pure quaternion), for unit input.
fn log(q: DQuat) -> DQuat {
    let mut coeff = 1.0;
    if q.w.abs() < 1.0 {
        let angle = q.w.acos();
        let sin = angle.sin();
        if sin.abs() >= EPSILON {
            coeff = angle / sin;
        }
    }
    DQuat::from_xyzw(coeff * q.x, coeff * q.y, coeff * q.z, 0.0)
}

/// Quaternion exponential of a pure quaternion.
fn exp(q: DQuat) -> DQuat {
    let angle = DVec3::new(q.x, q.y, q.z).length();
    let (sin, cos) = angle.sin_cos();
    let coeff = if sin.abs() >= EPSILON {
        sin / angle
    } else {
        1.0
    };
    DQuat::from_xyzw(coeff * q.x, coeff * q.y, coeff * q.z, cos)
}

/// Spherical interpolation without the shortest-path flip (Eberly's, which squad needs: its
/// control points must not be negated behind its back).
fn slerp(t: f64, p: DQuat, q: DQuat) -> DQuat {
    let angle = p.dot(q).clamp(-1.0, 1.0).acos();
    let sin = angle.sin();
    // Eberly tests the angle only; opposite quaternions (sin = 0 at angle π) would divide by zero.
    if angle.abs() < EPSILON || sin.abs() < EPSILON {
        return p;
    }
    p * (((1.0 - t) * angle).sin() / sin) + q * ((t * angle).sin() / sin)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key<T>(time: f64, value: T) -> Key<T> {
        Key {
            time,
            value,
            tension: 0.0,
            continuity: 0.0,
            bias: 0.0,
        }
    }

    #[test]
    fn position_spline_interpolates_inner_keys_and_clamps() {
        let pts = [
            (-1.0, DVec3::new(5.0, 5.0, 5.0)),
            (0.0, DVec3::ZERO),
            (1.0, DVec3::new(1.0, 2.0, 0.0)),
            (3.0, DVec3::new(4.0, 0.0, -1.0)),
            (4.0, DVec3::new(0.0, 9.0, 0.0)),
        ];
        let keys: Vec<_> = pts.iter().map(|&(t, p)| key(t, p)).collect();
        let s = PositionSpline::new(&keys);
        for &(t, p) in &pts[1..4] {
            assert!((s.at(t) - p).length() < 1e-12, "at {t}");
        }
        // Clamped to the first and last inner keys.
        assert!((s.at(-5.0) - pts[1].1).length() < 1e-12);
        assert!((s.at(10.0) - pts[3].1).length() < 1e-12);
    }

    #[test]
    fn catmull_rom_midpoint_by_hand() {
        // Evenly spaced keys with T = C = B = 0 give Catmull–Rom: tangents (P2 − P0)/2 and
        // (P3 − P1)/2, so at the middle of the piece P(½) = (−P0 + 9P1 + 9P2 − P3)/16.
        let p = [0.0, 1.0, 3.0, 7.0].map(|x| DVec3::new(x, 0.0, 0.0));
        let keys: Vec<_> = (0..4).map(|i| key(i as f64, p[i])).collect();
        let s = PositionSpline::new(&keys);
        let expected = (-p[0] + 9.0 * p[1] + 9.0 * p[2] - p[3]) / 16.0;
        assert!((s.at(1.5) - expected).length() < 1e-12);
        // Tension 1 kills the tangents: the piece becomes the smoothstep between P1 and P2.
        let tense: Vec<_> = keys.iter().map(|k| Key { tension: 1.0, ..*k }).collect();
        let s = PositionSpline::new(&tense);
        let u: f64 = 0.25;
        let smooth = p[1] + (p[2] - p[1]) * (3.0 * u * u - 2.0 * u * u * u);
        assert!((s.at(1.25) - smooth).length() < 1e-12);
    }

    #[test]
    fn rotation_spline_hits_keys_and_turns_monotonically_about_one_axis() {
        // Quarter turns about z at times 0..4: between keys the rotation stays about z and its
        // angle lies between the neighbouring keys' angles.
        let angles = [0.0f64, 0.0, 90.0, 180.0, 270.0, 270.0];
        let keys: Vec<_> = angles
            .iter()
            .enumerate()
            .map(|(i, a)| key(i as f64 - 1.0, (DVec3::Z, a.to_radians())))
            .collect();
        let s = RotationSpline::new(&keys);
        for (i, a) in angles.iter().enumerate().take(5).skip(1) {
            let q = s.at(i as f64 - 1.0);
            let expected = DQuat::from_rotation_z(a.to_radians());
            assert!(q.dot(expected).abs() > 1.0 - 1e-12, "key {i}");
        }
        let q = s.at(1.5);
        let (axis, angle) = q.to_axis_angle();
        assert!((axis - DVec3::Z).length() < 1e-9);
        assert!(angle > 90f64.to_radians() && angle < 180f64.to_radians());
        // By symmetry of the evenly spaced keys 90°, 180° about the middle, it is 135° there.
        assert!((angle - 135f64.to_radians()).abs() < 1e-9);
    }
}
