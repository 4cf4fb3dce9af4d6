//! A shard's heat-map panels on disk (`heatmaps.bin`). A shard of a sweep draws no figures (they
//! would show a part), so it writes what it measured for them — each scene's shaded first frame
//! and every tracer's maps, already shrunk to their panels (`heatmap_set::for_figure`) — and
//! `raylab merge` reads every shard's back and draws the sweep's figures, the same PNGs an
//! unsharded run writes.
//!
//! Little-endian. A string is a u32 byte length and its UTF-8 bytes.
//!
//! | part         | fields                                                                                   |
//! |--------------|------------------------------------------------------------------------------------------|
//! | header       | magic `RAYLABHM`, u32 version 1, u32 shaded frames, u32 panels                          |
//! | shaded frame | u32 scene, string name, u32 width, u32 height, width·height × 3 f32 (linear RGB)        |
//! | panel        | u32 scene, string ray kind, u32 instance, string tracer, u32 maps (`NO_COUNTS`: none)   |
//! | map          | string cost, u32 width, u32 height, width·height u64 totals, width·height u64 divisors |

use std::io::{BufWriter, Write};
use std::path::Path;

use glam::Vec3;

use crate::error::{Error, Result};
use crate::geometry::RayKind;
use crate::render::cost_map::{Cost, CostMap};
use crate::render::image::Image;

use super::heatmap_set::{HeatmapPanel, HeatmapSet, ShadedFrame};

const MAGIC: &[u8; 8] = b"RAYLABHM";
const VERSION: u32 = 1;
/// A panel's map count for a production baseline, which reports no counts.
const NO_COUNTS: u32 = u32::MAX;

/// Writes `set` to `path`.
pub fn write(path: &Path, set: &HeatmapSet) -> Result<()> {
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut out = BufWriter::new(file);
    encode(&mut out, set)
        .and_then(|()| out.flush())
        .map_err(|e| Error::io(path, e))
}

fn encode(out: &mut impl Write, set: &HeatmapSet) -> std::io::Result<()> {
    let count = |n: usize| u32::try_from(n).expect("fewer than 2³² panels");
    out.write_all(MAGIC)?;
    for n in [VERSION, count(set.shaded.len()), count(set.panels.len())] {
        out.write_all(&n.to_le_bytes())?;
    }
    let string = |out: &mut dyn Write, s: &str| -> std::io::Result<()> {
        out.write_all(&count(s.len()).to_le_bytes())?;
        out.write_all(s.as_bytes())
    };
    for frame in &set.shaded {
        out.write_all(&count(frame.scene).to_le_bytes())?;
        string(out, &frame.name)?;
        out.write_all(&frame.image.width.to_le_bytes())?;
        out.write_all(&frame.image.height.to_le_bytes())?;
        for p in &frame.image.pixels {
            for c in p.to_array() {
                out.write_all(&c.to_le_bytes())?;
            }
        }
    }
    for panel in &set.panels {
        out.write_all(&count(panel.scene).to_le_bytes())?;
        string(out, panel.kind.name())?;
        out.write_all(&count(panel.instance).to_le_bytes())?;
        string(out, &panel.tracer)?;
        let Some(maps) = &panel.maps else {
            out.write_all(&NO_COUNTS.to_le_bytes())?;
            continue;
        };
        out.write_all(&count(maps.len()).to_le_bytes())?;
        for map in maps {
            string(out, map.cost.name())?;
            out.write_all(&map.width.to_le_bytes())?;
            out.write_all(&map.height.to_le_bytes())?;
            for v in map.total.iter().chain(&map.per) {
                out.write_all(&v.to_le_bytes())?;
            }
        }
    }
    Ok(())
}

/// Reads the set `write` wrote to `path`. A file that is not one, is cut short, has bytes past
/// its end or names an unknown ray kind or cost is an error naming the file and the byte.
pub fn read(path: &Path) -> Result<HeatmapSet> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let mut r = Reader {
        path,
        bytes: &bytes,
        at: 0,
    };
    if r.take(MAGIC.len(), "the magic")? != MAGIC {
        return Err(r.error(0, "not a raylab heat-map file (no RAYLABHM magic)"));
    }
    let version = r.u32("the version")?;
    if version != VERSION {
        return Err(r.error(8, format!("version {version}; this raylab reads {VERSION}")));
    }
    let (frames, panels) = (r.u32("the frame count")?, r.u32("the panel count")?);
    let mut set = HeatmapSet::default();
    for _ in 0..frames {
        let scene = r.u32("a frame's scene")? as usize;
        let name = r.string("a frame's name")?;
        let (width, height) = (r.u32("a frame's width")?, r.u32("a frame's height")?);
        let floats = r.values(width, height, 3 * 4, "a frame's pixels")?;
        let pixels = floats
            .chunks_exact(12)
            .map(|p| {
                let c = |i: usize| f32::from_le_bytes(p[4 * i..4 * i + 4].try_into().unwrap());
                Vec3::new(c(0), c(1), c(2))
            })
            .collect();
        let image = Image {
            width,
            height,
            pixels,
        };
        set.shaded.push(ShadedFrame { scene, name, image });
    }
    for _ in 0..panels {
        let scene = r.u32("a panel's scene")? as usize;
        let at = r.at;
        let kind = r.string("a panel's ray kind")?;
        let kind = RayKind::parse(&kind)
            .ok_or_else(|| r.error(at, format!("unknown ray kind {kind:?}")))?;
        let instance = r.u32("a panel's instance")? as usize;
        let tracer = r.string("a panel's tracer")?;
        let maps = match r.u32("a panel's map count")? {
            NO_COUNTS => None,
            n => Some((0..n).map(|_| r.map()).collect::<Result<Vec<_>>>()?),
        };
        set.panels.push(HeatmapPanel {
            scene,
            kind,
            instance,
            tracer,
            maps,
        });
    }
    if r.at != bytes.len() {
        return Err(r.error(r.at, "bytes past the last panel"));
    }
    Ok(set)
}

/// A cursor over the file's bytes that names the file and the byte of whatever is wrong.
struct Reader<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn error(&self, at: usize, message: impl std::fmt::Display) -> Error {
        Error::input(self.path, None, format!("byte {at}: {message}"))
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| self.error(self.at, format!("the file ends in {what}")))?;
        let bytes: &'a [u8] = self.bytes;
        let taken = &bytes[self.at..end];
        self.at = end;
        Ok(taken)
    }

    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(self.take(4, what)?.try_into().unwrap()))
    }

    fn string(&mut self, what: &str) -> Result<String> {
        let at = self.at;
        let n = self.u32(what)? as usize;
        let bytes = self.take(n, what)?;
        String::from_utf8(bytes.to_vec()).map_err(|_| self.error(at, format!("{what}: not UTF-8")))
    }

    /// The bytes of `width × height` values of `size` bytes each (checked against the file's
    /// length before anything is allocated).
    fn values(&mut self, width: u32, height: u32, size: usize, what: &str) -> Result<&'a [u8]> {
        let n = (width as usize)
            .checked_mul(height as usize)
            .and_then(|n| n.checked_mul(size))
            .ok_or_else(|| self.error(self.at, format!("{what}: {width}×{height} is too large")))?;
        self.take(n, what)
    }

    fn map(&mut self) -> Result<CostMap> {
        let at = self.at;
        let cost = self.string("a map's cost")?;
        let cost = cost
            .parse::<Cost>()
            .map_err(|_| self.error(at, format!("unknown cost {cost:?}")))?;
        let (width, height) = (self.u32("a map's width")?, self.u32("a map's height")?);
        let mut column = |what: &str| -> Result<Vec<u64>> {
            let bytes = self.values(width, height, 8, what)?;
            Ok(bytes
                .chunks_exact(8)
                .map(|v| u64::from_le_bytes(v.try_into().unwrap()))
                .collect())
        };
        let total = column("a map's totals")?;
        let per = column("a map's divisors")?;
        Ok(CostMap {
            cost,
            width,
            height,
            total,
            per,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> std::path::PathBuf {
        std::env::temp_dir().join(format!("raylab-heatmap-file-{name}-{}", std::process::id()))
    }

    fn a_set() -> HeatmapSet {
        let map = |cost, width: u32, height: u32| CostMap {
            cost,
            width,
            height,
            total: (0..u64::from(width * height))
                .map(|i| i * 3 + u64::MAX / 2)
                .collect(),
            per: (0..u64::from(width * height)).map(|i| i % 2).collect(),
        };
        let image = Image {
            width: 2,
            height: 3,
            pixels: (0..6)
                .map(|i| Vec3::new(i as f32, -0.5, f32::MAX))
                .collect(),
        };
        HeatmapSet {
            shaded: vec![ShadedFrame {
                scene: 1,
                name: "rings-16".into(),
                image,
            }],
            panels: vec![
                HeatmapPanel {
                    scene: 1,
                    kind: RayKind::SoftShadow,
                    instance: 4,
                    tracer: "packet[packet=16]".into(),
                    maps: Some(vec![map(Cost::Box, 3, 2), map(Cost::Lanes, 1, 1)]),
                },
                HeatmapPanel {
                    scene: 1,
                    kind: RayKind::Primary,
                    instance: 0,
                    tracer: "embree3-1".into(),
                    maps: None,
                },
                HeatmapPanel {
                    scene: 0,
                    kind: RayKind::Shadow,
                    instance: 2,
                    tracer: "mft".into(),
                    maps: Some(vec![]),
                },
            ],
        }
    }

    #[test]
    fn a_set_reads_back_as_written() {
        let path = scratch("round");
        let set = a_set();
        write(&path, &set).unwrap();
        assert_eq!(read(&path).unwrap(), set);
        let _ = std::fs::remove_file(&path);
    }

    #[test]
    fn a_damaged_file_is_an_error_naming_the_file_and_byte() {
        let path = scratch("damaged");
        write(&path, &a_set()).unwrap();
        let good = std::fs::read(&path).unwrap();
        let fails = |bytes: &[u8]| {
            std::fs::write(&path, bytes).unwrap();
            let e = read(&path).unwrap_err();
            assert_eq!(e.exit_code(), 2);
            let e = e.to_string();
            assert!(e.contains(&path.display().to_string()), "{e}");
            e
        };
        // Cut short anywhere: in the header, in a frame, in a map.
        for cut in [5, 30, good.len() - 1] {
            let e = fails(&good[..cut]);
            assert!(e.contains("the file ends in"), "{e}");
        }
        let mut longer = good.clone();
        longer.push(0);
        assert!(fails(&longer).contains(&format!("byte {}: bytes past", good.len())));
        let mut magic = good.clone();
        magic[0] = b'X';
        assert!(fails(&magic).contains("byte 0: not a raylab heat-map file"));
        // An absurd frame size is refused before anything is allocated. The first frame's
        // width is at byte 20 (header) + 4 (scene) + 4 + 8 ("rings-16").
        let mut huge = good.clone();
        huge[36..44].copy_from_slice(&[0xff; 8]);
        assert!(fails(&huge).contains("a frame's pixels"));
        let kind_at = good.windows(11).position(|w| w == b"soft_shadow").unwrap();
        let mut kind = good.clone();
        kind[kind_at] = b'x';
        assert!(fails(&kind).contains("unknown ray kind \"xoft_shadow\""));
        let _ = std::fs::remove_file(&path);
    }
}
