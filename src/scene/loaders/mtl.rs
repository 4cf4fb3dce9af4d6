//! Wavefront MTL material libraries, mapped onto the scene's material model:
//!
//! - `Kd` → diffuse albedo; `Ke` → emission;
//! - `Ks` (mean of its channels) with `Ns` → a Phong glossy lobe `(Ns, Ks)`, or a perfect mirror
//!   of reflectance `Ks` when the illumination model asks for ray-traced reflection (`illum` 3, 5
//!   or 7) or the lobe is so narrow (`Ns` ≥ 1000) that it is one; `Ks` without a positive `Ns`
//!   describes no lobe and is dropped;
//! - transparency `1 − d` (or `Tr` when `d` is absent) > 0 → a dielectric with that transmission
//!   and index of refraction `Ni` (1 when absent or ≤ 0: a see-through surface that does not bend
//!   light).
//!
//! Parsed here rather than by `tobj` so that every malformed statement is reported with its line
//! (and `tobj` panics on colour statements with fewer than three numbers).

use std::path::Path;

use glam::Vec3;

use super::nff::dielectric;
use crate::error::{Error, Result};
use crate::scene::Material;

/// Phong exponents at or above this are treated as perfect mirrors.
const MIRROR_EXPONENT: f32 = 1000.0;

/// The statements of one `newmtl` block that the material model uses.
#[derive(Default)]
struct Statements {
    kd: Option<Vec3>,
    ks: Option<Vec3>,
    ke: Option<Vec3>,
    ns: Option<f32>,
    ni: Option<f32>,
    d: Option<f32>,
    tr: Option<f32>,
    illum: Option<u32>,
}

impl Statements {
    fn into_material(self, name: String) -> Material {
        let base = Material::default();
        let mut m = Material {
            name,
            diffuse: self.kd.unwrap_or(base.diffuse),
            emission: self.ke.unwrap_or(Vec3::ZERO),
            ..base
        };
        let reflectance = self.ks.map_or(0.0, |ks| (ks.x + ks.y + ks.z) / 3.0);
        if reflectance > 0.0 {
            let exponent = self.ns.unwrap_or(0.0);
            let ray_traced = matches!(self.illum, Some(3 | 5 | 7));
            if ray_traced || exponent >= MIRROR_EXPONENT {
                m.mirror = reflectance;
            } else if exponent > 0.0 {
                m.glossy = Some((exponent, reflectance));
            }
        }
        let transmission = match (self.d, self.tr) {
            (Some(d), _) => 1.0 - d,
            (None, Some(tr)) => tr,
            (None, None) => 0.0,
        };
        m.dielectric = dielectric(transmission, self.ni.unwrap_or(1.0));
        m
    }
}

/// The materials of an MTL file, in file order.
pub fn parse(path: &Path, text: &str) -> Result<Vec<Material>> {
    let mut materials = Vec::new();
    let mut current: Option<(String, Statements)> = None;
    // A byte-order mark (editors on Windows write one) is not part of the first keyword.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    for (index, line) in text.lines().enumerate() {
        let at = |message: String| Error::at_line(path, index + 1, message);
        let line = line.split('#').next().unwrap_or("").trim();
        let mut words = line.split_whitespace();
        let Some(keyword) = words.next() else {
            continue;
        };
        if keyword == "newmtl" {
            let name = line["newmtl".len()..].trim();
            if name.is_empty() {
                return Err(at("newmtl without a name".into()));
            }
            if let Some((name, s)) = current.take() {
                materials.push(s.into_material(name));
            }
            current = Some((name.to_string(), Statements::default()));
            continue;
        }
        let used = matches!(
            keyword,
            "Kd" | "Ks" | "Ke" | "Ka" | "Ns" | "Ni" | "d" | "Tr" | "illum"
        );
        if !used {
            // Texture maps and renderer-specific extensions: textures are not part of the data.
            continue;
        }
        let Some((_, s)) = current.as_mut() else {
            return Err(at(format!("'{keyword}' before any 'newmtl'")));
        };
        let args: Vec<&str> = words.collect();
        match keyword {
            "Kd" => s.kd = Some(colour(&args).map_err(at)?),
            "Ks" => s.ks = Some(colour(&args).map_err(at)?),
            "Ke" => s.ke = Some(colour(&args).map_err(at)?),
            // Ambient has no place in the material model; it is still checked.
            "Ka" => {
                colour(&args).map_err(at)?;
            }
            "Ns" => s.ns = Some(scalar(keyword, &args).map_err(at)?),
            "Ni" => s.ni = Some(scalar(keyword, &args).map_err(at)?),
            // `d -halo f` is the one option a dissolve may carry.
            "d" => {
                let args = args.strip_prefix(&["-halo"]).unwrap_or(&args);
                s.d = Some(scalar(keyword, args).map_err(at)?);
            }
            "Tr" => s.tr = Some(scalar(keyword, &args).map_err(at)?),
            _ => {
                let illum = match args.as_slice() {
                    [n] => n.parse::<u32>().ok(),
                    _ => None,
                };
                s.illum = Some(illum.ok_or_else(|| {
                    at(format!(
                        "illum needs one integer, found '{}'",
                        args.join(" ")
                    ))
                })?);
            }
        }
    }
    if let Some((name, s)) = current {
        materials.push(s.into_material(name));
    }
    Ok(materials)
}

fn number(word: &str) -> Option<f32> {
    word.parse::<f32>().ok().filter(|x| x.is_finite())
}

/// An RGB colour: three numbers, or one for grey (as the MTL specification allows).
fn colour(args: &[&str]) -> std::result::Result<Vec3, String> {
    let values: Option<Vec<f32>> = args.iter().map(|w| number(w)).collect();
    match values.as_deref() {
        Some([g]) => Ok(Vec3::splat(*g)),
        Some([r, g, b]) => Ok(Vec3::new(*r, *g, *b)),
        _ => Err(format!(
            "expected a colour (1 or 3 finite numbers), found '{}'",
            args.join(" ")
        )),
    }
}

fn scalar(keyword: &str, args: &[&str]) -> std::result::Result<f32, String> {
    match args {
        [w] => number(w).ok_or_else(|| format!("{keyword} needs a finite number, found '{w}'")),
        _ => Err(format!(
            "{keyword} needs one number, found '{}'",
            args.join(" ")
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statements_map_to_the_material_model() {
        let text = "\
# test library
newmtl red
Kd 0.8 0.1 0.1
Ks 0 0 0
newmtl shiny
Kd 0.2
Ks 0.3 0.6 0.9
Ns 50
newmtl mirror
Ks 0.9 0.9 0.9
illum 3
newmtl glass
Kd 0 0 0
Ni 1.5
d 0.25
newmtl lamp
Ke 4 4 2
newmtl veil
Tr 0.5
map_Kd veil.ppm
";
        let m = parse(Path::new("t.mtl"), text).unwrap();
        let names: Vec<&str> = m.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["red", "shiny", "mirror", "glass", "lamp", "veil"]);
        assert_eq!(m[0].diffuse, Vec3::new(0.8, 0.1, 0.1));
        assert!(!m[0].is_reflective() && !m[0].is_refractive());
        assert_eq!(m[1].diffuse, Vec3::splat(0.2));
        let (exponent, reflectance) = m[1].glossy.unwrap();
        assert_eq!(exponent, 50.0);
        assert!((reflectance - 0.6).abs() < 1e-6);
        assert_eq!(m[1].mirror, 0.0);
        assert!((m[2].mirror - 0.9).abs() < 1e-6);
        assert_eq!(m[2].glossy, None);
        assert_eq!(m[3].dielectric, Some((1.5, 0.75)));
        assert_eq!(m[4].emission, Vec3::new(4.0, 4.0, 2.0));
        assert_eq!(m[5].dielectric, Some((1.0, 0.5)));
    }

    #[test]
    fn malformed_statements_name_their_line() {
        let cases = [
            ("newmtl a\nKd 1 2\n", 2, "colour"),
            ("Kd 1 1 1\n", 1, "before any 'newmtl'"),
            ("newmtl a\n\nNs inf\n", 3, "finite"),
            ("newmtl a\nillum x\n", 2, "illum"),
            ("newmtl\n", 1, "without a name"),
        ];
        for (text, line, what) in cases {
            let err = parse(Path::new("bad.mtl"), text).unwrap_err().to_string();
            assert!(err.starts_with(&format!("bad.mtl:{line}:")), "{err}");
            assert!(err.contains(what), "{err}");
        }
    }

    #[test]
    fn a_byte_order_mark_is_not_part_of_the_first_keyword() {
        let m = parse(Path::new("bom.mtl"), "\u{feff}newmtl red\nKd 1 0 0\n").unwrap();
        assert_eq!((m[0].name.as_str(), m[0].diffuse), ("red", Vec3::X));
    }
}
