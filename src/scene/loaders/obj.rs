//! Wavefront OBJ through `tobj`, with materials from the MTL libraries it names (`mtl.rs`).
//!
//! Polygons are ear-clipped (`tobj` would fan them). A missing `.mtl` is a warning on stderr, not
//! an error: toasters and the McGuire teapot name libraries that were never distributed.
//! `tobj` reports what went wrong but not where, so on failure the file is scanned again to find
//! the offending line.

use std::cell::RefCell;
use std::io::Cursor;
use std::path::Path;

use glam::Vec3;

use super::{mtl, still_mesh_scene, triangulate, Files};
use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::scene::{Material, Mesh, Scene};

pub fn load(path: &Path) -> Result<Scene> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &bytes, &|library| std::fs::read(library))
}

/// The OBJ file `bytes` (named `path` in errors); material libraries are read through `files`,
/// relative to `path`'s directory.
pub fn parse(path: &Path, bytes: &[u8], files: Files) -> Result<Scene> {
    // A byte-order mark (editors on Windows write one) would hide the first line's keyword from
    // tobj, which then drops that line.
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let dir = path.parent().unwrap_or(Path::new("")).to_path_buf();

    // Materials of every library that loaded, in the order tobj numbers them, and the first
    // malformed library (an error: unlike a missing one, it is broken data).
    let materials: RefCell<Vec<Material>> = RefCell::new(Vec::new());
    let broken_library: RefCell<Option<Error>> = RefCell::new(None);
    let load_library = |name: &Path| -> tobj::MTLLoadResult {
        let file = dir.join(name);
        let text = match files(&file) {
            Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
            Err(e) => {
                eprintln!(
                    "warning: {}: material library {} cannot be read ({e}); using the default material",
                    path.display(),
                    file.display()
                );
                return Err(tobj::LoadError::OpenFileFailed);
            }
        };
        match mtl::parse(&file, &text) {
            Ok(parsed) => {
                let names: Vec<tobj::Material> = parsed
                    .iter()
                    .map(|m| tobj::Material {
                        name: m.name.clone(),
                        ..Default::default()
                    })
                    .collect();
                let index = parsed
                    .iter()
                    .enumerate()
                    .map(|(i, m)| (m.name.clone(), i))
                    .collect();
                materials.borrow_mut().extend(parsed);
                Ok((names, index))
            }
            Err(e) => {
                broken_library.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::MaterialParseError)
            }
        }
    };
    let options = tobj::LoadOptions {
        triangulate: false,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    if let Some(problem) = overflowing_index(path, bytes) {
        return Err(problem);
    }
    let loaded = tobj::load_obj_buf(&mut Cursor::new(bytes), &options, load_library);
    if let Some(e) = broken_library.into_inner() {
        return Err(e);
    }
    let (models, _) = match loaded {
        Ok(loaded) => loaded,
        Err(e) => return Err(locate_problem(path, bytes, &e.to_string())),
    };
    let mut materials = materials.into_inner();

    let mut mesh = Mesh::default();
    let mut default_material = None;
    for model in &models {
        let m = &model.mesh;
        if m.positions.iter().any(|x| !x.is_finite()) {
            return Err(locate_problem(path, bytes, "non-finite vertex position"));
        }
        let material = match m.material_id {
            Some(id) if id < materials.len() => id as u32,
            _ => *default_material.get_or_insert_with(|| {
                materials.push(Material::default());
                (materials.len() - 1) as u32
            }),
        };
        let vertex = |i: u32| {
            let i = i as usize * 3;
            Vec3::new(m.positions[i], m.positions[i + 1], m.positions[i + 2])
        };
        if m.face_arities.is_empty() {
            for f in m.indices.chunks_exact(3) {
                mesh.push(
                    Triangle::new(vertex(f[0]), vertex(f[1]), vertex(f[2])),
                    material,
                );
            }
        } else {
            let mut start = 0;
            for &arity in &m.face_arities {
                let face = &m.indices[start..start + arity as usize];
                start += arity as usize;
                let polygon: Vec<Vec3> = face.iter().map(|&i| vertex(i)).collect();
                for [a, b, c] in triangulate(&polygon) {
                    mesh.push(Triangle::new(polygon[a], polygon[b], polygon[c]), material);
                }
            }
        }
    }
    still_mesh_scene(path, mesh, materials)
}

/// The first line that breaks the OBJ rules `tobj` enforces (numbers that do not parse, indices
/// out of range, a zero `w`) or ours (non-finite positions); `fallback` when none is found.
fn locate_problem(path: &Path, bytes: &[u8], fallback: &str) -> Error {
    let (mut positions, mut texcoords, mut normals) = (0usize, 0usize, 0usize);
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let at = |message: String| Error::at_line(path, index + 1, message);
        let Ok(line) = std::str::from_utf8(raw) else {
            return at("not UTF-8 text".into());
        };
        let words: Vec<&str> = line.split_whitespace().collect();
        let Some((&keyword, args)) = words.split_first() else {
            continue;
        };
        let problem = match keyword {
            "v" => {
                positions += 1;
                check_position(args)
            }
            "vt" => {
                texcoords += 1;
                check_numbers("texture coordinate", args, 2)
            }
            "vn" => {
                normals += 1;
                check_numbers("normal", args, 3)
            }
            "f" => args
                .iter()
                .find_map(|corner| check_corner(corner, [positions, texcoords, normals])),
            "usemtl" | "mtllib" if args.is_empty() => Some(format!("{keyword} without a name")),
            _ => None,
        };
        if let Some(message) = problem {
            return at(message);
        }
    }
    Error::input(path, None, fallback)
}

/// The first face corner whose index would overflow tobj's index arithmetic (a panic in builds
/// with overflow checks): a relative index reaching before the first element, or an index larger
/// than the file could define.
fn overflowing_index(path: &Path, bytes: &[u8]) -> Option<Error> {
    let mut counts = [0u64; 3];
    for (index, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        // tobj refuses lines that are not UTF-8 itself.
        let Ok(line) = std::str::from_utf8(raw) else {
            continue;
        };
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => counts[0] += 1,
            Some("vt") => counts[1] += 1,
            Some("vn") => counts[2] += 1,
            Some("f") => {
                for corner in words {
                    for (k, part) in corner.split('/').take(3).enumerate() {
                        let Ok(i) = part.parse::<i64>() else {
                            continue;
                        };
                        let n = i.unsigned_abs();
                        if (i < 0 && n > counts[k]) || n > bytes.len() as u64 {
                            return Some(Error::at_line(
                                path,
                                index + 1,
                                format!(
                                    "{} index {i} is out of range ({} defined so far)",
                                    KINDS[k], counts[k]
                                ),
                            ));
                        }
                    }
                }
            }
            _ => {}
        }
    }
    None
}

fn finite(word: &str) -> bool {
    word.parse::<f32>().is_ok_and(|x| x.is_finite())
}

/// `v x y z [w | r g b]`.
fn check_position(args: &[&str]) -> Option<String> {
    if let Some(problem) = check_numbers("vertex position", args, 3) {
        return Some(problem);
    }
    match &args[3..] {
        [] => None,
        [w] if !finite(w) => Some(format!("vertex weight '{w}' is not a finite number")),
        [w] if w.parse::<f32>() == Ok(0.0) => Some("vertex weight w is zero".into()),
        [_] => None,
        [r, g, b] if [r, g, b].iter().all(|c| finite(c)) => None,
        _ => Some(format!(
            "a vertex has 3 coordinates and optionally w or an RGB colour, found '{}'",
            args.join(" ")
        )),
    }
}

fn check_numbers(what: &str, args: &[&str], n: usize) -> Option<String> {
    if args.len() < n || !args[..n].iter().all(|w| finite(w)) {
        Some(format!(
            "{what} needs {n} finite numbers, found '{}'",
            args.join(" ")
        ))
    } else {
        None
    }
}

const KINDS: [&str; 3] = ["vertex", "texture coordinate", "normal"];

/// One face corner `v`, `v/vt`, `v//vn` or `v/vt/vn`: 1-based, or negative counting back from
/// the last element defined so far.
fn check_corner(corner: &str, counts: [usize; 3]) -> Option<String> {
    let parts: Vec<&str> = corner.split('/').collect();
    if parts.len() > 3 || parts[0].is_empty() {
        return Some(format!("malformed face corner '{corner}'"));
    }
    for (k, part) in parts.iter().enumerate().filter(|(_, p)| !p.is_empty()) {
        let Ok(i) = part.parse::<i64>() else {
            return Some(format!("malformed face corner '{corner}'"));
        };
        let count = counts[k] as i64;
        let valid = if i > 0 {
            i <= count
        } else {
            i < 0 && -i <= count
        };
        if !valid {
            return Some(format!(
                "{} index {i} is out of range ({count} defined so far)",
                KINDS[k]
            ));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loaders::{default_camera, temp_file};

    #[test]
    fn triangles_quads_and_concave_polygons_with_materials() {
        let obj = temp_file(
            "shapes.obj",
            b"mtllib shapes.mtl\n\
              v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
              v 2 0 0\nv 2 2 0\nv 0 2 0\nv 0 1.5 0\nv 1.5 1.5 0\nv 1.5 0.5 0\n\
              usemtl red\n\
              f 1 2 3\n\
              f 1/1 2/1 3/1 4/1\n\
              usemtl glass\n\
              f 1 5 6 7 8 9 10\n\
              usemtl nowhere\n\
              f -3 -2 -1\n",
        );
        std::fs::write(
            obj.with_file_name("shapes.mtl"),
            "newmtl red\nKd 1 0 0\nnewmtl glass\nNi 1.5\nd 0.1\n",
        )
        .unwrap();
        // Texture coordinate 1 is referenced but never defined: tobj ignores texcoords when
        // there are none, and so do we.
        let scene = load(&obj).unwrap();
        // 1 + 2 + (7 - 2) + 1 triangles.
        assert_eq!(scene.triangle_count(), 9);
        let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["red", "glass", "default"]);
        assert_eq!(scene.mesh.material_ids, [0, 0, 0, 1, 1, 1, 1, 1, 2]);
        assert_eq!(
            scene.mesh.triangles[0],
            Triangle::new(Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0))
        );
        assert_eq!(scene.materials[1].dielectric, Some((1.5, 0.9)));
        // The concave heptagon's five triangles cover exactly its (shoelace) area.
        let heptagon = [
            (0.0, 0.0),
            (2.0, 0.0),
            (2.0, 2.0),
            (0.0, 2.0),
            (0.0, 1.5),
            (1.5, 1.5),
            (1.5, 0.5),
        ];
        let shoelace: f32 = (0..7)
            .map(|i| {
                let (a, b) = (heptagon[i], heptagon[(i + 1) % 7]);
                a.0 * b.1 - b.0 * a.1
            })
            .sum::<f32>()
            / 2.0;
        let area: f32 = scene.mesh.triangles[3..8].iter().map(|t| t.area()).sum();
        assert!((area - shoelace).abs() < 1e-5, "{area} vs {shoelace}");
        assert_eq!(scene.mesh.triangles[8].v[2], Vec3::new(1.5, 0.5, 0.0));
        assert!(scene.lights.is_empty() && scene.animation.is_none());
        assert_eq!(scene.camera, default_camera(&scene.mesh.bounds()));
    }

    #[test]
    fn a_byte_order_mark_keeps_the_first_line() {
        // tobj dropped the first vertex behind the mark: "vertex index 3 is out of range".
        let no_files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
        let text = b"\xEF\xBB\xBFv 0 0 0\r\nv 1 0 0\r\nv 0 1 0\r\nf 1 2 3\r\n";
        let scene = parse(Path::new("bom.obj"), text, no_files).unwrap();
        assert_eq!(
            scene.mesh.triangles,
            [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)]
        );
    }

    #[test]
    fn missing_library_is_only_a_warning() {
        let obj = temp_file(
            "lonely.obj",
            b"mtllib gone.mtl\nusemtl x\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        let scene = load(&obj).unwrap();
        assert_eq!(scene.triangle_count(), 1);
        assert_eq!(scene.materials, [Material::default()]);
    }

    #[test]
    fn malformed_files_name_the_line() {
        let cases: [(&[u8], usize, &str); 7] = [
            (b"v 0 0 0\nv 1 0\nf 1 2 3\n", 2, "vertex position"),
            (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", 4, "vertex index 4"),
            (b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", 4, "vertex index 0"),
            (
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n",
                4,
                "vertex index -4",
            ),
            (b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", 2, "finite"),
            (b"v 0 0 0\nv 1 0 0\nv inf 1 0\nf 1 2 3\n", 3, "finite"),
            (
                b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 x 3\n",
                4,
                "malformed face corner 'x'",
            ),
        ];
        for (text, line, what) in cases {
            let path = temp_file("bad.obj", text);
            let err = load(&path).unwrap_err().to_string();
            assert!(err.contains("bad.obj"), "{err}");
            assert!(err.contains(&format!(":{line}: ")), "{err}");
            assert!(err.contains(what), "{err}");
        }
        // Found by cargo fuzz with overflow checks: a relative index before the first element
        // or a huge one made tobj's index arithmetic overflow.
        let no_files: Files = &|_| Err(std::io::ErrorKind::NotFound.into());
        for (text, at, what) in [
            (
                &b"v 0 0 0\nvt 0 0\nf 1/-12 1/1 1/1\n"[..],
                "overflow.obj:3:",
                "texture coordinate index -12",
            ),
            (
                b"v 0 0 0\nf 1 1 9223372036854775807\n",
                "overflow.obj:2:",
                "vertex index 9223372036854775807",
            ),
        ] {
            let err = parse(Path::new("overflow.obj"), text, no_files)
                .unwrap_err()
                .to_string();
            assert!(err.starts_with(at) && err.contains(what), "{err}");
        }
        let empty = temp_file("empty.obj", b"# nothing\nv 0 0 0\n");
        assert!(load(&empty)
            .unwrap_err()
            .to_string()
            .contains("no triangles"));
        let broken_lib = temp_file(
            "lib.obj",
            b"mtllib lib.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        );
        std::fs::write(broken_lib.with_file_name("lib.mtl"), "newmtl a\nKd 1 1\n").unwrap();
        let err = load(&broken_lib).unwrap_err().to_string();
        assert!(err.contains("lib.mtl:2:"), "{err}");
    }
}
