//! Rays and ray batches. A batch is structure-of-arrays so that packet and stream tracers can load
//! lanes directly; every tracer receives the very same batch ("same rays for everyone").

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
    pub tmin: f32,
    pub tmax: f32,
}

impl Ray {
    pub fn new(origin: Vec3, dir: Vec3, tmin: f32, tmax: f32) -> Self {
        Ray {
            origin,
            dir,
            tmin,
            tmax,
        }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// What a batch of rays is for; counters and CSV rows are kept per kind.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum RayKind {
    Primary,
    Shadow,
    Diffuse,
}

impl RayKind {
    pub const ALL: [RayKind; 3] = [RayKind::Primary, RayKind::Shadow, RayKind::Diffuse];

    pub fn name(self) -> &'static str {
        match self {
            RayKind::Primary => "primary",
            RayKind::Shadow => "shadow",
            RayKind::Diffuse => "diffuse",
        }
    }

    /// Shadow rays ask "is anything in between" (occlusion); the others ask for the closest hit.
    pub fn is_occlusion(self) -> bool {
        matches!(self, RayKind::Shadow)
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
        }
    }

    pub fn kind(&self) -> RayKind {
        self.kind.unwrap_or(RayKind::Primary)
    }

    pub fn push(&mut self, ray: Ray, pixel: u32) {
        self.ox.push(ray.origin.x);
        self.oy.push(ray.origin.y);
        self.oz.push(ray.origin.z);
        self.dx.push(ray.dir.x);
        self.dy.push(ray.dir.y);
        self.dz.push(ray.dir.z);
        self.tmin.push(ray.tmin);
        self.tmax.push(ray.tmax);
        self.pixel.push(pixel);
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
            tmax: &self.tmax[range],
        }
    }
}
