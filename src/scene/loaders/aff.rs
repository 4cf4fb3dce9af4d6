//! BART's Animation File Format (Lext, Assarsson and Möller, "A Benchmark for Animated Ray
//! Tracing", IEEE CG&A 21(2), 2001): NFF (`nff.rs`) plus
//!
//! - `fm` materials: ambient, diffuse and specular RGB, shine, T, ior → diffuse, a mirror of
//!   the specular colour's mean, and a dielectric `(ior, T)` when T > 0 (ambient and the global
//!   ambient light `am` have no place in the material model and are dropped);
//! - `m` meshes: `vertices n … [normals n …] [texturecoords n file …] triangles n` with, per
//!   triangle, three vertex indices, then three normal and three texture indices when those
//!   sections exist (normals and texture coordinates are checked and dropped);
//! - `tt`/`ttp` textured triangles (with normals), `tpa` vertex-keyed triangles;
//! - `i level file` includes, resolved next to the including file and skipped when `level`
//!   exceeds the detail level set by `d` (0 by default);
//! - `xs` fixed and `x name` keyframed transform blocks `{ … }`, and `k name { … }` keyframes
//!   (`keyframes.rs`, `scene_graph.rs`); a block must close in the file that opens it;
//! - `a start end frames`: the animation's time range and frame count. Scene time 0 is BART
//!   time `start`; frame i of `frames` is at `i · (end − start)/(frames − 1)`, and the camera
//!   path has a key at every frame, so interpolating it is exact at frames.
//!
//! Textures are not part of the data: texture names are read and ignored, and textured surfaces
//! keep their material colour. Refused with a clear error, because no BART scene uses them and
//! the scene model cannot express them: animated lights (`la`) and visibility keys.
//!
//! As in BART's reader, lights and the view are in world coordinates; everything else follows the
//! transform blocks around it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::Vec3;

use super::keyframes::{self, TransformTrack};
use super::nff::{self, View};
use super::scene_graph::{Clock, Morph, SceneGraph};
use super::tokens::Tokens;
use super::{default_camera, require_traceable, scene_name, triangulate, Files, LoadOptions};
use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::scene::{CameraKey, CameraPath, Light, Material, Scene};

/// Which command set a file may use.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dialect {
    Nff,
    Aff,
}

/// BART's animations have at most a few thousand frames; a camera key for each of a count a
/// typo made huge would take gigabytes.
const MAX_FRAMES: i64 = 100_000;

/// Includes nested deeper than this are taken for a cycle the path check missed.
const MAX_INCLUDE_DEPTH: usize = 64;

pub fn load(path: &Path, options: &LoadOptions) -> Result<Scene> {
    load_dialect(path, options, Dialect::Aff)
}

pub fn load_dialect(path: &Path, options: &LoadOptions, dialect: Dialect) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes, options, dialect, &|file| std::fs::read(file))
}

/// The file `bytes` (named `path` in errors); included files are read through `files`.
pub fn parse(
    path: &Path,
    bytes: &[u8],
    options: &LoadOptions,
    dialect: Dialect,
    files: Files,
) -> Result<Scene> {
    let mut reader = Reader {
        options,
        dialect,
        files,
        materials: Vec::new(),
        current_material: None,
        lights: Vec::new(),
        view: None,
        graph: SceneGraph::default(),
        tracks: HashMap::new(),
        animation: None,
        detail_level: 0,
    };
    reader.read_file(path, bytes, &mut Vec::new())?;
    reader.into_scene(path)
}

/// `a start end frames`.
#[derive(Clone, Copy, Debug)]
struct AnimationRange {
    start: f32,
    end: f32,
    frames: usize,
}

struct Reader<'a> {
    options: &'a LoadOptions,
    dialect: Dialect,
    files: Files<'a>,
    materials: Vec<Material>,
    current_material: Option<u32>,
    lights: Vec<Light>,
    view: Option<View>,
    graph: SceneGraph,
    tracks: HashMap<String, TransformTrack>,
    animation: Option<AnimationRange>,
    detail_level: i64,
}

impl Reader<'_> {
    /// Reads one file; `chain` holds the files that include it, to catch cycles.
    fn read_file(&mut self, path: &Path, bytes: &[u8], chain: &mut Vec<PathBuf>) -> Result<()> {
        // Comments may hold Latin-1 text; commands are ASCII.
        let text = String::from_utf8_lossy(bytes);
        let mut t = Tokens::new(path, &text);
        chain.push(path.canonicalize().unwrap_or_else(|_| path.to_path_buf()));
        // Lines of the blocks opened in this file and not yet closed.
        let mut open_blocks: Vec<usize> = Vec::new();
        while let Some(command) = t.next_word() {
            self.command(command, &mut t, &mut open_blocks, chain)?;
        }
        if let Some(&line) = open_blocks.last() {
            return Err(Error::at_line(
                path,
                line,
                "this block is not closed ('}') before the end of its file",
            ));
        }
        chain.pop();
        Ok(())
    }

    fn command(
        &mut self,
        command: &str,
        t: &mut Tokens,
        open_blocks: &mut Vec<usize>,
        chain: &mut Vec<PathBuf>,
    ) -> Result<()> {
        match command {
            "v" => self.view = Some(nff::view(t)?),
            "b" => nff::background(t)?,
            "l" => self.lights.push(nff::light(t)?),
            "f" => {
                let name = self.material_name(t);
                let material = nff::fill(t, name)?;
                self.set_material(material);
            }
            "p" | "pp" => {
                let polygon = nff::polygon(t, command == "pp")?;
                let material = self.geometry_material();
                for [a, b, c] in triangulate(&polygon) {
                    let tri = Triangle::new(polygon[a], polygon[b], polygon[c]);
                    self.graph.add_triangle(tri, material);
                }
            }
            "s" => {
                let tris = nff::sphere(t, self.options)?;
                self.add_triangles(tris);
            }
            "c" => {
                let tris = nff::cone(t, self.options)?;
                self.add_triangles(tris);
            }
            // SPD's teapot.nff has a `Q 0` line that is in no NFF description; it carries no
            // geometry, so it is read and dropped.
            "Q" if self.dialect == Dialect::Nff => {
                t.integer("Q value")?;
            }
            _ if self.dialect == Dialect::Nff => {
                return Err(t.error(format!("unknown NFF command '{command}'")));
            }
            "fm" => {
                let name = self.material_name(t);
                let material = extended_material(t, name)?;
                self.set_material(material);
            }
            "am" => {
                t.vec3("ambient light colour")?;
            }
            "m" => self.mesh(t)?,
            "tt" | "ttp" => {
                t.word("texture name")?;
                let mut v = [Vec3::ZERO; 3];
                for p in &mut v {
                    *p = t.vec3("triangle vertex")?;
                    if command == "ttp" {
                        t.vec3("vertex normal")?;
                    }
                    t.number("texture u")?;
                    t.number("texture v")?;
                }
                let material = self.geometry_material();
                self.graph.add_triangle(Triangle { v }, material);
            }
            "tpa" => {
                let morph = animated_triangle(t)?;
                let material = self.geometry_material();
                self.graph.add_morph(morph, material);
            }
            "i" => self.include(t, chain)?,
            "d" => self.detail_level = t.integer("detail level")?,
            "xs" => {
                let scale = t.vec3("scale")?;
                let axis = t.vec3("rotation axis")?;
                let degrees = t.number("rotation angle")?;
                let axis = keyframes::unit_axis(t, axis, degrees)?;
                let translation = t.vec3("translation")?;
                t.keyword("{")?;
                let m = keyframes::static_transform(scale, axis, degrees, translation);
                self.graph.open_fixed(m);
                open_blocks.push(t.line());
            }
            "x" => {
                let name = t.word("transform name")?;
                t.keyword("{")?;
                self.graph.open_keyframed(name);
                open_blocks.push(t.line());
            }
            "}" => {
                if open_blocks.pop().is_none() {
                    return Err(t.error("'}' without a block opened in this file"));
                }
                self.graph.close();
            }
            "a" => {
                let start = t.number("start time")?;
                let end = t.number("end time")?;
                let frames = t.integer("frame count")?;
                if frames < 1 || end < start || (frames > 1 && end == start) {
                    return Err(t.error(format!(
                        "animation range {start}..{end} with {frames} frames: frames must be at \
                         least 1 and the range must be non-empty when there are several"
                    )));
                }
                if frames > MAX_FRAMES {
                    return Err(t.error(format!(
                        "{frames} frames are more than {MAX_FRAMES} (the camera path has a key \
                         at every frame)"
                    )));
                }
                self.animation = Some(AnimationRange {
                    start,
                    end,
                    frames: frames as usize,
                });
            }
            "k" => {
                // A later block with the same name replaces the earlier one, as in BART, which
                // looks names up newest first.
                let (name, track) = keyframes::parse(t)?;
                self.tracks.insert(name, track);
            }
            "la" => {
                return Err(t.error(
                    "animated lights (la) are not supported: the scene model's lights are static",
                ))
            }
            _ => return Err(t.error(format!("unknown AFF command '{command}'"))),
        }
        Ok(())
    }

    fn material_name(&self, t: &Tokens) -> String {
        let file = t.path().file_name().unwrap_or_default().to_string_lossy();
        format!("{file}:{}", t.line())
    }

    /// Makes `material` current, reusing an identical earlier one (kitchen repeats a few
    /// materials in hundreds of `fm` lines).
    fn set_material(&mut self, material: Material) {
        let same = |m: &Material| Material {
            name: String::new(),
            ..m.clone()
        };
        let key = same(&material);
        let index = match self.materials.iter().position(|m| same(m) == key) {
            Some(i) => i,
            None => {
                self.materials.push(material);
                self.materials.len() - 1
            }
        };
        self.current_material = Some(index as u32);
    }

    /// The material for geometry: the current one, or the default before any `f`/`fm`.
    fn geometry_material(&mut self) -> u32 {
        if self.current_material.is_none() {
            self.set_material(Material::default());
        }
        self.current_material.unwrap_or(0)
    }

    fn add_triangles(&mut self, tris: Vec<Triangle>) {
        let material = self.geometry_material();
        for tri in tris {
            self.graph.add_triangle(tri, material);
        }
    }

    /// After `m`.
    fn mesh(&mut self, t: &mut Tokens) -> Result<()> {
        t.keyword("vertices")?;
        let n = t.count("vertex count", 3)?;
        let vertices = (0..n)
            .map(|_| t.vec3("mesh vertex"))
            .collect::<Result<Vec<Vec3>>>()?;
        let mut section = t.word("'normals', 'texturecoords' or 'triangles'")?;
        let mut normals = None;
        if section == "normals" {
            let n = t.count("normal count", 3)?;
            for _ in 0..n {
                t.vec3("mesh normal")?;
            }
            normals = Some(n);
            section = t.word("'texturecoords' or 'triangles'")?;
        }
        let mut texcoords = None;
        if section == "texturecoords" {
            let n = t.count("texture coordinate count", 2)?;
            t.word("texture file name")?;
            for _ in 0..2 * n {
                t.number("texture coordinate")?;
            }
            texcoords = Some(n);
            section = t.word("'triangles'")?;
        }
        if section != "triangles" {
            return Err(t.error(format!("expected 'triangles' in mesh, found '{section}'")));
        }
        let words_each =
            3 * (1 + usize::from(normals.is_some()) + usize::from(texcoords.is_some()));
        let count = t.count("triangle count", words_each)?;
        let material = self.geometry_material();
        for _ in 0..count {
            let mut v = [Vec3::ZERO; 3];
            for p in &mut v {
                *p = vertices[t.index("vertex index", n)?];
            }
            for (len, what) in [
                (normals, "normal index"),
                (texcoords, "texture coordinate index"),
            ] {
                if let Some(len) = len {
                    for _ in 0..3 {
                        t.index(what, len)?;
                    }
                }
            }
            self.graph.add_triangle(Triangle { v }, material);
        }
        Ok(())
    }

    /// After `i`.
    fn include(&mut self, t: &mut Tokens, chain: &mut Vec<PathBuf>) -> Result<()> {
        let level = t.integer("detail level")?;
        let name = t.word("file name")?;
        if level > self.detail_level {
            return Ok(());
        }
        let file = t.path().parent().unwrap_or(Path::new("")).join(name);
        let canonical = file.canonicalize().unwrap_or_else(|_| file.clone());
        if chain.contains(&canonical) || chain.len() >= MAX_INCLUDE_DEPTH {
            return Err(t.error(format!("include cycle through {}", file.display())));
        }
        let bytes = (self.files)(&file).map_err(|e| {
            t.error(format!(
                "included file {} cannot be read: {e}",
                file.display()
            ))
        })?;
        self.read_file(&file, &bytes, chain)
    }

    fn into_scene(self, path: &Path) -> Result<Scene> {
        if self.animation.is_none() && !self.tracks.is_empty() {
            eprintln!(
                "warning: {}: keyframes without an animation range ('a'): loading the still at time 0",
                path.display()
            );
        }
        let clock = self.animation.map(|a| Clock {
            start: a.start.into(),
            end: a.end.into(),
        });
        let (mesh, animation) = self.graph.finish(&self.tracks, clock);
        require_traceable(path, &mesh)?;
        let view = self.view.unwrap_or_else(|| {
            let c = default_camera(&mesh.bounds());
            View {
                from: c.position,
                at: c.target,
                up: c.up,
                angle: c.fov_y_deg,
            }
        });
        let (camera, camera_path) = match (self.tracks.get("camera"), self.animation) {
            (Some(track), Some(range)) => {
                let step = if range.frames > 1 {
                    (f64::from(range.end) - f64::from(range.start)) / (range.frames - 1) as f64
                } else {
                    0.0
                };
                let keys: Vec<CameraKey> = (0..range.frames)
                    .map(|i| {
                        let time = i as f64 * step;
                        CameraKey {
                            time: time as f32,
                            camera: track.camera(f64::from(range.start) + time, &view),
                        }
                    })
                    .collect();
                (keys[0].camera, Some(CameraPath { keys }))
            }
            (Some(track), None) => (track.camera(0.0, &view), None),
            (None, _) => (view.camera(), None),
        };
        Ok(Scene {
            name: scene_name(path),
            source: path.display().to_string(),
            mesh,
            materials: self.materials,
            lights: self.lights,
            camera,
            camera_path,
            animation,
        })
    }
}

/// After `fm`: ambient, diffuse, specular RGB, then shine, T, ior.
fn extended_material(t: &mut Tokens, name: String) -> Result<Material> {
    t.vec3("ambient colour")?;
    let diffuse = t.vec3("diffuse colour")?;
    let specular = t.vec3("specular colour")?;
    t.number("shine exponent")?;
    let transmittance = t.number("transmittance T")?;
    let ior = t.number("index of refraction")?;
    Ok(Material {
        name,
        diffuse,
        mirror: (specular.x + specular.y + specular.z) / 3.0,
        glossy: None,
        dielectric: nff::dielectric(transmittance, ior),
        emission: Vec3::ZERO,
    })
}

/// After `tpa`: the key count, then per key its time and three (vertex, normal) pairs.
fn animated_triangle(t: &mut Tokens) -> Result<Morph> {
    let n = t.count("key count", 1 + 3 * 6)?;
    if n == 0 {
        return Err(t.error("an animated triangle needs at least one key"));
    }
    let mut times = Vec::with_capacity(n);
    let mut positions = Vec::with_capacity(n);
    for _ in 0..n {
        let time = t.number("key time")?;
        if times.last().is_some_and(|&last| time < last) {
            return Err(t.error(format!("key time {time} is earlier than the key before it")));
        }
        times.push(time);
        let mut v = [Vec3::ZERO; 3];
        for p in &mut v {
            *p = t.vec3("triangle vertex")?;
            t.vec3("vertex normal")?;
        }
        positions.push(v);
    }
    Ok(Morph { times, positions })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loaders::{load, temp_file};

    /// Writes `files` (relative name, contents) next to a fresh `main.aff` and returns its path.
    fn write_scene(main: &str, files: &[(&str, &str)]) -> PathBuf {
        let path = temp_file("main.aff", main.as_bytes());
        let dir = path.parent().unwrap();
        for (name, contents) in files {
            let file = dir.join(name);
            std::fs::create_dir_all(file.parent().unwrap()).unwrap();
            std::fs::write(file, contents).unwrap();
        }
        path
    }

    const MAIN: &str = "\
% a small animated AFF scene
v
from 0 0 10
at 0 0 0
up 0 1 0
angle 50
hither 0.01
resolution 80 60
am 0.3 0.3 0.3
l 0 5 0 0.2 0.2 0.2
a 0 2 3
fm 0.1 0.1 0.1  0.5 0.6 0.7  0.3 0.3 0.6  40 0 1
i 0 parts/static.aff
i 1 parts/too_detailed.aff
x mover
{
  tt wood.ppm
    0 0 0  0 0
    1 0 0  1 0
    0 1 0  0 1
}
xs 2 2 2  0 0 1 90  10 0 0
{
  x mover
  {
    p 3
    1 0 0
    1 1 0
    0 1 0
  }
}
fm 0.1 0.1 0.1  0.5 0.6 0.7  0.3 0.3 0.6  40 0 1
tpa 2
  0
  0 0 0  0 0 1
  1 0 0  0 0 1
  0 1 0  0 0 1
  2
  0 0 4  0 0 1
  1 0 4  0 0 1
  0 1 4  0 0 1
k mover
{
  transl 5
  -1  0 0 0  0 0 0
   0  0 0 0  0 0 0
   1  2 0 0  0 0 0
   2  2 4 0  0 0 0
   3  2 4 0  0 0 0
}
k camera
{
  transl 4
  -1  0 0 10  0 0 0
   0  0 0 10  0 0 0
   2  0 0 10  0 0 0
   3  0 0 10  0 0 0
  rot 4
  -1  0 1 0 90  0 0 0
   0  0 1 0 90  0 0 0
   2  0 1 0 90  0 0 0
   3  0 1 0 90  0 0 0
}
";

    const STATIC: &str = "\
fm 0 0 0  0.9 0.1 0.1  0 0 0  1 0.5 1.33
m
 vertices 4
  0 0 0
  1 0 0
  1 1 0
  0 1 0
 normals 4
  0 0 1
  0 0 1
  0 0 1
  0 0 1
 texturecoords 4 floor.ppm
  0 0
  1 0
  1 1
  0 1
 triangles 2
  0 1 2  0 1 2  0 1 2
  0 2 3  0 2 3  0 2 3
i 0 inner.aff
";

    const INNER: &str = "xs 1 1 1  1 0 0 0  0 0 -3\n{\n p 4\n 0 0 0\n 1 0 0\n 1 1 0\n 0 1 0\n}\n";

    fn load_small() -> Scene {
        let path = write_scene(
            MAIN,
            &[
                ("parts/static.aff", STATIC),
                ("parts/inner.aff", INNER),
                (
                    "parts/too_detailed.aff",
                    "this file is skipped at detail level 0",
                ),
            ],
        );
        load(&path).unwrap()
    }

    #[test]
    fn geometry_materials_lights_and_includes() {
        let scene = load_small();
        // mesh 2 + inner quad 2 + tt 1 + polygon 1 + tpa 1.
        assert_eq!(scene.triangle_count(), 7);
        let t = &scene.mesh.triangles;
        assert_eq!(
            t[1],
            Triangle::new(Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0), Vec3::Y)
        );
        // The include of the include is found next to its includer, under its static block.
        assert!(t[2..4].iter().flat_map(|t| t.v).all(|p| p.z == -3.0));
        assert_eq!(t[2].area() + t[3].area(), 1.0);
        let m = &scene.materials;
        // The second `fm` repeats the first: one material.
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].diffuse, Vec3::new(0.5, 0.6, 0.7));
        assert!((m[0].mirror - 0.4).abs() < 1e-6);
        assert_eq!(m[0].dielectric, None);
        assert_eq!(m[1].diffuse, Vec3::new(0.9, 0.1, 0.1));
        assert_eq!(m[1].dielectric, Some((1.33, 0.5)));
        // The current material is global state (as in BART): the included file's `fm` stays
        // current after the include, until the second `fm` in main.aff.
        assert_eq!(scene.mesh.material_ids, [1, 1, 1, 1, 1, 1, 0]);
        assert_eq!(
            scene.lights,
            [Light::Point {
                position: Vec3::new(0.0, 5.0, 0.0),
                intensity: Vec3::splat(0.2)
            }]
        );
    }

    #[test]
    fn keyframed_transform_hits_keys_and_follows_the_spline_between() {
        let scene = load_small();
        let animation = scene.animation.as_ref().unwrap();
        assert_eq!(animation.duration(), 2.0);
        assert_eq!(scene.duration(), 2.0);
        // The `tt` triangle's vertex at the origin rides on the translation spline: at keys the
        // key values; between them Catmull–Rom (evenly spaced keys, T = C = B = 0):
        // P(½) = (−P0 + 9P1 + 9P2 − P3)/16.
        let origin_at = |t: f32| animation.mesh_at(t).triangles[4].v[0];
        let close = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
        assert!(close(origin_at(0.0), Vec3::ZERO));
        assert!(close(origin_at(1.0), Vec3::new(2.0, 0.0, 0.0)));
        assert!(close(origin_at(2.0), Vec3::new(2.0, 4.0, 0.0)));
        assert!(close(origin_at(0.5), Vec3::new(1.0, -0.25, 0.0)));
        assert!(close(origin_at(1.5), Vec3::new(2.125, 2.0, 0.0)));
        // Clamped outside the keyed range.
        assert!(close(origin_at(5.0), Vec3::new(2.0, 4.0, 0.0)));
        // Nested under `xs`: parent · child. At t = 1 the local point (1, 0, 0) moves to
        // (3, 0, 0), is scaled to (6, 0, 0), turned 90° about z to (0, 6, 0), shifted by x 10.
        assert!(close(
            animation.mesh_at(1.0).triangles[5].v[0],
            Vec3::new(10.0, 6.0, 0.0)
        ));
        // `tpa` moves linearly between its keys.
        assert!(close(
            animation.mesh_at(1.0).triangles[6].v[1],
            Vec3::new(1.0, 0.0, 2.0)
        ));
        // Static triangles stay put; the count and materials never change.
        let later = animation.mesh_at(1.5);
        assert_eq!(later.triangles[..4], scene.mesh.triangles[..4]);
        assert_eq!(later.material_ids, scene.mesh.material_ids);
        assert_eq!(animation.mesh_at(0.0), scene.mesh);
    }

    #[test]
    fn keyframed_camera_becomes_a_path_sampled_at_every_frame() {
        let scene = load_small();
        let path = scene.camera_path.as_ref().unwrap();
        let times: Vec<f32> = path.keys.iter().map(|k| k.time).collect();
        assert_eq!(times, [0.0, 1.0, 2.0]);
        // BART's viewer looks down its local −z with +y up; turned 90° about y it looks down −x.
        let c = path.keys[1].camera;
        assert!((c.position - Vec3::new(0.0, 0.0, 10.0)).length() < 1e-6);
        assert!((c.target - c.position - Vec3::NEG_X).length() < 1e-6);
        assert!((c.up - Vec3::Y).length() < 1e-6);
        assert_eq!(c.fov_y_deg, 50.0);
        assert_eq!(scene.camera, path.keys[0].camera);
    }

    #[test]
    fn huge_frame_counts_are_refused() {
        // With a camera track, `a 0 1 100000000` asked for 10⁸ camera keys (seconds, gigabytes).
        let text = "a 0 1 100000000\np 3\n0 0 0\n1 0 0\n0 1 0\nk camera\n{\ntransl 4\n\
                    -1 0 0 1 0 0 0\n0 0 0 1 0 0 0\n1 0 0 1 0 0 0\n2 0 0 1 0 0 0\n}\n";
        let no_files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
        let options = LoadOptions::default();
        let err = parse(
            Path::new("long.aff"),
            text.as_bytes(),
            &options,
            Dialect::Aff,
            no_files,
        )
        .unwrap_err()
        .to_string();
        assert!(
            err.starts_with("long.aff:1:") && err.contains("more than 100000"),
            "{err}"
        );
    }

    #[test]
    fn malformed_aff_names_file_and_line() {
        // (main.aff, other files, where, what)
        type Case<'a> = (&'a str, &'a [(&'a str, &'a str)], &'a str, &'a str);
        let cases: [Case; 9] = [
            (
                "p 3\n0 0 0\n1 0 0\n0 1 0\ni 0 nothere.aff\n",
                &[],
                "main.aff:5:",
                "nothere.aff",
            ),
            (
                "i 0 sub.aff\n",
                &[("sub.aff", "\n\nm vertices 1 0 0 0 triangles 1 0 0 1\n")],
                "sub.aff:3:",
                "vertex index 1 is out of range",
            ),
            (
                "xs 1 1 1 0 1 0 0 0 0 0\n{\np 3\n0 0 0\n1 0 0\n0 1 0\n",
                &[],
                "main.aff:2:",
                "not closed",
            ),
            (
                "p 3\n0 0 0\n1 0 0\n0 1 0\n}\n",
                &[],
                "main.aff:5:",
                "without a block",
            ),
            (
                "i 0 sub.aff\n",
                &[("sub.aff", "x a {\n")],
                "sub.aff:1:",
                "not closed",
            ),
            ("zz 1 2 3\n", &[], "main.aff:1:", "unknown AFF command 'zz'"),
            ("a 0 1 0\n", &[], "main.aff:1:", "frames must be at least 1"),
            ("la lamp 0 0 0\n", &[], "main.aff:1:", "animated lights"),
            ("i 0 main.aff\n", &[], "main.aff:1:", "include cycle"),
        ];
        for (main, files, at, what) in cases {
            let err = load(&write_scene(main, files)).unwrap_err().to_string();
            assert!(err.contains(at) && err.contains(what), "{err}");
        }
        let err = load(&write_scene("tpa 2\n1\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n", &[]))
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("main.aff:6:") && err.contains("earlier"),
            "{err}"
        );
    }
}
