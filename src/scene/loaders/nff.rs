//! Eric Haines' Neutral File Format, the language of the Standard Procedural Databases (Haines,
//! "A Proposal for Standard Graphics Environments", IEEE CG&A 1987; NFF.DOC of the SPD):
//!
//! - `v` viewpoint: `from`, `at`, `up`, `angle` (full vertical field of view, degrees), `hither`,
//!   `resolution` → `Camera` (hither and resolution are the renderer's business and are dropped);
//! - `b` background colour (dropped: the scene model has none); `l` point light with optional
//!   colour (white when absent);
//! - `f` fill: `colour Kd Ks shine T ior` → diffuse = colour·Kd, mirror = Ks, dielectric
//!   `(ior, T)` when T > 0 (shine is a highlight exponent, not a reflection lobe; see
//!   `dielectric` for indices ≤ 0);
//! - `p` polygon and `pp` polygonal patch (its normals are dropped), ear-clipped;
//! - `s` sphere and `c` cone or cylinder, tessellated (`quadrics.rs`).
//!
//! These commands are also the core of BART's AFF (`aff.rs`), which reads both formats.

use std::path::Path;

use glam::Vec3;

use super::{aff, quadrics, tokens::Tokens, LoadOptions};
use crate::error::Result;
use crate::geometry::Triangle;
use crate::scene::{Camera, Light, Material, Scene};

pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    aff::load_dialect(path, options, aff::Dialect::Nff)
}

/// The `v` block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    pub from: Vec3,
    pub at: Vec3,
    pub up: Vec3,
    /// Vertical field of view in degrees (BART: "the FOV in the y-direction").
    pub angle: f32,
}

impl View {
    pub fn camera(&self) -> Camera {
        Camera {
            position: self.from,
            target: self.at,
            up: self.up,
            fov_y_deg: self.angle,
            aperture: 0.0,
            focus_distance: (self.at - self.from).length(),
        }
    }
}

/// After `v`: the six viewing lines, in the order NFF prescribes.
pub fn view(t: &mut Tokens) -> Result<View> {
    t.keyword("from")?;
    let from = t.vec3("eye position")?;
    t.keyword("at")?;
    let at = t.vec3("look-at point")?;
    t.keyword("up")?;
    let up = t.vec3("up vector")?;
    t.keyword("angle")?;
    let angle = t.number("field of view")?;
    t.keyword("hither")?;
    t.number("hither distance")?;
    t.keyword("resolution")?;
    t.integer("horizontal resolution")?;
    t.integer("vertical resolution")?;
    if from == at {
        return Err(t.error("the eye position and the look-at point coincide"));
    }
    if up == Vec3::ZERO {
        return Err(t.error("the up vector is zero"));
    }
    if !(angle > 0.0 && angle < 180.0) {
        return Err(t.error(format!("field of view {angle}° is not in (0°, 180°)")));
    }
    Ok(View {
        from,
        at,
        up,
        angle,
    })
}

/// After `l`: a position and an optional colour.
pub fn light(t: &mut Tokens) -> Result<Light> {
    let position = t.vec3("light position")?;
    let intensity = if t.next_is_number() {
        t.vec3("light colour")?
    } else {
        Vec3::ONE
    };
    Ok(Light::Point {
        position,
        intensity,
    })
}

/// After `b`: a colour, checked and dropped.
pub fn background(t: &mut Tokens) -> Result<()> {
    t.vec3("background colour")?;
    Ok(())
}

/// After `f`: `r g b Kd Ks shine T ior`.
pub fn fill(t: &mut Tokens, name: String) -> Result<Material> {
    let colour = t.vec3("fill colour")?;
    let kd = t.number("diffuse coefficient Kd")?;
    let ks = t.number("specular coefficient Ks")?;
    t.number("shine exponent")?;
    let transmittance = t.number("transmittance T")?;
    let ior = t.number("index of refraction")?;
    Ok(Material {
        name,
        diffuse: colour * kd,
        mirror: ks,
        glossy: None,
        dielectric: dielectric(transmittance, ior),
        emission: Vec3::ZERO,
    })
}

/// The dielectric part of a material with transmittance `t` and index of refraction `ior`:
/// none when `t` is 0. An index of refraction ≤ 0 cannot bend light; BART robots' headlights
/// (`u_body.aff`) say `T 0.04, ior 0`, so such an index is read as 1: light passes unbent.
pub fn dielectric(t: f32, ior: f32) -> Option<(f32, f32)> {
    (t > 0.0).then_some((if ior > 0.0 { ior } else { 1.0 }, t))
}

/// After `p` (or `pp` with `with_normals`): the vertex count and the vertices.
pub fn polygon(t: &mut Tokens, with_normals: bool) -> Result<Vec<Vec3>> {
    let words_each = if with_normals { 6 } else { 3 };
    let n = t.count("vertex count", words_each)?;
    if n < 3 {
        return Err(t.error(format!("a polygon needs at least 3 vertices, not {n}")));
    }
    let mut vertices = Vec::with_capacity(n);
    for _ in 0..n {
        vertices.push(t.vec3("polygon vertex")?);
        if with_normals {
            t.vec3("vertex normal")?;
        }
    }
    Ok(vertices)
}

/// After `s`: centre and radius.
pub fn sphere(t: &mut Tokens, options: &LoadOptions) -> Result<Vec<Triangle>> {
    let centre = t.vec3("sphere centre")?;
    let radius = t.number("sphere radius")?;
    if radius == 0.0 {
        return Err(t.error("sphere radius is zero"));
    }
    Ok(quadrics::sphere(centre, radius, options.sphere_segments))
}

/// After `c`: base point and radius, apex point and radius.
pub fn cone(t: &mut Tokens, options: &LoadOptions) -> Result<Vec<Triangle>> {
    let base = t.vec3("cone base")?;
    let base_radius = t.number("cone base radius")?;
    let apex = t.vec3("cone apex")?;
    let apex_radius = t.number("cone apex radius")?;
    quadrics::cone(base, base_radius, apex, apex_radius, options.cone_segments)
        .ok_or_else(|| t.error("cone base and apex coincide"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loaders::{load, temp_file};

    const SCENE: &str = "\
b 0.1 0.2 0.3
v
from 0 -5 1
at 0 0 1
up 0 0 1
angle 40
hither 0.1
resolution 64 48
l 1 2 3
l -1 -2 3 0.5 0.25 1
f 1 0.5 0.25 0.8 0.2 30 0 1
# concave L-shaped hexagon in the plane z = 0
p 6
0 0 0
2 0 0
2 1 0
1 1 0
1 2 0
0 2 0
f 0.9 0.9 0.9 0.1 0.5 100 0.7 1.5
pp 3
0 0 1  0 0 1
1 0 1  0 0 1
0 1 1  0 0 1
s 0 0 5 0.5
c 0 0 0 0.1  0 0 2 0.1
";

    #[test]
    fn nff_scene_has_its_geometry_materials_lights_and_view() {
        let scene = load(&temp_file("small.nff", SCENE.as_bytes())).unwrap();
        let o = LoadOptions::default();
        let sphere = (2 * o.sphere_segments * (o.sphere_segments / 2 - 1)) as usize;
        let cylinder = 2 * o.cone_segments as usize;
        assert_eq!(scene.triangle_count(), 4 + 1 + sphere + cylinder);
        assert_eq!(scene.name, "small");
        // The L: 4 triangles inside it, covering its area 3, in the polygon's winding (+z).
        let area: f32 = scene.mesh.triangles[..4].iter().map(|t| t.area()).sum();
        assert!((area - 3.0).abs() < 1e-6);
        assert!(scene.mesh.triangles[..4].iter().all(|t| t.normal().z > 0.0));
        for t in &scene.mesh.triangles[..4] {
            let c = t.centroid();
            assert!(!(c.x > 1.0 && c.y > 1.0), "triangle {t:?} in the notch");
        }
        assert_eq!(
            scene.mesh.triangles[4],
            Triangle::new(Vec3::Z, Vec3::new(1.0, 0.0, 1.0), Vec3::new(0.0, 1.0, 1.0))
        );
        assert_eq!(scene.mesh.material_ids[..5], [0, 0, 0, 0, 1]);
        let m = &scene.materials;
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].diffuse, Vec3::new(0.8, 0.4, 0.2));
        assert_eq!(m[0].mirror, 0.2);
        assert_eq!(m[0].dielectric, None);
        assert_eq!(m[0].name, "small.nff:11");
        assert_eq!(m[1].mirror, 0.5);
        assert_eq!(m[1].dielectric, Some((1.5, 0.7)));
        assert_eq!(
            scene.lights,
            [
                Light::Point {
                    position: Vec3::new(1.0, 2.0, 3.0),
                    intensity: Vec3::ONE
                },
                Light::Point {
                    position: Vec3::new(-1.0, -2.0, 3.0),
                    intensity: Vec3::new(0.5, 0.25, 1.0)
                },
            ]
        );
        assert_eq!(scene.camera.position, Vec3::new(0.0, -5.0, 1.0));
        assert_eq!(scene.camera.target, Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(scene.camera.up, Vec3::Z);
        assert_eq!(scene.camera.fov_y_deg, 40.0);
        assert!(scene.animation.is_none() && scene.camera_path.is_none());
        // Sphere vertices lie on the sphere; cylinder vertices on the cylinder.
        let sphere_tris = &scene.mesh.triangles[5..5 + sphere];
        assert!(sphere_tris
            .iter()
            .flat_map(|t| t.v)
            .all(|p| ((p - Vec3::new(0.0, 0.0, 5.0)).length() - 0.5).abs() < 1e-5));
        assert!(scene.mesh.triangles[5 + sphere..]
            .iter()
            .flat_map(|t| t.v)
            .all(|p| (p.truncate().length() - 0.1).abs() < 1e-5 && (p.z == 0.0 || p.z == 2.0)));
    }

    #[test]
    fn malformed_nff_names_file_and_line() {
        let cases = [
            ("p 2\n0 0 0\n1 0 0\n", 1, "at least 3"),
            ("p 3\n0 0 0\n1 inf 0\n0 1 0\n", 3, "not finite"),
            (
                "p 3\n0 0 0\n1 0 0\n0 1\n",
                1,
                "more than the rest of the file holds",
            ),
            ("f 1 1 1 0.5 0.5\n", 1, "end of file"),
            ("s 0 0 0 zero\n", 1, "sphere radius"),
            ("c 0 0 0 1\n0 0 0 1\n", 2, "coincide"),
            (
                "v\nfrom 0 0 0\nat 0 0 1\nup 0 1 0\nangle 45\nresolution 8 8\n",
                6,
                "'hither'",
            ),
            (
                "p 3\n0 0 0\n1 0 0\n0 1 0\nm\n",
                5,
                "unknown NFF command 'm'",
            ),
            (
                "v\nfrom 1 1 1\nat 1 1 1\nup 0 1 0\nangle 45\nhither 1\nresolution 8 8\n",
                7,
                "coincide",
            ),
            ("l 0 0 0\n", 1, "no triangles"),
        ];
        for (text, line, what) in cases {
            let err = load(&temp_file("bad.nff", text.as_bytes()))
                .unwrap_err()
                .to_string();
            let at = if what == "no triangles" {
                "bad.nff: ".to_string()
            } else {
                format!("bad.nff:{line}: ")
            };
            assert!(err.contains(&at) && err.contains(what), "{err}");
        }
    }
}
