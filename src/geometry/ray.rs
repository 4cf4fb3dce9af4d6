//! Rays and ray batches. A batch is structure-of-arrays so that packet and stream tracers can load
//! lanes directly; every tracer receives the very same batch ("same rays for everyone").

use glam::Vec3;

use crate::geometry::CameraGrid;

/// The largest coordinate magnitude raylab traces: Embree's `FLT_LARGE`, beyond which its ray
/// validity check rejects a ray (the Debian build asserts and aborts). Scene files with vertices
/// beyond it are refused (`scene::loaders`): Embree could not check their hits, and obvhs's
/// builder panics on scenes a few times larger.
pub const LARGEST_COORDINATE: f32 = 1.844e18;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
    /// When the ray is cast, in [0, 1) of the shutter interval (motion blur); 0 for rays of a
    /// single instant. Only tracers over moving geometry read it.
    pub time: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Ray {
            origin,
            dir,
            tmin,
            tmax,
            time: 0.0,
        }
    }

    /// The same ray cast at `time` of the shutter interval.
    pub fn at_time(self, time: f32) -> Self {
        Ray { time, ..self }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }

    /// Whether the ray asks a defined question: finite origin and direction, a non-zero
    /// direction, a finite `tmin ≥ 0` (Embree's rule; its ray check aborts on a negative one)
    /// and `tmin < tmax` (`tmax` may be +∞). Every tracer answers any other ray with a miss
    /// (not occluded): NaN or infinite components, a zero direction, a negative `tmin`, an
    /// empty or NaN interval.
    pub fn is_well_formed(&self) -> bool {
        self.origin.is_finite()
            && self.dir.is_finite()
            && self.dir != Vec3::ZERO
            && self.tmin.is_finite()
            && self.tmin >= 0.0
            && self.tmin < self.tmax
    }
}

/// What a batch of rays is for; counters and CSV rows are kept per kind.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize,
)]
pub enum RayKind {
    Primary,
    Shadow,
    Diffuse,
    /// Perfect mirror reflection (Whitted).
    Reflection,
    /// Refraction through a dielectric (Whitted).
    Refraction,
    /// Shadow rays from shading points to samples on an area light (`tracers::visibility`).
    SoftShadow,
}

impl RayKind {
    pub const ALL: [RayKind; 6] = [
        RayKind::Primary,
        RayKind::Shadow,
        RayKind::Diffuse,
        RayKind::Reflection,
        RayKind::Refraction,
        RayKind::SoftShadow,
    ];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
            RayKind::Reflection => "reflection",
            RayKind::Refraction => "refraction",
            RayKind::SoftShadow => "soft_shadow",
        }
    }

    /// Shadow rays ask "is anything in between" (occlusion); the others ask for the closest hit.
    pub fn is_occlusion(self) -> bool {
        matches!(self, RayKind::Shadow | RayKind::SoftShadow)
    }

    pub fn parse(name: &str) -> Option<RayKind> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }
}

/// Closest-hit result. `prim` is the scene triangle index, `Hit::MISS.prim` when nothing was hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

impl Hit {
    pub const NO_PRIM: u32 = u32::MAX;
    pub const MISS: Hit = Hit {
        t: f32::INFINITY,
        prim: Hit::NO_PRIM,
        u: 0.0,
        v: 0.0,
    };

    pub fn is_hit(&self) -> bool {
        self.prim != Hit::NO_PRIM
    }
}

/// An owned structure-of-arrays batch of rays of one kind. `pixel[i]` is the image pixel the ray
/// descends from (its camera ancestor), used to assemble images and to group packets by screen
/// position.
#[derive(Clone, Debug, Default)]
pub struct RayBatch {
    pub kind: Option<RayKind>,
    pub ox: Vec<f32>,
    pub oy: Vec<f32>,
    pub oz: Vec<f32>,
    pub dx: Vec<f32>,
    pub dy: Vec<f32>,
    pub dz: Vec<f32>,
    pub tmin: Vec<f32>,
    pub tmax: Vec<f32>,
    pub pixel: Vec<u32>,
    /// Explicit packets (packet assembly, Boulos et al. 2007 §3.2): `packet_start[i]` says ray `i`
    /// begins a packet. Empty when the batch has none: packet tracers then group consecutive rays
    /// (camera rays come in Morton-ordered tiles, so consecutive means a screen block).
    pub packet_start: Vec<bool>,
    /// Ray times (`Ray::time`, motion blur). Empty when every ray is at time 0, as in every batch
    /// of a single instant; filled from the first ray with a non-zero time on.
    pub time: Vec<f32>,
    /// The pinhole camera every ray of the batch comes from: `Some` only while ray `i` is
    /// `camera.pixel_ray(pixel[i])` for every `i` (`push_camera_ray`; any other push clears it,
    /// and code editing rays in place must too). Multi-frusta tracing regenerates such rays on
    /// demand instead of reading them.
    pub camera: Option<Box<CameraGrid>>,
}

impl RayBatch {
    pub fn new(kind: RayKind) -> Self {
        RayBatch {
            kind: Some(kind),
            ..Default::default()
        }
    }

    pub fn with_capacity(kind: RayKind, n: usize) -> Self {
        let v = || Vec::with_capacity(n);
        RayBatch {
            kind: Some(kind),
            ox: v(),
            oy: v(),
            oz: v(),
            dx: v(),
            dy: v(),
            dz: v(),
            tmin: v(),
            tmax: v(),
            pixel: Vec::with_capacity(n),
            packet_start: Vec::new(),
            time: Vec::new(),
            camera: None,
        }
    }

    pub fn kind(&self) -> RayKind {
        self.kind.unwrap_or(RayKind::Primary)
    }

    /// The rays' eight f32 columns (origin, direction, tmin, tmax), for code that treats them
    /// alike.
    pub(crate) fn columns_mut(&mut self) -> [&mut Vec<f32>; 8] {
        [
            &mut self.ox,
            &mut self.oy,
            &mut self.oz,
            &mut self.dx,
            &mut self.dy,
            &mut self.dz,
            &mut self.tmin,
            &mut self.tmax,
        ]
    }

    /// Empty, of `kind`, keeping the allocations (a buffer refilled per chunk).
    pub fn clear(&mut self, kind: RayKind) {
        self.kind = Some(kind);
        for v in self.columns_mut() {
            v.clear();
        }
        self.time.clear();
        self.pixel.clear();
        self.packet_start.clear();
        self.camera = None;
    }

    /// The batch's first `n` rays (all of them when it has fewer), in a batch of its kind: a
    /// sample of a ray file (`raylab bench --sample`).
    pub fn first(&self, n: usize) -> RayBatch {
        let mut sample = RayBatch {
            kind: self.kind,
            ..RayBatch::default()
        };
        for i in 0..n.min(self.len()) {
            sample.push(self.ray(i), self.pixel[i]);
        }
        sample
    }

    pub fn push(&mut self, ray: Ray, pixel: u32) {
        self.camera = None;
        self.push_ray(ray, pixel);
    }

    /// Pushes `grid`'s ray through the centre of pixel id `pixel` (starting an explicit packet
    /// with `packet_start`); the batch keeps `grid` as its camera while all its rays are such.
    pub fn push_camera_ray(&mut self, grid: &CameraGrid, pixel: u32, packet_start: bool) {
        let camera = match self.camera.take() {
            Some(camera) if *camera == *grid => Some(camera),
            _ if self.is_empty() => Some(Box::new(*grid)),
            _ => None,
        };
        let ray = grid.pixel_ray(pixel);
        if packet_start {
            self.push_packet_start(ray, pixel);
        } else {
            self.push(ray, pixel);
        }
        self.camera = camera;
    }

    fn push_ray(&mut self, ray: Ray, pixel: u32) {
        if !self.packet_start.is_empty() {
            self.packet_start.push(false);
        }
        self.push_lanes(ray, pixel);
    }

    fn push_lanes(&mut self, ray: Ray, pixel: u32) {
        self.ox.push(ray.origin.x);
        self.oy.push(ray.origin.y);
        self.oz.push(ray.origin.z);
        self.dx.push(ray.dir.x);
        self.dy.push(ray.dir.y);
        self.dz.push(ray.dir.z);
        self.tmin.push(ray.tmin);
        self.tmax.push(ray.tmax);
        self.pixel.push(pixel);
        if !self.time.is_empty() {
            self.time.push(ray.time);
        } else if ray.time != 0.0 {
            // The first timed ray: the rays before it were all at time 0.
            self.time.resize(self.len() - 1, 0.0);
            self.time.push(ray.time);
        }
    }

    /// Pushes `ray` as the first ray of a new explicit packet; from then on the batch has explicit
    /// packets, and the rays pushed so far form one packet.
    pub fn push_packet_start(&mut self, ray: Ray, pixel: u32) {
        self.camera = None;
        if self.packet_start.is_empty() {
            // Switch to explicit packets: the rays so far (if any) form the first one.
            self.packet_start.resize(self.len(), false);
            if let Some(first) = self.packet_start.first_mut() {
                *first = true;
            }
            self.packet_start.push(true);
            self.push_lanes(ray, pixel);
            return;
        }
        self.push_ray(ray, pixel);
        *self.packet_start.last_mut().expect("just pushed") = true;
    }

    pub fn len(&self) -> usize {
        self.ox.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ox.is_empty()
    }

    pub fn ray(&self, i: usize) -> Ray {
        self.view().ray(i)
    }

    pub fn view(&self) -> Rays<'_> {
        Rays {
            ox: &self.ox,
            oy: &self.oy,
            oz: &self.oz,
            dx: &self.dx,
            dy: &self.dy,
            dz: &self.dz,
            tmin: &self.tmin,
            tmax: &self.tmax,
            packet_start: &self.packet_start,
            time: &self.time,
            kind: self.kind(),
            pixel: &self.pixel,
            camera: self.camera.as_deref(),
        }
    }
}

/// A borrowed view of (part of) a batch: what tracers receive. Splitting a view is free, so the
/// runner hands each thread a contiguous chunk.
#[derive(Clone, Copy, Debug)]
pub struct Rays<'a> {
    pub ox: &'a [f32],
    pub oy: &'a [f32],
    pub oz: &'a [f32],
    pub dx: &'a [f32],
    pub dy: &'a [f32],
    pub dz: &'a [f32],
    pub tmin: &'a [f32],
    pub tmax: &'a [f32],
    /// As `RayBatch::packet_start`: empty, or one flag per ray.
    pub packet_start: &'a [bool],
    /// As `RayBatch::time`: empty (every ray at time 0), or one time per ray.
    pub time: &'a [f32],
    /// What the rays are for (a tracer may tune itself to it: Embree's coherence hint).
    pub kind: RayKind,
    /// As `RayBatch::pixel`.
    pub pixel: &'a [u32],
    /// As `RayBatch::camera`.
    pub camera: Option<&'a CameraGrid>,
}

impl<'a> Rays<'a> {
    pub fn len(&self) -> usize {
        self.ox.len()
    }

    pub fn is_empty(&self) -> bool {
        self.ox.is_empty()
    }

    #[inline(always)]
    pub fn ray(&self, i: usize) -> Ray {
        Ray {
            origin: Vec3::new(self.ox[i], self.oy[i], self.oz[i]),
            dir: Vec3::new(self.dx[i], self.dy[i], self.dz[i]),
            tmin: self.tmin[i],
            tmax: self.tmax[i],
            time: self.time(i),
        }
    }

    /// The time of ray `i` (`Ray::time`).
    #[inline(always)]
    pub fn time(&self, i: usize) -> f32 {
        if self.time.is_empty() {
            0.0
        } else {
            self.time[i]
        }
    }

    /// The sub-view `range` of this view.
    pub fn slice(&self, range: std::ops::Range<usize>) -> Rays<'a> {
        Rays {
            ox: &self.ox[range.clone()],
            oy: &self.oy[range.clone()],
            oz: &self.oz[range.clone()],
            dx: &self.dx[range.clone()],
            dy: &self.dy[range.clone()],
            dz: &self.dz[range.clone()],
            tmin: &self.tmin[range.clone()],
            tmax: &self.tmax[range.clone()],
            packet_start: if self.packet_start.is_empty() {
                &[]
            } else {
                &self.packet_start[range.clone()]
            },
            time: if self.time.is_empty() {
                &[]
            } else {
                &self.time[range.clone()]
            },
            kind: self.kind,
            pixel: &self.pixel[range],
            camera: self.camera,
        }
    }

    /// Asks the CPU to bring rays `range` (origins, directions, intervals, times) into its
    /// caches while it works on earlier ones: a packet tracer calls it for the next packet, whose
    /// rays would otherwise arrive from memory only when it loads them (a packet's arrays are
    /// too short, and the traversal in between too long, for the hardware prefetcher).
    #[inline(always)]
    pub fn prefetch(&self, range: std::ops::Range<usize>) {
        let arrays = [self.ox, self.oy, self.oz, self.dx, self.dy, self.dz];
        for array in arrays.into_iter().chain([self.tmin, self.tmax, self.time]) {
            if let Some(rays) = array.get(range.clone()) {
                prefetch(rays);
            }
        }
    }

    /// Whether the rays come in explicit packets (`RayBatch::packet_start`).
    pub fn has_explicit_packets(&self) -> bool {
        !self.packet_start.is_empty()
    }

    /// The packets of this view, of at most `max` rays each: consecutive runs of `max` rays, or,
    /// with explicit packets, each explicit packet cut into runs of at most `max`.
    pub fn packets(&self, max: usize) -> impl Iterator<Item = std::ops::Range<usize>> + 'a {
        assert!(max > 0, "packets of at least one ray");
        let (len, starts) = (self.len(), self.packet_start);
        let mut begin = 0;
        std::iter::from_fn(move || {
            if begin >= len {
                return None;
            }
            let limit = (begin + max).min(len);
            let end = if starts.is_empty() {
                limit
            } else {
                (begin + 1..limit).find(|&i| starts[i]).unwrap_or(limit)
            };
            let packet = begin..end;
            begin = end;
            Some(packet)
        })
    }
}

/// Prefetches every cache line of `data` into all cache levels (a hint: no effect on results).
#[inline(always)]
pub fn prefetch<T>(data: &[T]) {
    use crate::lanes::prefetch::{line, Level, LINE};
    let start = data.as_ptr() as *const u8;
    for offset in (0..std::mem::size_of_val(data)).step_by(LINE) {
        line(start.wrapping_add(offset), Level::Far);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ray(x: f32) -> Ray {
        Ray::new(Vec3::new(x, 0.0, 0.0), Vec3::Z, 0.0, 1.0)
    }

    #[test]
    fn uniform_batches_are_cut_into_runs_of_max() {
        let mut b = RayBatch::new(RayKind::Primary);
        (0..10).for_each(|i| b.push(ray(i as f32), i));
        let packets: Vec<_> = b.view().packets(4).collect();
        assert_eq!(packets, vec![0..4, 4..8, 8..10]);
        assert!(!b.view().has_explicit_packets());
    }

    #[test]
    fn explicit_packets_are_kept_and_cut_at_max() {
        let mut b = RayBatch::new(RayKind::Shadow);
        b.push(ray(0.0), 0);
        b.push(ray(1.0), 1);
        b.push_packet_start(ray(2.0), 2);
        (3..9).for_each(|i| b.push(ray(i as f32), i));
        b.push_packet_start(ray(9.0), 9);
        assert_eq!(b.packet_start.len(), 10);
        let packets: Vec<_> = b.view().packets(4).collect();
        assert_eq!(packets, vec![0..2, 2..6, 6..9, 9..10]);
        // A sub-view keeps its part of the flags.
        let tail: Vec<_> = b.view().slice(5..10).packets(8).collect();
        assert_eq!(tail, vec![0..4, 4..5]);
    }

    #[test]
    fn time_lane_appears_with_the_first_timed_ray() {
        let mut b = RayBatch::new(RayKind::Primary);
        b.push(ray(0.0), 0);
        assert!(b.time.is_empty() && b.view().time(0) == 0.0);
        b.push_packet_start(ray(1.0).at_time(0.25), 1);
        b.push(ray(2.0), 2);
        assert_eq!(b.time, vec![0.0, 0.25, 0.0]);
        assert_eq!(b.ray(1).time, 0.25);
        assert_eq!(b.view().slice(1..3).time, &[0.25, 0.0]);
    }
}
