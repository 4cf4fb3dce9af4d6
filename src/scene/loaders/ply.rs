//! PLY polygon files (Turk, "The PLY Polygon File Format", 1994): ASCII and binary little- or
//! big-endian, elements and properties in any order, vertices from the `x y z` properties of
//! `vertex`, faces from the list property `vertex_indices` (or `vertex_index`) of `face` with any
//! integer count and index types. Other elements and properties are read past. `.ply.gz` files
//! (the Stanford dragons) are inflated with flate2 first; line numbers then refer to the
//! decompressed text. Binary bodies have no lines, so their errors give the byte offset.

use std::io::Read;
use std::path::Path;

use glam::Vec3;

use super::{still_mesh_scene, triangulate};
use crate::error::{Error, Result};
use crate::geometry::Triangle;
use crate::scene::{Material, Mesh, Scene};

pub fn load(path: &Path) -> Result<Scene> {
    let raw = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse(path, &raw)
}

/// The PLY file `raw` (named `path` in errors), inflated first when `path` ends in `.gz`.
pub fn parse(path: &Path, raw: &[u8]) -> Result<Scene> {
    let gzipped = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("gz"));
    let data = if gzipped {
        let mut data = Vec::new();
        flate2::read::GzDecoder::new(raw)
            .read_to_end(&mut data)
            .map_err(|e| Error::input(path, None, format!("cannot inflate gzip data: {e}")))?;
        std::borrow::Cow::Owned(data)
    } else {
        std::borrow::Cow::Borrowed(raw)
    };
    let mesh = parse_mesh(path, &data)?;
    still_mesh_scene(path, mesh, vec![Material::default()])
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn from_name(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_integer(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }
}

enum Property {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

struct Element {
    name: String,
    count: usize,
    /// (name, type) in file order.
    properties: Vec<(String, Property)>,
    line: usize,
}

enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset and line number where the body starts.
    body: usize,
    body_line: usize,
}

fn parse_header(path: &Path, data: &[u8]) -> Result<Header> {
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut offset = 0;
    let mut line_no = 0;
    loop {
        line_no += 1;
        let at = |message: String| Error::at_line(path, line_no, message);
        let Some(len) = data[offset..].iter().position(|&b| b == b'\n') else {
            return Err(at("the header does not end with 'end_header'".into()));
        };
        let line = std::str::from_utf8(&data[offset..offset + len])
            .map_err(|_| at("the header is not ASCII text".into()))?
            .trim();
        offset += len + 1;
        let words: Vec<&str> = line.split_whitespace().collect();
        if line_no == 1 {
            if line != "ply" {
                return Err(at("not a PLY file: the first line must be 'ply'".into()));
            }
            continue;
        }
        match words.as_slice() {
            ["format", format, version] => {
                if *version != "1.0" {
                    return Err(at(format!("unsupported PLY version '{version}'")));
                }
                encoding = Some(match *format {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    _ => return Err(at(format!("unknown PLY format '{format}'"))),
                });
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count = count
                    .parse::<usize>()
                    .map_err(|_| at(format!("element count '{count}' is not a number")))?;
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    properties: Vec::new(),
                    line: line_no,
                });
            }
            ["property", rest @ ..] => {
                let element = elements
                    .last_mut()
                    .ok_or_else(|| at("property before any element".into()))?;
                let scalar = |name: &str| {
                    Scalar::from_name(name).ok_or_else(|| at(format!("unknown type '{name}'")))
                };
                let (name, property) = match rest {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if !count.is_integer() {
                            return Err(at("a list's count type must be an integer".into()));
                        }
                        let item = scalar(item)?;
                        (name, Property::List { count, item })
                    }
                    [ty, name] => (name, Property::Scalar(scalar(ty)?)),
                    _ => return Err(at(format!("malformed property line '{line}'"))),
                };
                element.properties.push((name.to_string(), property));
            }
            ["end_header"] => {
                let encoding =
                    encoding.ok_or_else(|| at("no 'format' line before 'end_header'".into()))?;
                return Ok(Header {
                    encoding,
                    elements,
                    body: offset,
                    body_line: line_no + 1,
                });
            }
            _ => return Err(at(format!("unexpected header line '{line}'"))),
        }
    }
}

/// Where the body reader is, for error messages.
enum Body<'a> {
    Ascii {
        text: &'a [u8],
        pos: usize,
        line: usize,
        token_line: usize,
    },
    Binary {
        data: &'a [u8],
        pos: usize,
        big_endian: bool,
    },
}

impl Body<'_> {
    fn error(&self, path: &Path, message: String) -> Error {
        match self {
            Body::Ascii { token_line, .. } => Error::at_line(path, *token_line, message),
            Body::Binary { pos, .. } => {
                Error::input(path, None, format!("at byte {pos} of the body: {message}"))
            }
        }
    }

    fn value(&mut self, ty: Scalar) -> std::result::Result<f64, String> {
        match self {
            Body::Ascii {
                text,
                pos,
                line,
                token_line,
            } => {
                while *pos < text.len() && text[*pos].is_ascii_whitespace() {
                    if text[*pos] == b'\n' {
                        *line += 1;
                    }
                    *pos += 1;
                }
                let start = *pos;
                while *pos < text.len() && !text[*pos].is_ascii_whitespace() {
                    *pos += 1;
                }
                if start == *pos {
                    // Reported at the line of the last value read.
                    return Err("the file ends before all elements are read".into());
                }
                *token_line = *line;
                let word = std::str::from_utf8(&text[start..*pos]).unwrap_or("");
                let value = if ty.is_integer() {
                    word.parse::<i64>().map(|i| i as f64).ok()
                } else {
                    word.parse::<f64>().ok()
                };
                value.ok_or_else(|| format!("expected a {ty:?} value, found '{word}'"))
            }
            Body::Binary {
                data,
                pos,
                big_endian,
            } => {
                let n = ty.size();
                let bytes = data
                    .get(*pos..*pos + n)
                    .ok_or("the file ends before all elements are read")?;
                *pos += n;
                let mut b = [0u8; 8];
                b[..n].copy_from_slice(bytes);
                if *big_endian {
                    b[..n].reverse();
                }
                Ok(match ty {
                    Scalar::I8 => i8::from_le_bytes([b[0]]) as f64,
                    Scalar::U8 => b[0] as f64,
                    Scalar::I16 => i16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::U16 => u16::from_le_bytes([b[0], b[1]]) as f64,
                    Scalar::I32 => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    Scalar::F64 => f64::from_le_bytes(b),
                })
            }
        }
    }
}

fn parse_mesh(path: &Path, data: &[u8]) -> Result<Mesh> {
    let header = parse_header(path, data)?;
    let vertex_count = header
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count);
    let mut body = match header.encoding {
        Encoding::Ascii => Body::Ascii {
            text: &data[header.body..],
            pos: 0,
            line: header.body_line,
            token_line: header.body_line,
        },
        Encoding::Binary { big_endian } => Body::Binary {
            data: &data[header.body..],
            pos: 0,
            big_endian,
        },
    };
    let mut vertices: Vec<Vec3> = Vec::new();
    // Faces as flat index lists; triangulated once all vertices are known (faces may come first).
    let mut indices: Vec<u32> = Vec::new();
    let mut arities: Vec<usize> = Vec::new();
    let mut has_faces = false;
    for element in &header.elements {
        let slot = |name: &str| element.properties.iter().position(|(n, _)| n == name);
        let header_error = |message: String| Error::at_line(path, element.line, message);
        let xyz = match element.name.as_str() {
            "vertex" => {
                let scalar = |name: &str| {
                    slot(name).filter(|&i| matches!(element.properties[i].1, Property::Scalar(_)))
                };
                match [scalar("x"), scalar("y"), scalar("z")] {
                    [Some(x), Some(y), Some(z)] => Some([x, y, z]),
                    _ => {
                        return Err(header_error(
                            "vertex element without scalar x, y and z properties".into(),
                        ))
                    }
                }
            }
            _ => None,
        };
        let face_list = match element.name.as_str() {
            "face" => {
                has_faces = true;
                let list = slot("vertex_indices").or_else(|| slot("vertex_index"));
                match list.map(|i| &element.properties[i].1) {
                    Some(Property::List { item, .. }) if item.is_integer() => list,
                    _ => {
                        return Err(header_error(
                            "face element without an integer list 'vertex_indices'".into(),
                        ))
                    }
                }
            }
            _ => None,
        };
        if xyz.is_some() {
            vertices.reserve(element.count.min(data.len()));
        }
        // An element without properties has nothing in the body, whatever its count says.
        let count = if element.properties.is_empty() {
            0
        } else {
            element.count
        };
        for instance in 0..count {
            let mut position = [0.0f64; 3];
            for (p, (_, property)) in element.properties.iter().enumerate() {
                match property {
                    Property::Scalar(ty) => {
                        let v = body.value(*ty).map_err(|m| body.error(path, m))?;
                        if let Some(axis) = xyz.and_then(|xyz| xyz.iter().position(|&s| s == p)) {
                            position[axis] = v;
                        }
                    }
                    Property::List { count, item } => {
                        let n = body.value(*count).map_err(|m| body.error(path, m))?;
                        if n < 0.0 {
                            return Err(body.error(path, format!("negative list length {n}")));
                        }
                        let is_face = face_list == Some(p);
                        for _ in 0..n as usize {
                            let v = body.value(*item).map_err(|m| body.error(path, m))?;
                            if is_face {
                                if v < 0.0 || v >= vertex_count as f64 {
                                    return Err(body.error(
                                        path,
                                        format!(
                                            "face {instance}: vertex index {v} is out of range (0..{vertex_count})"
                                        ),
                                    ));
                                }
                                indices.push(v as u32);
                            }
                        }
                        if is_face {
                            if n < 3.0 {
                                return Err(body.error(
                                    path,
                                    format!(
                                        "face {instance} has {n} vertices; at least 3 are needed"
                                    ),
                                ));
                            }
                            arities.push(n as usize);
                        }
                    }
                }
            }
            if xyz.is_some() {
                let p = Vec3::new(position[0] as f32, position[1] as f32, position[2] as f32);
                if !p.is_finite() {
                    return Err(body.error(path, format!("vertex {instance} is not finite: {p}")));
                }
                vertices.push(p);
            }
        }
    }
    if !has_faces {
        return Err(Error::input(
            path,
            None,
            "no face element (point clouds are not scenes)",
        ));
    }
    let mut mesh = Mesh::default();
    let mut start = 0;
    for &n in &arities {
        let face: Vec<Vec3> = indices[start..start + n]
            .iter()
            .map(|&i| vertices[i as usize])
            .collect();
        start += n;
        for [a, b, c] in triangulate(&face) {
            mesh.push(Triangle::new(face[a], face[b], face[c]), 0);
        }
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::loaders::temp_file;
    use std::io::Write;

    const SQUARE: [[f32; 3]; 5] = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
        [1.0, 1.0, 5.0],
    ];

    /// Header for 5 vertices with an extra property before x, and faces whose list comes after
    /// another property; one triangle and one quad.
    fn header(format: &str) -> String {
        format!(
            "ply\nformat {format} 1.0\ncomment test\nelement vertex 5\nproperty uchar flag\n\
             property float x\nproperty double y\nproperty float z\n\
             element face 2\nproperty int tag\nproperty list uchar uint vertex_indices\nend_header\n"
        )
    }

    fn binary(big_endian: bool) -> Vec<u8> {
        let mut out = header(if big_endian {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        })
        .into_bytes();
        let mut put = |bytes: &[u8]| {
            let mut b = bytes.to_vec();
            if big_endian {
                b.reverse();
            }
            out.extend_from_slice(&b);
        };
        for v in SQUARE {
            put(&[7]);
            put(&v[0].to_le_bytes());
            put(&(v[1] as f64).to_le_bytes());
            put(&v[2].to_le_bytes());
        }
        for face in [&[0u32, 1, 4][..], &[0, 1, 2, 3]] {
            put(&(-1i32).to_le_bytes());
            put(&[face.len() as u8]);
            for &i in face {
                put(&i.to_le_bytes());
            }
        }
        out
    }

    fn check(scene: &Scene) {
        assert_eq!(scene.triangle_count(), 3);
        let v = |i: usize| Vec3::from(SQUARE[i]);
        assert_eq!(scene.mesh.triangles[0], Triangle::new(v(0), v(1), v(4)));
        let quad_area: f32 = scene.mesh.triangles[1..].iter().map(|t| t.area()).sum();
        assert_eq!(quad_area, 4.0);
        assert!(scene.mesh.triangles[1..].iter().all(|t| t.normal().z > 0.0));
    }

    #[test]
    fn ascii_binary_both_endians_and_gzip_agree() {
        let ascii = header("ascii")
            + "7 0 0 0\n7 2 0 0\n7 2 2 0\n7 0 2 0\n7 1 1 5\n-1 3 0 1 4\n-1 4 0 1 2 3\n";
        check(&load(&temp_file("a.ply", ascii.as_bytes())).unwrap());
        check(&load(&temp_file("le.ply", &binary(false))).unwrap());
        check(&load(&temp_file("be.ply", &binary(true))).unwrap());
        let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
        gz.write_all(ascii.as_bytes()).unwrap();
        let scene = load(&temp_file("z.ply.gz", &gz.finish().unwrap())).unwrap();
        check(&scene);
        assert_eq!(scene.name, "z");
    }

    #[test]
    fn faces_may_precede_vertices() {
        let text = "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_index\n\
                    element vertex 3\nproperty float x\nproperty float y\nproperty float z\nend_header\n\
                    3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n";
        let scene = load(&temp_file("fv.ply", text.as_bytes())).unwrap();
        assert_eq!(
            scene.mesh.triangles,
            [Triangle::new(Vec3::Y, Vec3::X, Vec3::ZERO)]
        );
    }

    /// Fuzzing found a hang: an element without properties claiming 10⁹ instances was read
    /// instance by instance, though it has no data.
    #[test]
    fn elements_without_properties_take_no_time() {
        let text = "ply\nformat binary_little_endian 1.0\nelement edge 1000000000000\n\
                    element face 0\nproperty list uchar int vertex_indices\nend_header\n";
        let start = std::time::Instant::now();
        let scene = parse(Path::new("empty.ply"), text.as_bytes());
        assert!(scene.unwrap_err().to_string().contains("no triangles"));
        assert!(start.elapsed().as_secs_f64() < 0.1);
    }

    #[test]
    fn malformed_files_name_the_line_or_offset() {
        let base = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
                    property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
        let cases = [
            (
                format!("{base}0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n"),
                "bad.ply:13:",
                "out of range",
            ),
            (
                format!("{base}0 0 0\n1 nan 0\n0 1 0\n3 0 1 2\n"),
                "bad.ply:11:",
                "not finite",
            ),
            (
                format!("{base}0 0 0\n1 0 0\n0 1 x\n3 0 1 2\n"),
                "bad.ply:12:",
                "found 'x'",
            ),
            (
                format!("{base}0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
                "bad.ply:13:",
                "at least 3",
            ),
            (
                format!("{base}0 0 0\n1 0 0\n"),
                "bad.ply:11:",
                "ends before",
            ),
            (
                base.replace("float y", "flaot y"),
                "bad.ply:5:",
                "unknown type 'flaot'",
            ),
            (
                base.replace("ascii", "utf8"),
                "bad.ply:2:",
                "unknown PLY format",
            ),
            ("plx\n".to_string(), "bad.ply:1:", "not a PLY file"),
        ];
        for (text, at, what) in cases {
            let err = load(&temp_file("bad.ply", text.as_bytes()))
                .unwrap_err()
                .to_string();
            assert!(err.contains(at) && err.contains(what), "{err}");
        }
        let mut truncated = binary(false);
        truncated.truncate(truncated.len() - 3);
        let err = load(&temp_file("cut.ply", &truncated))
            .unwrap_err()
            .to_string();
        assert!(err.contains("cut.ply") && err.contains("at byte"), "{err}");
        let not_gzip = load(&temp_file("fake.ply.gz", b"ply\n"))
            .unwrap_err()
            .to_string();
        assert!(
            not_gzip.contains("fake.ply.gz") && not_gzip.contains("gzip"),
            "{not_gzip}"
        );
    }
}
