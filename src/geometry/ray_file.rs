//! User ray files: rays written by one run (or by someone else's renderer) and replayed against
//! any tracer. Two encodings, told apart by content (the magic), never by the file name:
//!
//! Binary, all little-endian:
//!
//! | byte offset | size      | field                                                           |
//! |-------------|-----------|-----------------------------------------------------------------|
//! | 0           | 8         | magic `RAYLABRY`                                                |
//! | 8           | 4 (u32)   | version, 1                                                      |
//! | 12          | 4 (u32)   | flags: bit 0 = every ray has a time; other bits must be 0       |
//! | 16          | 8 (u64)   | ray count n                                                     |
//! | 24          | n × 32/36 | per ray, f32: ox oy oz dx dy dz tmin tmax [time]                |
//!
//! CSV: the header line `ox,oy,oz,dx,dy,dz,tmin,tmax` (or `…,tmax,time`), then one ray per line
//! with that many fields. Blank lines are skipped. Values are anything Rust's `f32` parser reads,
//! including `inf`, `-inf` and `NaN`.
//!
//! NaN and infinite values are allowed in both encodings: the stability suite feeds ill-formed
//! rays on purpose, and every tracer must answer them with a miss (not occluded). Binary files keep
//! every bit (NaN payloads, −0); CSV keeps every value exactly but writes every NaN as `NaN`.
//!
//! A truncated or malformed file is an `Error::Input` (exit code 2) naming the file and the byte
//! offset (binary) or line (CSV) where it goes wrong. The ray count of a binary header is checked
//! against the file's length before anything is allocated for it.
//!
//! Rays read from a file are of kind `Primary` (closest hit) with `pixel[i] = i`.

use std::path::Path;

use crate::error::{Error, Result};
use crate::geometry::{Hit, RayBatch, RayKind, Rays};

/// The first 8 bytes of a binary ray file.
pub const MAGIC: &[u8; 8] = b"RAYLABRY";
/// The binary format's version.
pub const VERSION: u32 = 1;
/// Header flag: each ray carries a ninth value, its time.
pub const FLAG_TIME: u32 = 1;
/// Bytes before the first ray of a binary file.
pub const HEADER_BYTES: usize = 24;
/// The CSV header without and with times.
pub const CSV_HEADER: &str = "ox,oy,oz,dx,dy,dz,tmin,tmax";
pub const CSV_HEADER_TIME: &str = "ox,oy,oz,dx,dy,dz,tmin,tmax,time";

/// The two encodings of a ray file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RayFileFormat {
    Binary,
    Csv,
}

/// Reads the rays of `path`, binary or CSV by content.
pub fn read_rays(path: &Path) -> Result<RayBatch> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_rays(path, &bytes)
}

/// Parses the contents `bytes` of `path` (named in errors).
pub fn parse_rays(path: &Path, bytes: &[u8]) -> Result<RayBatch> {
    let prefix = &bytes[..bytes.len().min(MAGIC.len())];
    if !bytes.is_empty() && MAGIC.starts_with(prefix) {
        parse_binary(path, bytes)
    } else {
        parse_csv(path, bytes)
    }
}

/// Writes the rays of `rays` to `path` in `format`.
pub fn write_rays(path: &Path, rays: Rays<'_>, format: RayFileFormat) -> Result<()> {
    let bytes = match format {
        RayFileFormat::Binary => encode_binary(rays),
        RayFileFormat::Csv => encode_csv(rays).into_bytes(),
    };
    std::fs::write(path, bytes).map_err(|e| Error::io(path, e))
}

/// The header of `hits_csv`.
pub const HITS_CSV_HEADER: &str = "ray,hit,t,prim,u,v";
/// The header of `occlusion_csv`.
pub const OCCLUSION_CSV_HEADER: &str = "ray,occluded";

/// Closest hits as CSV, one line per ray in file order: `ray,hit,t,prim,u,v` with `hit` 1 or 0;
/// a miss reads `ray,0,inf,-1,0,0`. Values are written in the shortest form that reads back
/// exactly, so two tracers' files compare byte for byte.
pub fn hits_csv(hits: &[Hit]) -> String {
    let mut out = String::with_capacity(32 + hits.len() * 40);
    out.push_str(HITS_CSV_HEADER);
    out.push('\n');
    for (i, h) in hits.iter().enumerate() {
        let line = match h.is_hit() {
            true => format!("{i},1,{},{},{},{}\n", h.t, h.prim, h.u, h.v),
            false => format!("{i},0,inf,-1,0,0\n"),
        };
        out.push_str(&line);
    }
    out
}

/// Occlusion answers as CSV, one line per ray in file order: `ray,occluded` with 1 or 0.
pub fn occlusion_csv(occluded: &[bool]) -> String {
    let mut out = String::with_capacity(16 + occluded.len() * 10);
    out.push_str(OCCLUSION_CSV_HEADER);
    out.push('\n');
    for (i, &o) in occluded.iter().enumerate() {
        out.push_str(&format!("{i},{}\n", u8::from(o)));
    }
    out
}

fn has_time(rays: &Rays<'_>) -> bool {
    !rays.time.is_empty()
}

/// The binary encoding of `rays`: with times when the view has a time lane.
pub fn encode_binary(rays: Rays<'_>) -> Vec<u8> {
    let timed = has_time(&rays);
    let record = record_bytes(timed);
    let mut out = Vec::with_capacity(HEADER_BYTES + rays.len() * record);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&VERSION.to_le_bytes());
    out.extend_from_slice(&(if timed { FLAG_TIME } else { 0 }).to_le_bytes());
    out.extend_from_slice(&(rays.len() as u64).to_le_bytes());
    for i in 0..rays.len() {
        for value in ray_values(&rays, i, timed) {
            out.extend_from_slice(&value.to_le_bytes());
        }
    }
    out
}

/// The CSV encoding of `rays`: with a time column when the view has a time lane. Every finite
/// value is written in the shortest form that reads back to the same `f32`.
pub fn encode_csv(rays: Rays<'_>) -> String {
    let timed = has_time(&rays);
    let mut out = String::with_capacity(16 + rays.len() * 64);
    out.push_str(if timed { CSV_HEADER_TIME } else { CSV_HEADER });
    out.push('\n');
    for i in 0..rays.len() {
        let values: Vec<String> = ray_values(&rays, i, timed).map(|v| v.to_string()).collect();
        out.push_str(&values.join(","));
        out.push('\n');
    }
    out
}

/// Ray `i`'s values in file order.
fn ray_values<'a>(rays: &'a Rays<'_>, i: usize, timed: bool) -> impl Iterator<Item = f32> + 'a {
    let lanes = [
        rays.ox, rays.oy, rays.oz, rays.dx, rays.dy, rays.dz, rays.tmin, rays.tmax,
    ];
    let time = timed.then(|| rays.time[i]);
    lanes.into_iter().map(move |lane| lane[i]).chain(time)
}

fn record_bytes(timed: bool) -> usize {
    4 * if timed { 9 } else { 8 }
}

/// An empty batch with room for `n` rays (`n` already checked against the input's size).
fn batch_for(n: usize, timed: bool) -> RayBatch {
    let mut batch = RayBatch::with_capacity(RayKind::Primary, n);
    if timed {
        batch.time.reserve_exact(n);
    }
    batch
}

/// Appends one ray given as its values in file order; the time lane is kept whole and trimmed
/// by `finish` when every time is zero.
fn push_values(batch: &mut RayBatch, v: &[f32]) {
    let lanes = [
        &mut batch.ox,
        &mut batch.oy,
        &mut batch.oz,
        &mut batch.dx,
        &mut batch.dy,
        &mut batch.dz,
        &mut batch.tmin,
        &mut batch.tmax,
    ];
    for (lane, &value) in lanes.into_iter().zip(v) {
        lane.push(value);
    }
    if let Some(&time) = v.get(8) {
        batch.time.push(time);
    }
    batch.pixel.push(batch.pixel.len() as u32);
}

/// A time lane of only +0 is the same as none (`RayBatch::time`): drop it.
fn finish(mut batch: RayBatch) -> RayBatch {
    if batch.time.iter().all(|t| t.to_bits() == 0) {
        batch.time = Vec::new();
    }
    batch
}

fn at_offset(path: &Path, offset: usize, message: impl std::fmt::Display) -> Error {
    Error::input(path, None, format!("byte offset {offset}: {message}"))
}

fn parse_binary(path: &Path, bytes: &[u8]) -> Result<RayBatch> {
    let field = |offset: usize, len: usize, name: &str| -> Result<&[u8]> {
        bytes.get(offset..offset + len).ok_or_else(|| {
            at_offset(
                path,
                offset,
                format!(
                    "truncated binary ray file: the header's {name} needs {len} bytes, the file ends after {}",
                    bytes.len()
                ),
            )
        })
    };
    let u32_at = |offset: usize, name: &str| -> Result<u32> {
        let b = field(offset, 4, name)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    field(0, MAGIC.len(), "magic")?;
    let version = u32_at(8, "version")?;
    if version != VERSION {
        return Err(at_offset(
            path,
            8,
            format!("unsupported ray file version {version} (this raylab reads version {VERSION})"),
        ));
    }
    let flags = u32_at(12, "flags")?;
    if flags & !FLAG_TIME != 0 {
        return Err(at_offset(
            path,
            12,
            format!("unknown flags {flags:#x} (only bit 0, has time, is defined)"),
        ));
    }
    let count = field(16, 8, "ray count")?;
    let count = u64::from_le_bytes(count.try_into().expect("8 bytes"));
    let timed = flags & FLAG_TIME != 0;
    let record = record_bytes(timed);
    let body = bytes.len() - HEADER_BYTES;
    let complete = body / record;
    if count > complete as u64 {
        let at = HEADER_BYTES + complete * record;
        return Err(at_offset(
            path,
            at,
            format!(
                "truncated binary ray file: the header says {count} rays of {record} bytes, the file ends {} bytes into ray {complete}",
                body % record
            ),
        ));
    }
    let n = count as usize;
    let end = HEADER_BYTES + n * record;
    if end != bytes.len() {
        return Err(at_offset(
            path,
            end,
            format!(
                "{} bytes after the last of the header's {count} rays",
                bytes.len() - end
            ),
        ));
    }
    let mut batch = batch_for(n, timed);
    let mut values = [0f32; 9];
    for chunk in bytes[HEADER_BYTES..].chunks_exact(record) {
        for (value, b) in values.iter_mut().zip(chunk.chunks_exact(4)) {
            *value = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
        push_values(&mut batch, &values[..record / 4]);
    }
    Ok(finish(batch))
}

fn parse_csv(path: &Path, bytes: &[u8]) -> Result<RayBatch> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        at_offset(
            path,
            e.valid_up_to(),
            "neither a binary ray file (magic RAYLABRY) nor CSV text (not UTF-8)",
        )
    })?;
    // A byte-order mark, as spreadsheet programs write, is not part of the header.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, line)| (i + 1, line.trim()))
        .filter(|(_, line)| !line.is_empty());
    let Some((header_line, header)) = lines.next() else {
        return Err(Error::input(
            path,
            None,
            format!("empty ray file: expected the magic RAYLABRY or the CSV header {CSV_HEADER}"),
        ));
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let timed = if columns.join(",") == CSV_HEADER {
        false
    } else if columns.join(",") == CSV_HEADER_TIME {
        true
    } else {
        return Err(Error::at_line(
            path,
            header_line,
            format!(
                "not a ray file: expected the magic RAYLABRY or the CSV header {CSV_HEADER}[,time], found {header:?}"
            ),
        ));
    };
    let width = if timed { 9 } else { 8 };
    // At most one ray per remaining line: a bound given by the input itself.
    let mut batch = batch_for(text.lines().count().saturating_sub(header_line), timed);
    let mut values = [0f32; 9];
    for (line_number, line) in lines {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        if fields.len() != width {
            return Err(Error::at_line(
                path,
                line_number,
                format!("expected {width} values, found {}", fields.len()),
            ));
        }
        for ((value, field), name) in values.iter_mut().zip(&fields).zip(columns.iter()) {
            *value = field.parse().map_err(|_| {
                Error::at_line(
                    path,
                    line_number,
                    format!("{name}: not a number: {field:?}"),
                )
            })?;
        }
        push_values(&mut batch, &values[..width]);
    }
    Ok(finish(batch))
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::geometry::Ray;

    fn path() -> &'static Path {
        Path::new("test.rays")
    }

    /// Rays with awkward values: ±0, infinities, NaNs with different payloads, subnormals.
    fn awkward(timed: bool) -> RayBatch {
        let nan_a = f32::from_bits(0x7fc0_0001);
        let nan_b = f32::from_bits(0xffa0_0000);
        let mut b = RayBatch::new(RayKind::Primary);
        let rays = [
            Ray::new(
                Vec3::new(0.0, -0.0, 1.5),
                Vec3::new(0.0, 0.0, -1.0),
                0.0,
                f32::INFINITY,
            ),
            Ray::new(
                Vec3::new(nan_a, 1e-40, -3.25e7),
                Vec3::new(nan_b, f32::NEG_INFINITY, 0.1),
                -0.0,
                f32::MAX,
            ),
            Ray::new(Vec3::splat(f32::MIN_POSITIVE), Vec3::X, 1e-4, 0.3),
        ];
        for (i, ray) in rays.into_iter().enumerate() {
            let ray = if timed {
                ray.at_time(0.25 * i as f32 + 0.125)
            } else {
                ray
            };
            b.push(ray, i as u32);
        }
        b
    }

    fn bits(b: &RayBatch) -> Vec<Vec<u32>> {
        let lanes = [
            &b.ox, &b.oy, &b.oz, &b.dx, &b.dy, &b.dz, &b.tmin, &b.tmax, &b.time,
        ];
        lanes
            .iter()
            .map(|lane| lane.iter().map(|v| v.to_bits()).collect())
            .collect()
    }

    /// Equal as values, any NaN equal to any NaN.
    fn same_values(a: &RayBatch, b: &RayBatch) -> bool {
        let canon = |v: u32| {
            if f32::from_bits(v).is_nan() {
                u32::MAX
            } else {
                v
            }
        };
        let (a, b) = (bits(a), bits(b));
        a.len() == b.len()
            && a.iter().zip(&b).all(|(x, y)| {
                x.len() == y.len() && x.iter().zip(y).all(|(&p, &q)| canon(p) == canon(q))
            })
    }

    #[test]
    fn binary_round_trip_is_bit_exact() {
        for timed in [false, true] {
            let rays = awkward(timed);
            let bytes = encode_binary(rays.view());
            assert_eq!(bytes.len(), HEADER_BYTES + 3 * if timed { 36 } else { 32 });
            let back = parse_rays(path(), &bytes).unwrap();
            assert_eq!(bits(&back), bits(&rays), "timed {timed}");
            assert_eq!(back.pixel, vec![0, 1, 2]);
            assert_eq!(back.kind(), RayKind::Primary);
        }
    }

    #[test]
    fn csv_round_trip_keeps_every_value_and_nan_as_nan() {
        for timed in [false, true] {
            let rays = awkward(timed);
            let text = encode_csv(rays.view());
            assert!(text.starts_with(if timed { CSV_HEADER_TIME } else { CSV_HEADER }));
            let back = parse_rays(path(), text.as_bytes()).unwrap();
            assert!(same_values(&back, &rays), "timed {timed}:\n{text}");
            // −0 survives CSV too.
            assert_eq!(back.oy[0].to_bits(), (-0.0f32).to_bits());
            assert!(back.ox[1].is_nan() && back.dx[1].is_nan());
        }
    }

    #[test]
    fn a_time_lane_of_zeros_is_no_time_lane() {
        let mut rays = awkward(false);
        rays.time = vec![0.0; rays.len()];
        let bytes = encode_binary(rays.view());
        assert_eq!(bytes[12], FLAG_TIME as u8);
        let back = parse_rays(path(), &bytes).unwrap();
        assert!(back.time.is_empty());
        // But a −0 time is kept, bit for bit.
        rays.time[1] = -0.0;
        let back = parse_rays(path(), &encode_binary(rays.view())).unwrap();
        assert_eq!(back.time[1].to_bits(), (-0.0f32).to_bits());
    }

    #[test]
    fn empty_files_of_either_kind() {
        let empty = RayBatch::new(RayKind::Primary);
        assert!(parse_rays(path(), &encode_binary(empty.view()))
            .unwrap()
            .is_empty());
        assert!(parse_rays(path(), encode_csv(empty.view()).as_bytes())
            .unwrap()
            .is_empty());
        let e = parse_rays(path(), b"").unwrap_err();
        assert_eq!(e.exit_code(), 2);
        assert!(e.to_string().contains("empty"), "{e}");
    }

    /// The byte offset an error message names.
    fn offset_of(e: &Error) -> usize {
        let text = e.to_string();
        let rest = text
            .split("byte offset ")
            .nth(1)
            .unwrap_or_else(|| panic!("{text}"));
        rest.split(':').next().unwrap().parse().unwrap()
    }

    #[test]
    fn truncation_at_every_byte_names_the_region_cut() {
        let bytes = encode_binary(awkward(true).view());
        for len in 1..bytes.len() {
            let e = parse_rays(path(), &bytes[..len]).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().starts_with("test.rays: byte offset"), "{e}");
            let region = match len {
                0..=7 => 0,
                8..=11 => 8,
                12..=15 => 12,
                16..=23 => 16,
                _ => HEADER_BYTES + (len - HEADER_BYTES) / 36 * 36,
            };
            assert_eq!(offset_of(&e), region, "cut at {len}: {e}");
        }
    }

    #[test]
    fn a_claimed_count_beyond_the_file_fails_before_allocating() {
        let mut bytes = encode_binary(awkward(false).view());
        for count in [1_000_000_000u64, u64::MAX, 4] {
            bytes[16..24].copy_from_slice(&count.to_le_bytes());
            let e = parse_rays(path(), &bytes).unwrap_err();
            assert_eq!(offset_of(&e), HEADER_BYTES + 3 * 32, "count {count}: {e}");
            assert!(e.to_string().contains(&format!("says {count} rays")), "{e}");
        }
        // Fewer rays than the file holds: the extra bytes are an error too.
        bytes[16..24].copy_from_slice(&2u64.to_le_bytes());
        let e = parse_rays(path(), &bytes).unwrap_err();
        assert_eq!(offset_of(&e), HEADER_BYTES + 2 * 32, "{e}");
    }

    #[test]
    fn bad_headers_name_their_field() {
        let good = encode_binary(awkward(false).view());
        let mut version = good.clone();
        version[8] = 2;
        assert_eq!(offset_of(&parse_rays(path(), &version).unwrap_err()), 8);
        let mut flags = good.clone();
        flags[12] = 4;
        assert_eq!(offset_of(&parse_rays(path(), &flags).unwrap_err()), 12);
        // Not the magic and not UTF-8: the first invalid byte.
        let e = parse_rays(path(), b"ox\xff\xfe").unwrap_err();
        assert_eq!(offset_of(&e), 2, "{e}");
    }

    #[test]
    fn malformed_csv_names_the_line() {
        let cases: &[(&str, &str)] = &[
            ("x,y,z\n", "test.rays:1:"),
            (
                "ox,oy,oz,dx,dy,dz,tmin,tmax\n0,0,0,0,0,1,0,inf\n0,0,0,0,0,1,0\n",
                "test.rays:3:",
            ),
            (
                "\nox,oy,oz,dx,dy,dz,tmin,tmax\n\n0,0,0,0,0,1,0,one\n",
                "test.rays:4: tmax",
            ),
            (
                "ox,oy,oz,dx,dy,dz,tmin,tmax,time\n0,0,0,0,0,1,0,1\n",
                "test.rays:2: expected 9",
            ),
        ];
        for (text, needle) in cases {
            let e = parse_rays(path(), text.as_bytes()).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            assert!(e.to_string().starts_with(needle), "{text:?}: {e}");
        }
        let ok = "ox, oy, oz, dx, dy, dz, tmin, tmax\r\n1,2,3,NaN,-inf,0,0,1e30\r\n\r\n";
        let rays = parse_rays(path(), ok.as_bytes()).unwrap();
        assert_eq!(rays.len(), 1);
        assert!(rays.dx[0].is_nan() && rays.dy[0] == f32::NEG_INFINITY);
        // A byte-order mark before the header was once "not a ray file".
        let bom = "\u{feff}ox,oy,oz,dx,dy,dz,tmin,tmax\n0.25,0.5,1,0,0,-1,0,inf\n";
        let rays = parse_rays(path(), bom.as_bytes()).unwrap();
        assert_eq!(
            (rays.len(), rays.ox[0], rays.oy[0], rays.dz[0]),
            (1, 0.25, 0.5, -1.0)
        );
    }

    #[test]
    fn hits_and_occlusion_csv() {
        let hit = Hit {
            t: 1.5,
            prim: 7,
            u: 0.25,
            v: 0.125,
        };
        assert_eq!(
            hits_csv(&[hit, Hit::MISS]),
            "ray,hit,t,prim,u,v\n0,1,1.5,7,0.25,0.125\n1,0,inf,-1,0,0\n"
        );
        assert_eq!(occlusion_csv(&[true, false]), "ray,occluded\n0,1\n1,0\n");
    }

    #[test]
    fn files_round_trip_through_the_file_system() {
        let dir = std::env::temp_dir().join(format!("raylab-ray-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let rays = awkward(true);
        for (name, format) in [
            ("a.csv", RayFileFormat::Binary),
            ("a.rays", RayFileFormat::Csv),
        ] {
            // The content decides: a CSV named .rays reads as CSV and vice versa.
            let path = dir.join(name);
            write_rays(&path, rays.view(), format).unwrap();
            assert!(same_values(&read_rays(&path).unwrap(), &rays));
        }
        let missing = read_rays(&dir.join("missing.rays")).unwrap_err();
        assert_eq!(missing.exit_code(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
