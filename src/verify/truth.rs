//! The f64 ground truth that decides who is right when a tracer and Embree disagree: every triangle
//! of the mesh tested against the ray in double precision, on the very same f32 data, with how far
//! each hit or near miss lies from the triangle's edges and from the ends of the ray's interval.
//!
//! Double precision has 29 more bits than the data, so its edge functions and distances are
//! exact to far below an f32 tracer's rounding. Where a hit or miss lies within `tolerance` (the
//! rounding of f32 arithmetic at the coordinates' magnitude: `EDGE_GRAZE_ULPS` ULPs, the same
//! bound verification calls an edge graze) of an edge or an end of the interval, rounding decides
//! and either answer is right: the hit is *uncertain*. Everything else is *certain*, and a tracer
//! that contradicts it is wrong.
//!
//! A ray that is not well formed (`Ray::is_well_formed`) has no hits at all: raylab's defined
//! answer for NaN or infinite components, a zero direction, or an empty or NaN interval is a miss.

use glam::DVec3;
#[cfg(test)]
use glam::Vec3;

use crate::geometry::{Hit, Ray, Triangle};
use crate::scene::Mesh;
use crate::verify::compare::EDGE_GRAZE_ULPS;

/// One triangle the ray meets in f64, or passes within rounding of.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ExactHit {
    pub prim: u32,
    pub t: f64,
    /// Farther than `tolerance` from every edge and from both ends of the interval.
    pub certain: bool,
}

/// Every triangle a ray meets, nearest first.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Truth {
    pub hits: Vec<ExactHit>,
    /// The rounding bound along the ray, in world units.
    pub tolerance: f64,
    /// The ray's direction length, to turn parameter differences into distances.
    pub dir_length: f64,
}

/// How an answer compares with the ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Verdict {
    /// The answer is the f64 answer.
    Right,
    /// The answer differs from the f64 answer only where rounding decides.
    Rounding,
    /// A certain hit (nearer than the one given, or any, for a miss) was missed.
    Missed,
    /// A hit on a triangle the ray certainly misses, or at a distance it is not at.
    FalseHit,
}

impl Verdict {
    pub fn is_wrong(self) -> bool {
        matches!(self, Verdict::Missed | Verdict::FalseHit)
    }
}

impl Truth {
    /// Tests `ray` against every triangle of `mesh` in f64.
    pub fn of(mesh: &Mesh, ray: &Ray) -> Truth {
        if !ray.is_well_formed() {
            return Truth::default();
        }
        let o = ray.origin.as_dvec3();
        let d = ray.dir.as_dvec3();
        let dir_length = d.length();
        let mut tolerance: f64 = 0.0;
        let mut hits: Vec<ExactHit> = mesh
            .triangles
            .iter()
            .enumerate()
            .filter_map(|(prim, tri)| {
                let tol = rounding(tri, ray);
                let hit = exact_hit(tri, o, d, tol)?;
                let interval = [ray.tmin as f64, ray.tmax as f64];
                let t = hit.t;
                let near_end = interval
                    .iter()
                    .any(|&end| end.is_finite() && (t - end).abs() * dir_length <= tol);
                let inside = t >= interval[0] && t <= interval[1];
                if !inside && !near_end {
                    return None;
                }
                tolerance = tolerance.max(tol);
                Some(ExactHit {
                    prim: prim as u32,
                    t,
                    certain: hit.clear && inside && !near_end,
                })
            })
            .collect();
        hits.sort_by(|a, b| a.t.total_cmp(&b.t));
        Truth {
            hits,
            tolerance,
            dir_length,
        }
    }

    pub fn certain_hit(&self) -> bool {
        self.hits.iter().any(|h| h.certain)
    }

    /// Judges a closest-hit answer.
    pub fn judge_closest(&self, hit: &Hit) -> Verdict {
        let nearest_certain = self.hits.iter().find(|h| h.certain);
        if !hit.is_hit() {
            return match (nearest_certain, self.hits.is_empty()) {
                (Some(_), _) => Verdict::Missed,
                (None, true) => Verdict::Right,
                (None, false) => Verdict::Rounding,
            };
        }
        let Some(given) = self.hits.iter().find(|h| h.prim == hit.prim) else {
            return Verdict::FalseHit;
        };
        // The distance reported must be where the triangle is (rounding allowed).
        let slack = 4.0 * self.tolerance + 1e-5 * given.t.abs() * self.dir_length;
        if (hit.t as f64 - given.t).abs() * self.dir_length > slack {
            return Verdict::FalseHit;
        }
        match nearest_certain {
            Some(c) if (given.t - c.t) * self.dir_length > slack => Verdict::Missed,
            _ if given.certain && self.hits[0].prim == given.prim => Verdict::Right,
            _ => Verdict::Rounding,
        }
    }

    /// Judges an occlusion answer.
    pub fn judge_occluded(&self, occluded: bool) -> Verdict {
        match (occluded, self.certain_hit(), self.hits.is_empty()) {
            (true, _, true) => Verdict::FalseHit,
            (false, true, _) => Verdict::Missed,
            (true, true, _) | (false, _, true) => Verdict::Right,
            _ => Verdict::Rounding,
        }
    }
}

/// The exact distance (ray parameter) at which `ray` meets the plane of `tri` inside it or
/// within rounding of its edges, in f64; `None` where it passes farther from it.
pub fn distance(tri: &Triangle, ray: &Ray) -> Option<f64> {
    let hit = exact_hit(
        tri,
        ray.origin.as_dvec3(),
        ray.dir.as_dvec3(),
        rounding(tri, ray),
    )?;
    Some(hit.t)
}

/// The rounding bound of an f32 intersection of `ray` with `tri`: `EDGE_GRAZE_ULPS` ULPs of the
/// largest coordinate magnitude involved (its vertices and the ray origin: a watertight test works
/// on the vertices relative to the origin).
fn rounding(tri: &Triangle, ray: &Ray) -> f64 {
    let scale = tri.v.iter().fold(ray.origin.abs().max_element(), |m, v| {
        m.max(v.abs().max_element())
    });
    (EDGE_GRAZE_ULPS * f32::EPSILON) as f64 * scale.max(f32::MIN_POSITIVE) as f64
}

/// Where the ray's line meets the triangle (`t`), and whether the meeting point lies farther
/// than `tol` inside every edge (`clear`); `None` when it passes farther than `tol` outside.
struct LineHit {
    t: f64,
    clear: bool,
}

fn exact_hit(tri: &Triangle, o: DVec3, d: DVec3, tol: f64) -> Option<LineHit> {
    let v = tri.v.map(|p| p.as_dvec3() - o);
    let n = (v[1] - v[0]).cross(v[2] - v[0]);
    let denom = d.dot(n);
    let d_len = d.length();
    let n_len = n.length();
    // Parallel to the plane (or a degenerate triangle): the ray grazes it, at best within
    // rounding. Such a triangle is an uncertain hit where the line passes within `tol` of it.
    if denom.abs() <= 1e-12 * d_len * n_len || n_len == 0.0 {
        return grazing(&v, d, tol);
    }
    let t = v[0].dot(n) / denom;
    let p = d * t;
    // Signed distance of `p` inside each edge, in the triangle's plane.
    let inside = (0..3).map(|i| {
        let (a, b) = (v[i], v[(i + 1) % 3]);
        let edge = b - a;
        n.cross(edge).dot(p - a) / (n_len * edge.length().max(f64::MIN_POSITIVE))
    });
    let clearance = inside.fold(f64::INFINITY, f64::min);
    (clearance >= -tol).then_some(LineHit {
        t,
        clear: clearance > tol,
    })
}

/// A ray in (or parallel to) the triangle's plane, or a degenerate triangle: an uncertain hit at
/// the line's closest approach to the nearest edge, when that approach is within `tol`.
fn grazing(v: &[DVec3; 3], d: DVec3, tol: f64) -> Option<LineHit> {
    let dd = d.dot(d);
    (0..3)
        .filter_map(|i| {
            let (a, b) = (v[i], v[(i + 1) % 3]);
            let (t, gap) = line_to_segment(d, dd, a, b);
            (gap <= tol).then_some(t)
        })
        .min_by(f64::total_cmp)
        .map(|t| LineHit { t, clear: false })
}

/// The parameter on the line `s·d` (origin 0) closest to segment `ab`, and that distance.
fn line_to_segment(d: DVec3, dd: f64, a: DVec3, b: DVec3) -> (f64, f64) {
    let e = b - a;
    let ee = e.dot(e);
    let de = d.dot(e);
    let denom = dd * ee - de * de;
    // Parameter along the segment of the closest approach, clamped to it.
    let u = if denom.abs() <= 1e-18 * dd * ee.max(f64::MIN_POSITIVE) {
        0.0
    } else {
        ((d.dot(a) * de - dd * e.dot(a)) / denom).clamp(0.0, 1.0)
    };
    let q = a + e * u;
    let t = d.dot(q) / dd;
    (t, (d * t - q).length())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn mesh(tris: &[Triangle]) -> Mesh {
        let mut m = Mesh::default();
        for t in tris {
            m.push(*t, 0);
        }
        m
    }

    fn unit_triangle(z: f32) -> Triangle {
        Triangle::new(
            Vec3::new(0.0, 0.0, z),
            Vec3::new(1.0, 0.0, z),
            Vec3::new(0.0, 1.0, z),
        )
    }

    fn down(x: f32, y: f32) -> Ray {
        Ray::new(Vec3::new(x, y, 5.0), -Vec3::Z, 0.0, f32::INFINITY)
    }

    #[test]
    fn inside_edge_and_outside_hits_are_certain_uncertain_and_absent() {
        let m = mesh(&[unit_triangle(0.0), unit_triangle(-1.0)]);
        let inside = Truth::of(&m, &down(0.25, 0.25));
        assert_eq!(inside.hits.len(), 2);
        assert_eq!((inside.hits[0].prim, inside.hits[0].t), (0, 5.0));
        assert!(inside.hits.iter().all(|h| h.certain));
        // On the hypotenuse x + y = 1: rounding decides.
        let edge = Truth::of(&m, &down(0.5, 0.5));
        assert_eq!(edge.hits.len(), 2);
        assert!(edge.hits.iter().all(|h| !h.certain));
        assert!(Truth::of(&m, &down(0.6, 0.6)).hits.is_empty());
    }

    #[test]
    fn verdicts_on_hand_worked_answers() {
        let m = mesh(&[unit_triangle(0.0), unit_triangle(-1.0)]);
        let truth = Truth::of(&m, &down(0.25, 0.25));
        let hit = |prim: u32, t: f32| Hit {
            t,
            prim,
            u: 0.0,
            v: 0.0,
        };
        assert_eq!(truth.judge_closest(&hit(0, 5.0)), Verdict::Right);
        assert_eq!(truth.judge_closest(&hit(1, 6.0)), Verdict::Missed);
        assert_eq!(truth.judge_closest(&hit(0, 5.5)), Verdict::FalseHit);
        assert_eq!(truth.judge_closest(&Hit::MISS), Verdict::Missed);
        assert_eq!(truth.judge_occluded(true), Verdict::Right);
        assert_eq!(truth.judge_occluded(false), Verdict::Missed);
        let edge = Truth::of(&m, &down(0.5, 0.5));
        assert_eq!(edge.judge_closest(&Hit::MISS), Verdict::Rounding);
        assert_eq!(edge.judge_closest(&hit(1, 6.0)), Verdict::Rounding);
        let nothing = Truth::of(&m, &down(2.0, 2.0));
        assert_eq!(nothing.judge_closest(&Hit::MISS), Verdict::Right);
        assert_eq!(nothing.judge_closest(&hit(0, 5.0)), Verdict::FalseHit);
        assert_eq!(nothing.judge_occluded(true), Verdict::FalseHit);
    }

    #[test]
    fn the_interval_ends_bound_the_hits_and_are_uncertain_at_the_boundary() {
        let m = mesh(&[unit_triangle(0.0)]);
        let short = Ray::new(Vec3::new(0.25, 0.25, 5.0), -Vec3::Z, 0.0, 4.0);
        assert!(Truth::of(&m, &short).hits.is_empty());
        let exact = Ray::new(Vec3::new(0.25, 0.25, 5.0), -Vec3::Z, 0.0, 5.0);
        let truth = Truth::of(&m, &exact);
        assert_eq!(truth.hits.len(), 1);
        assert!(!truth.hits[0].certain);
    }

    #[test]
    fn grazing_rays_and_degenerate_triangles_are_uncertain_never_certain() {
        let m = mesh(&[unit_triangle(0.0)]);
        let in_plane = Ray::new(Vec3::new(-1.0, 0.25, 0.0), Vec3::X, 0.0, f32::INFINITY);
        let truth = Truth::of(&m, &in_plane);
        assert_eq!(truth.hits.len(), 1);
        assert!(!truth.hits[0].certain);
        let above = Ray::new(Vec3::new(-1.0, 0.25, 0.01), Vec3::X, 0.0, f32::INFINITY);
        assert!(Truth::of(&m, &above).hits.is_empty());
        let p = Vec3::new(0.3, 0.3, 0.0);
        let point = mesh(&[Triangle::new(p, p, p)]);
        let through = Truth::of(&point, &down(0.3, 0.3));
        assert_eq!(through.hits.len(), 1);
        assert!(!through.hits[0].certain);
    }

    #[test]
    fn ill_formed_rays_have_no_hits() {
        let m = mesh(&[unit_triangle(0.0)]);
        let good = down(0.25, 0.25);
        let bad = [
            Ray {
                tmax: f32::NAN,
                ..good
            },
            Ray {
                tmin: 3.0,
                tmax: 3.0,
                ..good
            },
            Ray {
                tmin: 4.0,
                tmax: -1.0,
                ..good
            },
            Ray {
                dir: Vec3::ZERO,
                ..good
            },
            Ray {
                dir: Vec3::new(0.0, f32::NAN, -1.0),
                ..good
            },
            Ray {
                origin: Vec3::new(f32::INFINITY, 0.25, 5.0),
                ..good
            },
        ];
        assert!(good.is_well_formed());
        for ray in bad {
            assert!(!ray.is_well_formed(), "{ray:?}");
            assert_eq!(Truth::of(&m, &ray), Truth::default());
        }
    }
}
