//! Ear clipping for simple planar polygons, convex or not (Eberly, "Triangulation by Ear
//! Clipping", 2002; Meisters' two-ears theorem). A fan is only right for convex polygons, and
//! the SPD gears are not: their faces are toothed outlines of up to 144 vertices.
//!
//! The polygon is projected onto the coordinate plane most parallel to it — the one that drops
//! the largest component of its Newell normal — so that nearly vertical faces keep their shape.

use glam::{DVec2, DVec3, Vec3};

/// Triangles (index triples into `polygon`) covering a polygon of `n >= 3` vertices: always
/// `n - 2` of them, with the polygon's own winding. Degenerate input (repeated or collinear
/// vertices) still gives `n - 2` triangles, some of zero area, so counts stay predictable.
pub fn triangulate(polygon: &[Vec3]) -> Vec<[usize; 3]> {
    let n = polygon.len();
    if n < 3 {
        return Vec::new();
    }
    if n == 3 {
        return vec![[0, 1, 2]];
    }
    let points = project(polygon);
    let mut remaining: Vec<usize> = (0..n).collect();
    let mut triangles = Vec::with_capacity(n - 2);
    let mut at = 0;
    while remaining.len() > 3 {
        let m = remaining.len();
        let ear = (0..m)
            .map(|k| (at + k) % m)
            .find(|&i| is_ear(&points, &remaining, i))
            .unwrap_or_else(|| least_bad_corner(&points, &remaining));
        let prev = remaining[(ear + m - 1) % m];
        let next = remaining[(ear + 1) % m];
        triangles.push([prev, remaining[ear], next]);
        remaining.remove(ear);
        // Continue next to the clipped corner: neighbours of an ear often become ears.
        at = if ear == 0 { 0 } else { ear - 1 };
    }
    triangles.push([remaining[0], remaining[1], remaining[2]]);
    triangles
}

/// The polygon in 2D, counter-clockwise: the coordinate plane that drops the largest component of
/// the Newell normal, mirrored when that component is negative.
fn project(polygon: &[Vec3]) -> Vec<DVec2> {
    let mut normal = DVec3::ZERO;
    for (i, a) in polygon.iter().enumerate() {
        let a = a.as_dvec3();
        let b = polygon[(i + 1) % polygon.len()].as_dvec3();
        normal += DVec3::new(
            (a.y - b.y) * (a.z + b.z),
            (a.z - b.z) * (a.x + b.x),
            (a.x - b.x) * (a.y + b.y),
        );
    }
    let abs = normal.abs();
    let drop = if abs.x >= abs.y && abs.x >= abs.z {
        0
    } else if abs.y >= abs.z {
        1
    } else {
        2
    };
    let (u, v) = ((drop + 1) % 3, (drop + 2) % 3);
    // (u, v, drop) is a cyclic permutation of (x, y, z), so the projection is counter-clockwise
    // exactly when the dropped normal component is positive.
    let flip = if normal[drop] < 0.0 { -1.0 } else { 1.0 };
    polygon
        .iter()
        .map(|p| {
            let p = p.as_dvec3();
            DVec2::new(p[u], flip * p[v])
        })
        .collect()
}

/// Twice the signed area of (a, b, c): positive when counter-clockwise.
fn orient(a: DVec2, b: DVec2, c: DVec2) -> f64 {
    (b - a).perp_dot(c - a)
}

fn corner(points: &[DVec2], remaining: &[usize], i: usize) -> (DVec2, DVec2, DVec2) {
    let m = remaining.len();
    (
        points[remaining[(i + m - 1) % m]],
        points[remaining[i]],
        points[remaining[(i + 1) % m]],
    )
}

/// A strictly convex corner whose triangle holds no other remaining vertex (on its boundary
/// counts as inside, so no clipped triangle ever touches the rest of the outline).
fn is_ear(points: &[DVec2], remaining: &[usize], i: usize) -> bool {
    let (a, b, c) = corner(points, remaining, i);
    if orient(a, b, c) <= 0.0 {
        return false;
    }
    let m = remaining.len();
    (0..m)
        .filter(|&k| k != i && k != (i + 1) % m && k != (i + m - 1) % m)
        .map(|k| points[remaining[k]])
        .filter(|&p| p != a && p != b && p != c)
        .all(|p| orient(a, b, p) < 0.0 || orient(b, c, p) < 0.0 || orient(c, a, p) < 0.0)
}

/// When no ear exists (collinear or self-touching input), clip the most convex corner so that the
/// result still has `n - 2` triangles.
fn least_bad_corner(points: &[DVec2], remaining: &[usize]) -> usize {
    (0..remaining.len())
        .max_by(|&i, &j| {
            let (a, b, c) = corner(points, remaining, i);
            let (d, e, f) = corner(points, remaining, j);
            orient(a, b, c).total_cmp(&orient(d, e, f))
        })
        .unwrap_or(0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Triangle;

    /// Signed area of a polygon in the xy plane (shoelace).
    fn shoelace(p: &[Vec3]) -> f32 {
        (0..p.len())
            .map(|i| {
                let (a, b) = (p[i], p[(i + 1) % p.len()]);
                a.x * b.y - b.x * a.y
            })
            .sum::<f32>()
            * 0.5
    }

    /// Even-odd point-in-polygon test in the xy plane.
    fn inside(p: &[Vec3], q: Vec3) -> bool {
        let mut c = false;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            if (a.y > q.y) != (b.y > q.y) && q.x < (b.x - a.x) * (q.y - a.y) / (b.y - a.y) + a.x {
                c = !c;
            }
        }
        c
    }

    fn check_cover(polygon: &[Vec3]) {
        let tris = triangulate(polygon);
        assert_eq!(tris.len(), polygon.len() - 2);
        let mut area = 0.0;
        for t in &tris {
            let tri = Triangle::new(polygon[t[0]], polygon[t[1]], polygon[t[2]]);
            // Same winding as the polygon (counter-clockwise seen from +z).
            assert!(tri.normal().z > 0.0, "triangle {t:?} flipped");
            area += tri.area();
            assert!(inside(polygon, tri.centroid()), "triangle {t:?} outside");
        }
        assert!((area - shoelace(polygon)).abs() < 1e-4 * shoelace(polygon));
    }

    #[test]
    fn comb_is_cut_into_n_minus_2_triangles_inside_it() {
        // A comb with three teeth: a fan from vertex 0 would cross the gaps between the teeth.
        let comb: Vec<Vec3> = [
            (0.0, 0.0),
            (5.0, 0.0),
            (5.0, 3.0),
            (4.0, 3.0),
            (4.0, 1.0),
            (3.0, 1.0),
            (3.0, 3.0),
            (2.0, 3.0),
            (2.0, 1.0),
            (1.0, 1.0),
            (1.0, 3.0),
            (0.0, 3.0),
        ]
        .iter()
        .map(|&(x, y)| Vec3::new(x, y, 0.0))
        .collect();
        assert_eq!(shoelace(&comb), 5.0 * 3.0 - 2.0 * 2.0);
        // The fan from vertex 0 puts triangle (0, 6, 7) across the gap between two teeth.
        let fan = Triangle::new(comb[0], comb[6], comb[7]);
        assert!(!inside(&comb, fan.centroid()));
        check_cover(&comb);
    }

    #[test]
    fn vertical_clockwise_polygon_keeps_its_winding() {
        // An L in the xz plane, listed clockwise seen from +y: the triangles' normals must agree
        // with the polygon's Newell normal (-y).
        let l: Vec<Vec3> = [
            (0.0, 0.0),
            (0.0, 2.0),
            (1.0, 2.0),
            (1.0, 1.0),
            (2.0, 1.0),
            (2.0, 0.0),
        ]
        .iter()
        .map(|&(x, z)| Vec3::new(x, 5.0, z))
        .collect();
        let tris = triangulate(&l);
        assert_eq!(tris.len(), 4);
        let area: f32 = tris
            .iter()
            .map(|t| {
                let tri = Triangle::new(l[t[0]], l[t[1]], l[t[2]]);
                assert_eq!(tri.normal().y.signum(), newell_y_sign(&l));
                tri.area()
            })
            .sum();
        assert!((area - 3.0).abs() < 1e-5);
    }

    /// Sign of the Newell normal's y for a polygon in a plane of constant y.
    fn newell_y_sign(p: &[Vec3]) -> f32 {
        let mut ny = 0.0;
        for i in 0..p.len() {
            let (a, b) = (p[i], p[(i + 1) % p.len()]);
            ny += (a.z - b.z) * (a.x + b.x);
        }
        ny.signum()
    }

    #[test]
    fn degenerate_polygons_still_give_n_minus_2_triangles() {
        let collinear: Vec<Vec3> = (0..6).map(|i| Vec3::new(i as f32, 0.0, 0.0)).collect();
        assert_eq!(triangulate(&collinear).len(), 4);
        let repeated = vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::Y, Vec3::Y];
        let tris = triangulate(&repeated);
        assert_eq!(tris.len(), 3);
        let area: f32 = tris
            .iter()
            .map(|t| Triangle::new(repeated[t[0]], repeated[t[1]], repeated[t[2]]).area())
            .sum();
        assert!((area - 0.5).abs() < 1e-6);
    }
}
