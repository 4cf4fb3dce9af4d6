//! Indexed surfaces the built-in generators and the NFF loader's spheres and cones are made of:
//! parametric grids, boxes, spheres and tubes. A `Surface` is tessellated once and then emitted
//! into a `Mesh` through a point map, so animations re-emit the same faces in the same order with
//! moved vertices.

use glam::Vec3;

use crate::geometry::Triangle;
use crate::scene::Mesh;

/// Vertices and triangles indexing them. Winding is counter-clockwise seen from the outside
/// (the side the surface's normal `(v1 − v0) × (v2 − v0)` points to).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Surface {
    pub vertices: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
}

impl Surface {
    pub fn triangle_count(&self) -> usize {
        self.faces.len()
    }

    /// A `cols × rows` grid of quads, two triangles each (`2·cols·rows` triangles) over the
    /// `(cols + 1)·(rows + 1)` points `point(i, j)`, `i ∈ 0..=cols`, `j ∈ 0..=rows`. The normal
    /// points along ∂point/∂i × ∂point/∂j. Closed surfaces pass wrapped indices (`i % cols`) so
    /// seam vertices are bit-identical and the mesh stays watertight.
    pub fn grid(cols: u32, rows: u32, point: impl Fn(u32, u32) -> Vec3) -> Surface {
        let mut vertices = Vec::with_capacity(((cols + 1) * (rows + 1)) as usize);
        for j in 0..=rows {
            for i in 0..=cols {
                vertices.push(point(i, j));
            }
        }
        let index = |i: u32, j: u32| j * (cols + 1) + i;
        let mut faces = Vec::with_capacity((2 * cols * rows) as usize);
        for j in 0..rows {
            for i in 0..cols {
                let (a, b) = (index(i, j), index(i + 1, j));
                let (c, d) = (index(i + 1, j + 1), index(i, j + 1));
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            }
        }
        Surface { vertices, faces }
    }

    /// The parallelogram `corner + s·edge_u + t·edge_v` cut into `n × n` cells (`2n²` triangles),
    /// facing `edge_u × edge_v`.
    pub fn quad(corner: Vec3, edge_u: Vec3, edge_v: Vec3, n: u32) -> Surface {
        // i / n rather than i · (1/n): exact at the far edge, so faces meet bit-exactly.
        let s = |i: u32| i as f32 / n as f32;
        Surface::grid(n, n, |i, j| corner + edge_u * s(i) + edge_v * s(j))
    }

    /// The six faces of the unit cube [0, 1]³, each cut into `n × n` cells: `12n²` triangles,
    /// facing outwards. Map it onto any box (or parallelepiped) with `emit`.
    pub fn cube(n: u32) -> Surface {
        let (x, y, z) = (Vec3::X, Vec3::Y, Vec3::Z);
        let faces = [
            (Vec3::ZERO, z, y), // x = 0, facing −x
            (x, y, z),          // x = 1, facing +x
            (Vec3::ZERO, x, z), // y = 0, facing −y
            (y, z, x),          // y = 1, facing +y
            (Vec3::ZERO, y, x), // z = 0, facing −z
            (z, x, y),          // z = 1, facing +z
        ];
        let mut cube = Surface::default();
        for (corner, u, v) in faces {
            cube.append(&Surface::quad(corner, u, v, n));
        }
        cube
    }

    /// The unit sphere as a UV sphere: `slices` meridians and `stacks` latitude bands, poles on ±z.
    /// The pole bands are triangle fans, so there are no degenerate triangles:
    /// `2·slices·(stacks − 1)` triangles over `slices·(stacks − 1) + 2` vertices.
    pub fn uv_sphere(slices: u32, stacks: u32) -> Surface {
        assert!(
            slices >= 3 && stacks >= 2,
            "a UV sphere needs at least 3 slices and 2 stacks"
        );
        let mut vertices = vec![Vec3::Z, -Vec3::Z];
        for j in 1..stacks {
            let theta = std::f32::consts::PI * j as f32 / stacks as f32;
            for i in 0..slices {
                let phi = std::f32::consts::TAU * i as f32 / slices as f32;
                vertices.push(Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ));
            }
        }
        let ring = |j: u32, i: u32| 2 + (j - 1) * slices + i % slices;
        let mut faces = Vec::with_capacity((2 * slices * (stacks - 1)) as usize);
        for i in 0..slices {
            faces.push([0, ring(1, i), ring(1, i + 1)]);
        }
        for j in 1..stacks - 1 {
            for i in 0..slices {
                let (a, b) = (ring(j, i), ring(j + 1, i));
                let (c, d) = (ring(j + 1, i + 1), ring(j, i + 1));
                faces.push([a, b, c]);
                faces.push([a, c, d]);
            }
        }
        for i in 0..slices {
            faces.push([1, ring(stacks - 1, i + 1), ring(stacks - 1, i)]);
        }
        Surface { vertices, faces }
    }

    /// An open tube of radius 1 around the z axis from z = 0 to z = 1 with `sides` facets:
    /// `2·sides` triangles, facing outwards. The ends are left open (the generators close them
    /// with spheres or hide them in other geometry).
    pub fn tube(sides: u32) -> Surface {
        Surface::grid(sides, 1, |i, j| {
            let phi = std::f32::consts::TAU * (i % sides) as f32 / sides as f32;
            Vec3::new(phi.cos(), phi.sin(), j as f32)
        })
    }

    /// Appends `other`'s vertices and faces (re-indexed).
    pub fn append(&mut self, other: &Surface) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.faces.extend(
            other
                .faces
                .iter()
                .map(|f| [f[0] + base, f[1] + base, f[2] + base]),
        );
    }

    /// Pushes every face into `mesh` with material `material`, each vertex moved by `map`.
    pub fn emit(&self, mesh: &mut Mesh, material: u32, map: impl Fn(Vec3) -> Vec3) {
        self.emit_vertices(mesh, material, &self.moved(map));
    }

    /// Every face as a triangle, each vertex moved by `map`.
    pub fn triangles(&self, map: impl Fn(Vec3) -> Vec3) -> Vec<Triangle> {
        let moved = self.moved(map);
        self.faces.iter().map(|f| face(f, &moved)).collect()
    }

    fn moved(&self, map: impl Fn(Vec3) -> Vec3) -> Vec<Vec3> {
        self.vertices.iter().map(|&p| map(p)).collect()
    }

    /// Pushes every face into `mesh`, reading vertex positions from `vertices` (same indexing as
    /// `self.vertices`): the path for deformations computed per vertex.
    pub fn emit_vertices(&self, mesh: &mut Mesh, material: u32, vertices: &[Vec3]) {
        debug_assert_eq!(vertices.len(), self.vertices.len());
        mesh.triangles.reserve(self.faces.len());
        mesh.material_ids.reserve(self.faces.len());
        for f in &self.faces {
            mesh.push(face(f, vertices), material);
        }
    }
}

fn face(f: &[u32; 3], vertices: &[Vec3]) -> Triangle {
    Triangle::new(
        vertices[f[0] as usize],
        vertices[f[1] as usize],
        vertices[f[2] as usize],
    )
}

/// The map taking the unit cube [0, 1]³ onto the axis-aligned box `[min, max]`.
pub fn onto_box(min: Vec3, max: Vec3) -> impl Fn(Vec3) -> Vec3 {
    move |p| min + p * (max - min)
}

/// The map taking the unit tube (radius 1, z ∈ {0, 1}) onto a cylinder of `radius` from `a` to `b`.
pub fn onto_cylinder(a: Vec3, b: Vec3, radius: f32) -> impl Fn(Vec3) -> Vec3 {
    onto_cone(a, radius, b, radius)
}

/// The map taking the unit tube (radius 1, z ∈ {0, 1}) onto the side of a cone frustum: its z = 0
/// ring onto the circle of `base_radius` about `base`, its z = 1 ring onto `apex_radius` about
/// `apex`, both square to the axis.
pub fn onto_cone(
    base: Vec3,
    base_radius: f32,
    apex: Vec3,
    apex_radius: f32,
) -> impl Fn(Vec3) -> Vec3 {
    // (u, v, axis) right-handed keeps the outward winding.
    let w = (apex - base).normalize();
    let u = w.any_orthonormal_vector();
    let v = w.cross(u);
    move |p| {
        let (centre, radius) = if p.z == 0.0 {
            (base, base_radius)
        } else {
            (apex, apex_radius)
        };
        centre + radius * (p.x * u + p.y * v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn area_weighted_normal_sum(s: &Surface) -> Vec3 {
        s.faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| s.vertices[i as usize]);
                (b - a).cross(c - a)
            })
            .sum()
    }

    #[test]
    fn counts_follow_the_documented_formulas() {
        assert_eq!(
            Surface::grid(3, 2, |i, j| Vec3::new(i as f32, j as f32, 0.0)).triangle_count(),
            12
        );
        assert_eq!(
            Surface::quad(Vec3::ZERO, Vec3::X, Vec3::Y, 4).triangle_count(),
            32
        );
        assert_eq!(Surface::cube(3).triangle_count(), 108);
        let sphere = Surface::uv_sphere(8, 6);
        assert_eq!(sphere.triangle_count(), 80);
        assert_eq!(sphere.vertices.len(), 8 * 5 + 2);
        assert_eq!(Surface::tube(8).triangle_count(), 16);
    }

    #[test]
    fn closed_surfaces_face_outwards_and_close_up() {
        // A closed surface's area-weighted normals cancel; outward facing means the signed
        // volume (divergence theorem: Σ centroid · n / 3) is positive and equals the solid's.
        for (surface, volume) in [
            (Surface::cube(2), 1.0),
            (Surface::uv_sphere(64, 32), 4.18879),
        ] {
            assert!(area_weighted_normal_sum(&surface).length() < 1e-4);
            let signed: f32 = surface
                .faces
                .iter()
                .map(|f| {
                    let [a, b, c] = f.map(|i| surface.vertices[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!(
                (signed - volume).abs() < 0.02 * volume,
                "volume {signed} vs {volume}"
            );
        }
    }

    #[test]
    fn sphere_vertices_lie_on_the_unit_sphere_and_cylinder_map_hits_its_ends() {
        assert!(Surface::uv_sphere(12, 7)
            .vertices
            .iter()
            .all(|v| (v.length() - 1.0).abs() < 1e-6));
        let (a, b) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, 7.0));
        let map = onto_cylinder(a, b, 0.5);
        for p in Surface::tube(6).vertices {
            let q = map(p);
            let along = (q - a).dot(Vec3::Z);
            assert!((along - 4.0 * p.z).abs() < 1e-5);
            assert!(((q - a - Vec3::Z * along).length() - 0.5).abs() < 1e-5);
        }
        // Outward winding survives the map: the tube's face normals point away from the axis.
        let mut mesh = Mesh::default();
        Surface::tube(6).emit(&mut mesh, 0, map);
        for t in &mesh.triangles {
            let c = t.centroid();
            let radial = c - Vec3::new(1.0, 2.0, c.z);
            assert!(t.normal().dot(radial) > 0.0);
        }
    }
}
