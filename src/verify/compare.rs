//! Ray-by-ray comparison of a tracer's answer with the oracle's, and the classification of every
//! disagreement as a tie (with its reason) or as unexplained by the ties, which the f64 ground
//! truth then judges (`Judgement`, asked by `verify::classify`).

use crate::geometry::{Hit, Ray};
use crate::scene::Mesh;
use crate::verify::truth::Verdict;

/// Relative distance under which two hits count as "the same distance".
pub const SAME_DISTANCE: f32 = 1e-5;
/// Distance to an edge, in ULPs of the largest coordinate magnitude of the triangle, under which
/// a ray counts as grazing that edge: there rounding, not geometry, decides hit or miss. Measured
/// as a distance, not in barycentrics, so that long thin slivers are judged fairly.
pub const EDGE_GRAZE_ULPS: f32 = 16.0;

/// What differed between the two answers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Mismatch {
    /// One hit, the other missed.
    HitMiss,
    /// Both hit, different triangles.
    Primitive,
    /// Different occlusion flags.
    Occlusion,
}

/// Why a disagreement is a tie rather than an error.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Tie {
    /// Both hit at the same distance, on triangles sharing a vertex (so an edge or vertex was hit).
    SharedEdge,
    /// Both hit at the same distance, on coplanar triangles (overlapping geometry).
    Coplanar,
    /// Both hit at the same distance on unrelated triangles (intersecting geometry).
    SameDistance,
    /// The hit that one side lacks lies on an edge of its triangle, within `EDGE_GRAZE_ULPS`.
    EdgeGraze,
    /// The hit that one side lacks lies at the end of the ray's [tmin, tmax] interval.
    RangeBoundary,
}

impl Tie {
    pub const ALL: [Tie; 5] = [
        Tie::SharedEdge,
        Tie::Coplanar,
        Tie::SameDistance,
        Tie::EdgeGraze,
        Tie::RangeBoundary,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Tie::SharedEdge => "shared_edge",
            Tie::Coplanar => "coplanar",
            Tie::SameDistance => "same_distance",
            Tie::EdgeGraze => "edge_graze",
            Tie::RangeBoundary => "range_boundary",
        }
    }
}

/// Who the f64 ground truth (`verify::truth`) says is right about a disagreement the ties do not
/// explain.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Judgement {
    /// Ours right, Embree wrong.
    OursRight,
    /// Embree right, ours wrong.
    OursWrong,
    /// Both answers within rounding of the exact one.
    Rounding,
    /// The truth cannot decide: it contradicts both answers, or was not asked (the comparison
    /// functions here leave every disagreement undecided; `verify::classify` asks the truth
    /// within its budget).
    Undecided,
}

impl Judgement {
    pub const ALL: [Judgement; 4] = [
        Judgement::OursRight,
        Judgement::OursWrong,
        Judgement::Rounding,
        Judgement::Undecided,
    ];

    /// From the truth's verdicts on our answer and on Embree's.
    pub fn of(ours: Verdict, embree: Verdict) -> Judgement {
        match (ours.is_wrong(), embree.is_wrong()) {
            (false, true) => Judgement::OursRight,
            (true, false) => Judgement::OursWrong,
            (false, false) => Judgement::Rounding,
            (true, true) => Judgement::Undecided,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Judgement::OursRight => "ours_right",
            Judgement::OursWrong => "ours_wrong",
            Judgement::Rounding => "rounding",
            Judgement::Undecided => "undecided",
        }
    }

    /// Whether `raylab verify` fails on it: only when the truth says ours is wrong. (Of a
    /// tracer wrong everywhere, the first disagreements the truth's budget reaches are judged
    /// ours wrong, so a budget that runs out still fails it.)
    pub fn fails(self) -> bool {
        self == Judgement::OursWrong
    }

    /// Whether its ray goes to the replay file: the failing ones, and the undecided ones, which
    /// a person has to look at.
    pub fn replayed(self) -> bool {
        matches!(self, Judgement::OursWrong | Judgement::Undecided)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Agreement {
    Agree,
    Tie(Mismatch, Tie),
    /// Not a tie; judged by the f64 truth.
    Unexplained(Mismatch, Judgement),
}

/// A disagreement no tie explains, not judged yet.
fn unexplained(m: Mismatch) -> Agreement {
    Agreement::Unexplained(m, Judgement::Undecided)
}

fn same_distance(a: f32, b: f32) -> bool {
    (a - b).abs() <= SAME_DISTANCE * a.abs().max(b.abs())
}

/// Whether two hits on `ray` lie closer together than the intersection arithmetic can tell apart:
/// within `EDGE_GRAZE_ULPS` ULPs of the largest coordinate involved (both triangles, the ray
/// origin). This decides for very short hits — a refracted ray leaving a glass box where it stands
/// on the floor meets box and floor 1e-5 further on — where `same_distance`'s relative test asks
/// for more precision than the coordinates carry.
pub fn indistinguishable(mesh: &Mesh, ray: &Ray, a: &Hit, b: &Hit) -> bool {
    let scale = [a.prim, b.prim]
        .iter()
        .flat_map(|&p| mesh.triangles[p as usize].v)
        .fold(ray.origin.abs().max_element(), |m, v| {
            m.max(v.abs().max_element())
        });
    (a.t - b.t).abs() * ray.dir.length() <= EDGE_GRAZE_ULPS * scale * f32::EPSILON
}

fn grazes_edge(mesh: &Mesh, hit: &Hit) -> bool {
    let tri = &mesh.triangles[hit.prim as usize];
    let p = tri.point(hit.u, hit.v);
    let scale = tri
        .v
        .iter()
        .fold(p.abs().max_element(), |m, v| m.max(v.abs().max_element()));
    let tolerance = EDGE_GRAZE_ULPS * scale * f32::EPSILON;
    (0..3).any(|i| {
        let (a, b) = (tri.v[i], tri.v[(i + 1) % 3]);
        let edge = b - a;
        let along =
            ((p - a).dot(edge) / edge.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
        (a + edge * along).distance(p) <= tolerance
    })
}

pub fn at_range_end(ray: &Ray, hit: &Hit) -> bool {
    (ray.tmax.is_finite() && same_distance(hit.t, ray.tmax))
        || hit.t <= ray.tmin + SAME_DISTANCE * ray.tmin.abs().max(SAME_DISTANCE)
}

/// Why two triangles hit at the same distance are a tie.
fn tie_between(mesh: &Mesh, a: u32, b: u32) -> Tie {
    let (ta, tb) = (&mesh.triangles[a as usize], &mesh.triangles[b as usize]);
    if ta.v.iter().any(|p| tb.v.contains(p)) {
        return Tie::SharedEdge;
    }
    let (na, nb) = (
        ta.normal().normalize_or_zero(),
        tb.normal().normalize_or_zero(),
    );
    let scale = ta
        .bounds()
        .union(tb.bounds())
        .extent()
        .max_element()
        .max(f32::MIN_POSITIVE);
    let coplanar = na.cross(nb).length() < 1e-4 && (tb.v[0] - ta.v[0]).dot(na).abs() < 1e-5 * scale;
    if coplanar {
        Tie::Coplanar
    } else {
        Tie::SameDistance
    }
}

/// A hit present on one side only: a tie when the ray grazes an edge or ends at the hit.
fn one_sided(mesh: &Mesh, ray: &Ray, hit: &Hit, mismatch: Mismatch) -> Agreement {
    if grazes_edge(mesh, hit) {
        Agreement::Tie(mismatch, Tie::EdgeGraze)
    } else if at_range_end(ray, hit) {
        Agreement::Tie(mismatch, Tie::RangeBoundary)
    } else {
        unexplained(mismatch)
    }
}

/// Closest-hit comparison of `tested` against `reference` on `ray`.
pub fn closest(mesh: &Mesh, ray: &Ray, tested: &Hit, reference: &Hit) -> Agreement {
    closest_as(mesh, ray, tested, reference, None)
}

fn closest_as(
    mesh: &Mesh,
    ray: &Ray,
    tested: &Hit,
    reference: &Hit,
    as_mismatch: Option<Mismatch>,
) -> Agreement {
    match (tested.is_hit(), reference.is_hit()) {
        (false, false) => Agreement::Agree,
        (true, true) if tested.prim == reference.prim => Agreement::Agree,
        (true, true) => {
            let mismatch = as_mismatch.unwrap_or(Mismatch::Primitive);
            if same_distance(tested.t, reference.t)
                || indistinguishable(mesh, ray, tested, reference)
            {
                Agreement::Tie(mismatch, tie_between(mesh, tested.prim, reference.prim))
            } else {
                // One side missed the nearer triangle: fine only if that hit grazes an edge.
                let nearer = if tested.t < reference.t {
                    tested
                } else {
                    reference
                };
                one_sided(mesh, ray, nearer, mismatch)
            }
        }
        (true, false) => one_sided(mesh, ray, tested, as_mismatch.unwrap_or(Mismatch::HitMiss)),
        (false, true) => one_sided(
            mesh,
            ray,
            reference,
            as_mismatch.unwrap_or(Mismatch::HitMiss),
        ),
    }
}

/// Occlusion comparison. When the flags differ, the two sides' closest hits on the same ray say
/// why; if those agree with each other, the occlusion answer itself is inconsistent: unexplained.
pub fn occlusion(
    mesh: &Mesh,
    ray: &Ray,
    tested: bool,
    reference: bool,
    tested_hit: &Hit,
    reference_hit: &Hit,
) -> Agreement {
    if tested == reference {
        return Agreement::Agree;
    }
    match closest_as(
        mesh,
        ray,
        tested_hit,
        reference_hit,
        Some(Mismatch::Occlusion),
    ) {
        Agreement::Agree => {
            // Same closest answers, different flags: only a hit at the very end of the interval
            // can explain it (occlusion and closest-hit kernels may round tmax differently).
            let hit = if tested_hit.is_hit() {
                Some(tested_hit)
            } else {
                None
            };
            match hit {
                Some(h) if at_range_end(ray, h) => {
                    Agreement::Tie(Mismatch::Occlusion, Tie::RangeBoundary)
                }
                _ => unexplained(Mismatch::Occlusion),
            }
        }
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;
    use glam::Vec3;

    fn mesh() -> Mesh {
        let mut m = Mesh::default();
        // 0 and 1 share the diagonal of the unit square; 2 is coplanar with 0 and overlaps it;
        // 3 is far away and parallel.
        m.push(
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0)),
            0,
        );
        m.push(
            Triangle::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y),
            0,
        );
        m.push(
            Triangle::new(
                Vec3::new(0.1, 0.0, 0.0),
                Vec3::new(1.1, 0.0, 0.0),
                Vec3::new(1.1, 1.0, 0.0),
            ),
            0,
        );
        m.push(
            Triangle::new(
                Vec3::new(0.0, 0.0, -1.0),
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(0.0, 1.0, -1.0),
            ),
            0,
        );
        m
    }

    fn hit(t: f32, prim: u32, u: f32, v: f32) -> Hit {
        Hit { t, prim, u, v }
    }

    fn down() -> Ray {
        Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z, 0.0, f32::INFINITY)
    }

    #[test]
    fn equal_answers_agree() {
        let m = mesh();
        assert_eq!(
            closest(&m, &down(), &Hit::MISS, &Hit::MISS),
            Agreement::Agree
        );
        let h = hit(1.0, 0, 0.2, 0.3);
        assert_eq!(closest(&m, &down(), &h, &h), Agreement::Agree);
    }

    #[test]
    fn ties_are_classified() {
        let m = mesh();
        let r = down();
        assert_eq!(
            closest(&m, &r, &hit(1.0, 0, 0.0, 0.5), &hit(1.0, 1, 0.5, 0.0)),
            Agreement::Tie(Mismatch::Primitive, Tie::SharedEdge)
        );
        assert_eq!(
            closest(&m, &r, &hit(1.0, 0, 0.3, 0.3), &hit(1.0, 2, 0.3, 0.3)),
            Agreement::Tie(Mismatch::Primitive, Tie::Coplanar)
        );
        // One side hit triangle 0 on its edge and the other went on to triangle 3: a graze.
        assert_eq!(
            closest(&m, &r, &hit(2.0, 3, 0.3, 0.3), &hit(1.0, 0, 0.5, 0.0)),
            Agreement::Tie(Mismatch::Primitive, Tie::EdgeGraze)
        );
        assert_eq!(
            closest(&m, &r, &Hit::MISS, &hit(1.0, 0, 0.3, 1e-7)),
            Agreement::Tie(Mismatch::HitMiss, Tie::EdgeGraze)
        );
        // A ray starting 1e-4 above the plane: 1e-6 apart is 1% of the distance but below the
        // coordinates' precision (16 ULPs of 1 = 1.9e-6).
        let close = Ray::new(Vec3::new(0.5, 0.5, 1e-4), -Vec3::Z, 0.0, f32::INFINITY);
        assert_eq!(
            closest(
                &m,
                &close,
                &hit(1e-4, 0, 0.3, 0.3),
                &hit(1.01e-4, 2, 0.3, 0.3)
            ),
            Agreement::Tie(Mismatch::Primitive, Tie::Coplanar)
        );
        let short = Ray::new(Vec3::new(0.5, 0.5, 1.0), -Vec3::Z, 0.0, 1.0);
        assert_eq!(
            closest(&m, &short, &hit(1.0, 0, 0.3, 0.3), &Hit::MISS),
            Agreement::Tie(Mismatch::HitMiss, Tie::RangeBoundary)
        );
    }

    #[test]
    fn real_disagreements_are_unexplained() {
        let m = mesh();
        let r = down();
        assert_eq!(
            closest(&m, &r, &Hit::MISS, &hit(1.0, 0, 0.3, 0.3)),
            unexplained(Mismatch::HitMiss)
        );
        assert_eq!(
            closest(&m, &r, &hit(2.0, 3, 0.3, 0.3), &hit(1.0, 0, 0.3, 0.3)),
            unexplained(Mismatch::Primitive)
        );
        // Flags differ while both closest hits agree: inconsistent occlusion.
        let h = hit(1.0, 0, 0.3, 0.3);
        assert_eq!(
            occlusion(&m, &r, false, true, &h, &h),
            unexplained(Mismatch::Occlusion)
        );
        assert_eq!(
            occlusion(&m, &r, false, true, &Hit::MISS, &h),
            unexplained(Mismatch::Occlusion)
        );
        assert_eq!(
            occlusion(&m, &r, true, true, &Hit::MISS, &h),
            Agreement::Agree
        );
    }
}
