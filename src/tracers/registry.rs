//! The list of tracers by name, as data: which structure each traverses, which parameters it
//! reads, how to make one from a built structure, whether it traces moving geometry, and how many
//! rays it wants per work chunk. Adding a tracer is one entry here.

#[cfg(embree4)]
use crate::accel::embree::Embree4;
use crate::accel::embree::{Embree3, EmbreeConfig, EMBREE4_BUILT, EMBREE4_HINT};
use std::ops::Range;

#[cfg(tinybvh)]
use crate::accel::TinyLayout;
use crate::accel::{Accel, AccelKind, BvhOfWidth};
use crate::error::{Error, Result};
use crate::geometry::{Fast, Hit, RayKind, Rays, Robust};
use crate::scene::{Frame, Mesh};
use crate::stats::Counters;
use crate::tracers::chunked::CHUNK_RAYS;
use crate::tracers::coherent_grid::{CgtConfig, CgtTracer};
use crate::tracers::embree::{
    Coherence, EmbreeTracer, Packets16, Packets4, Packets8, Single, Stream, Submission,
};
use crate::tracers::multi_frusta::{MftConfig, MftTracer};
use crate::tracers::packet::{PacketConfig, PacketTracer, TreeWidth};
use crate::tracers::stream::{StreamConfig, StreamTracer};
#[cfg(tinybvh)]
use crate::tracers::tinybvh::{tile::TileConfig, SingleTracer, TileTracer};
use crate::tracers::{
    grid_dda::GridDdaTracer, obvhs::ObvhsTracer, reference::ReferenceTracer, wide_single,
    wide_single::WideSingleTracer, Params, StagedRays, Tracer, VisibilityQuery,
};

/// What a tracer is in a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Role {
    /// From scratch, after a paper (or our own variant of one): what the comparisons are about,
    /// "ours" in the summary.
    Paper,
    /// A production library (Embree, obvhs): what ours are measured against.
    Baseline,
    /// Our reference: the plain single-ray tracer whose hits generate secondary rays.
    Reference,
}

/// A tracer's parameters, parsed and checked (`TracerInfo::parse`): what `TracerInfo::make`
/// takes, one variant per tracer family.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TracerConfig {
    /// A tracer with no parameters of its own (obvhs, grid-dda).
    Plain,
    /// `robust`: conservative slabs and watertight triangles, or plain ones (`ROBUST`).
    Reference {
        robust: bool,
    },
    WideSingle {
        width: wide_single::Width,
        robust: bool,
    },
    GridDda {
        robust: bool,
    },
    /// Every Embree entry point: the coherence hint (`context`).
    Embree(Coherence),
    Cgt(CgtConfig),
    Packet {
        config: PacketConfig,
        width: TreeWidth,
    },
    Mft(MftConfig),
    Stream(StreamConfig),
    /// `tinybvh-256`: which of tinybvh's packet kernels.
    #[cfg(tinybvh)]
    TinyTile(TileConfig),
}

impl TracerConfig {
    /// Whether our tracer runs the robust tests (its `robust`); `None` for a library's tracer,
    /// whose tests its library or structure decides (`TracerInfo::robust_tests`).
    pub fn robust(&self) -> Option<bool> {
        match *self {
            TracerConfig::Reference { robust }
            | TracerConfig::WideSingle { robust, .. }
            | TracerConfig::GridDda { robust } => Some(robust),
            TracerConfig::Cgt(c) => Some(c.robust),
            TracerConfig::Packet { config, .. } => Some(config.robust),
            TracerConfig::Mft(c) => Some(c.robust),
            TracerConfig::Stream(c) => Some(c.robust),
            TracerConfig::Plain | TracerConfig::Embree(_) => None,
            #[cfg(tinybvh)]
            TracerConfig::TinyTile(_) => None,
        }
    }

    /// Children per node of the BVH the tracer walks: 2 (the binary tree; also every tracer
    /// over another structure), or 4 or 8 for a wide tree (`accel::WideTree`).
    pub fn tree_width(&self) -> usize {
        match *self {
            TracerConfig::WideSingle { width, .. } => width.children(),
            TracerConfig::Packet { width, .. } => width.children(),
            TracerConfig::Mft(c) => c.width,
            TracerConfig::Stream(c) if c.single > 0 => c.single_tree.children(),
            _ => 2,
        }
    }
}

/// Checks a tracer's own parameters and returns its typed configuration.
type Parse = fn(&Params) -> Result<TracerConfig>;

/// Makes a tracer from its configuration and a structure of its `AccelKind`.
type Make = fn(&TracerConfig, &Accel) -> Result<Box<dyn Tracer>>;

pub struct TracerInfo {
    pub name: &'static str,
    pub role: Role,
    pub accel: AccelKind,
    /// Parameters the tracer itself reads (the structure's own are in `AccelKind::params`).
    pub params: &'static [&'static str],
    pub about: &'static str,
    pub parse: Parse,
    /// Takes what `parse` returned.
    pub make: Make,
    /// Whether it counts its own box and triangle tests (`Kernel::COUNTS_INTERNALS`; Embree
    /// counts only rays).
    pub counts_internals: bool,
    /// Whether it traces moving geometry at each ray's time (motion blur); a moving structure
    /// handed to any other tracer is refused rather than answered for the wrong instant.
    pub motion_blur: bool,
    /// Rays per work chunk (`tracers::chunked`): a multiple of 1024, so no aligned n×n block of
    /// camera rays (n ≤ 32) straddles two chunks. A stream tracer wants far more than a packet
    /// tracer.
    pub chunk_rays: usize,
    /// Its family's source, paths under `src/` (a folder or a file), with the families it builds
    /// on: what a run that measured it depends on besides the shared core
    /// (`experiment::record::provenance`), so only a change here makes that run stale.
    pub source: &'static [&'static str],
    /// The configurations the test suites check it in, its defaults (`&[]`) first, then one per
    /// code path worth a check of its own: agreement with Embree, the light-visibility bits and,
    /// for ours, `robust = false` against the fast reference (tests/suite). The suites iterate
    /// the registry, so a new tracer is tested from its entry alone.
    pub test_configs: &'static [Settings],
    /// Whether and how the shorthand entries `embree-best` and `baseline-best` run it.
    pub best: BaselineBest,
}

/// Parameter settings given in code: (key, value) pairs.
pub type Settings = &'static [(&'static str, &'static str)];

/// Parameter axes given in code: (key, values).
pub type Axes = &'static [(&'static str, &'static [&'static str])];

/// A baseline's part in the shorthand entries of an experiment file: `embree-best` runs every
/// `Sweep` tracer, `baseline-best` those and every `Fixed` one, so that runs.csv's
/// `baseline_best` is the fastest production library on the rays.
#[derive(Clone, Copy, Debug)]
pub enum BaselineBest {
    /// Not in either (our tracers).
    Not,
    /// Swept over these axes unless the entry gives them (Embree's entry points: intersect
    /// context × build quality); the entry's `params` apply.
    Sweep(Axes),
    /// Run with exactly these settings, its library's recommended ones; the entry's `params` do
    /// not apply.
    Fixed(Axes),
}

/// The axes `embree-best` sweeps unless its entry gives them.
const EMBREE_BEST_AXES: Axes = &[
    ("context", &["coherent", "incoherent"]),
    ("quality", &["medium", "high"]),
];

/// The settings a tracer is tested in when it declares no others: its defaults.
const DEFAULTS_ONLY: &[Settings] = &[&[]];

/// The families' source (`TracerInfo::source`): each family's own folder or file, then those of
/// the families it imports.
const REFERENCE_SOURCE: &[&str] = &["tracers/reference.rs"];
const WIDE_SINGLE_SOURCE: &[&str] = &["tracers/wide_single", "tracers/reference.rs"];
const EMBREE_SOURCE: &[&str] = &["tracers/embree"];
const OBVHS_SOURCE: &[&str] = &["tracers/obvhs.rs", "tracers/reference.rs"];
#[cfg(tinybvh)]
const TINYBVH_SOURCE: &[&str] = &["tracers/tinybvh"];
const GRID_DDA_SOURCE: &[&str] = &["tracers/grid_dda.rs", "tracers/reference.rs"];
const CGT_SOURCE: &[&str] = &[
    "tracers/coherent_grid",
    "tracers/grid_dda.rs",
    "tracers/reference.rs",
];
const PACKET_SOURCE: &[&str] = &["tracers/packet"];
const MFT_SOURCE: &[&str] = &[
    "tracers/multi_frusta",
    "tracers/packet",
    "tracers/reference.rs",
];
const STREAM_SOURCE: &[&str] = &[
    "tracers/stream",
    "tracers/packet",
    "tracers/reference.rs",
    "tracers/wide_single",
];

/// The error of a `make` handed another family's configuration (a bug, not the user's input).
fn other_family(config: &TracerConfig) -> Error {
    Error::Runtime(format!(
        "a tracer was made from another tracer's configuration {config:?}"
    ))
}

fn plain(_: &Params) -> Result<TracerConfig> {
    Ok(TracerConfig::Plain)
}

use crate::geometry::robustness::robust_param as robust;
/// The switch between our robust tests and the fast ones, named and meant as Embree's `robust`
/// (`geometry::robustness`): accepted by every tracer of ours, default `true`.
pub use crate::geometry::robustness::PARAM as ROBUST;

fn embree_config(params: &Params) -> Result<TracerConfig> {
    Coherence::from_params(params).map(TracerConfig::Embree)
}

fn embree3<M: Submission<Embree3>>(
    config: &TracerConfig,
    accel: &Accel,
) -> Result<Box<dyn Tracer>> {
    let TracerConfig::Embree(coherence) = *config else {
        return Err(other_family(config));
    };
    let scene = accel.embree()?.clone();
    Ok(Box::new(EmbreeTracer::<Embree3, M>::new(scene, coherence)))
}

#[cfg(embree4)]
fn embree4<M: Submission<Embree4>>(
    config: &TracerConfig,
    accel: &Accel,
) -> Result<Box<dyn Tracer>> {
    let TracerConfig::Embree(coherence) = *config else {
        return Err(other_family(config));
    };
    let scene = accel.embree4()?.clone();
    Ok(Box::new(EmbreeTracer::<Embree4, M>::new(scene, coherence)))
}

/// An Embree tracer's entry: every one is a baseline that reads the coherence hint (`context`),
/// counts only rays and traces moving geometry.
const fn embree_entry(
    name: &'static str,
    accel: AccelKind,
    about: &'static str,
    make: Make,
) -> TracerInfo {
    TracerInfo {
        name,
        role: Role::Baseline,
        accel,
        params: Coherence::PARAMS,
        about,
        parse: embree_config,
        make,
        counts_internals: false,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
        source: EMBREE_SOURCE,
        // Embree's default (non-robust) build and its robust one.
        test_configs: &[&[], &[("robust", "true")]],
        best: BaselineBest::Sweep(EMBREE_BEST_AXES),
    }
}

/// A tinybvh tracer's entry: a baseline over one of tinybvh's layouts, counting only rays, for
/// geometry of one instant.
#[cfg(tinybvh)]
const fn tinybvh_entry(
    name: &'static str,
    layout: TinyLayout,
    about: &'static str,
    make: Make,
    best: BaselineBest,
) -> TracerInfo {
    TracerInfo {
        name,
        role: Role::Baseline,
        accel: AccelKind::TinyBvh(layout),
        params: &[],
        about,
        parse: plain,
        make,
        counts_internals: false,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: TINYBVH_SOURCE,
        // Its default build, and spatial splits plus reinsertion.
        test_configs: &[&[], &[("builder", "sbvh"), ("optimize", "5")]],
        best,
    }
}

/// The names the Embree 3 tracers had before Embree 4 came (`embree4` was rtcIntersect4!), kept
/// as aliases so existing experiment files still run; rows carry the new names.
pub const ALIASES: &[(&str, &str)] = &[
    ("embree1", "embree3-1"),
    ("embree4", "embree3-4"),
    ("embree8", "embree3-8"),
    ("embree16", "embree3-16"),
    ("embree-stream", "embree3-stream"),
];

/// The name rows carry for a tracer called `name`: the new name of an alias, else `name`.
pub fn canonical_name(name: &str) -> &str {
    ALIASES
        .iter()
        .find(|(alias, _)| *alias == name)
        .map_or(name, |(_, canonical)| canonical)
}

/// Whether `name` is a tracer this build lacks but another build has: Embree 4's, when
/// `build.rs` did not find Embree 4, and tinybvh's, when it could not build the shim.
pub fn not_built(name: &str) -> bool {
    missing_because(name).is_some()
}

/// What to do to get tracer `name` into this build, when this build lacks it.
fn missing_because(name: &str) -> Option<&'static str> {
    if !EMBREE4_BUILT && EMBREE4_TRACERS.contains(&name) {
        Some(EMBREE4_HINT)
    } else if !TINYBVH_BUILT && TINYBVH_TRACERS.contains(&name) {
        Some(TINYBVH_HINT)
    } else {
        None
    }
}

/// What a plan says of tracer `name` on rays of `kinds`, when the tracer answers some of them by
/// another method than its name says: `tinybvh-256` traces only blocks of pinhole camera rays
/// with its packet kernel.
pub fn plan_note(name: &str, kinds: &[RayKind]) -> Option<String> {
    let others: Vec<&str> = kinds
        .iter()
        .filter(|&&k| k != RayKind::Primary)
        .map(|k| k.name())
        .collect();
    (name == "tinybvh-256").then(|| {
        let others = match others.is_empty() {
            true => String::new(),
            false => format!(
                "; its {} rays by single rays (as tinybvh-2)",
                others.join(", ")
            ),
        };
        format!(
            "tinybvh-256 traces 16×16 blocks of pinhole camera rays with Intersect256Rays, any \
             other camera rays (partial blocks at image edges, a thin lens) by single rays{others}"
        )
    })
}

pub use crate::accel::libraries::{TINYBVH_BUILT, TINYBVH_HINT};

/// The tinybvh tracers, which a build without tinybvh lacks.
pub const TINYBVH_TRACERS: &[&str] = &["tinybvh-2", "tinybvh-4", "tinybvh-8", "tinybvh-256"];

/// The role of the tracer a runs.csv row names, also of one this build lacks (Embree 4's);
/// `None` for a name no build has.
pub fn role_of(name: &str) -> Option<Role> {
    match TracerInfo::find(name) {
        Ok(info) => Some(info.role),
        Err(_) => not_built(name).then_some(Role::Baseline),
    }
}

/// Whether the tracer a runs.csv row names calls Embree, also one this build lacks.
pub fn is_embree(name: &str) -> bool {
    match TracerInfo::find(name) {
        Ok(info) => info.accel.is_embree(),
        Err(_) => not_built(name),
    }
}

/// The Embree 4 tracers, which a build without Embree 4 lacks (`accel::embree::EMBREE4_HINT`).
pub const EMBREE4_TRACERS: &[&str] = &["embree4-1", "embree4-4", "embree4-8", "embree4-16"];

pub const TRACERS: &[TracerInfo] = &[
    TracerInfo {
        name: "reference",
        role: Role::Reference,
        accel: AccelKind::Bvh,
        params: &[],
        about:
            "single rays, binary SAH BVH, nearer child first; watertight triangles, robust slabs (robust = false: plain slabs, Möller–Trumbore)",
        parse: |params| Ok(TracerConfig::Reference { robust: robust(params)? }),
        make: |config, accel| {
            let bvh = accel.bvh()?.clone();
            match *config {
                TracerConfig::Reference { robust: true } => {
                    Ok(Box::new(ReferenceTracer::<Robust>::with_tests(bvh)))
                }
                TracerConfig::Reference { robust: false } => {
                    Ok(Box::new(ReferenceTracer::<Fast>::with_tests(bvh)))
                }
                _ => Err(other_family(config)),
            }
        },
        counts_internals: true,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
        source: REFERENCE_SOURCE,
        test_configs: DEFAULTS_ONLY,
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "wide-single",
        role: Role::Paper,
        accel: AccelKind::Bvh,
        params: wide_single::PARAMS,
        about: "single rays, the SAH BVH collapsed to 4 or 8 children per node (width, default 8): one SIMD slab test of all children, nearest first; the reference's watertight triangles and hits (robust = false: plain slabs, Möller–Trumbore)",
        parse: |params| {
            Ok(TracerConfig::WideSingle {
                width: wide_single::Width::from_params(params)?,
                robust: robust(params)?,
            })
        },
        make: |config, accel| match *config {
            TracerConfig::WideSingle { robust, .. } => match accel.tree()? {
                BvhOfWidth::Wide(tree) if robust => {
                    Ok(Box::new(WideSingleTracer::<Robust>::new(tree)))
                }
                BvhOfWidth::Wide(tree) => Ok(Box::new(WideSingleTracer::<Fast>::new(tree))),
                BvhOfWidth::Binary(_) => Err(Error::Runtime(
                    "wide-single was given the binary BVH, not a wide one".into(),
                )),
            },
            _ => Err(other_family(config)),
        },
        counts_internals: true,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
        source: WIDE_SINGLE_SOURCE,
        test_configs: &[&[], &[("width", "4")]],
        best: BaselineBest::Not,
    },
    embree_entry(
        "embree3-1",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect1 / rtcOccluded1 per ray (alias embree1)",
        embree3::<Single>,
    ),
    embree_entry(
        "embree3-4",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays (alias embree4)",
        embree3::<Packets4>,
    ),
    embree_entry(
        "embree3-8",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays (alias embree8)",
        embree3::<Packets8>,
    ),
    embree_entry(
        "embree3-16",
        AccelKind::Embree,
        "Embree 3 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays (alias embree16)",
        embree3::<Packets16>,
    ),
    embree_entry(
        "embree3-stream",
        AccelKind::Embree,
        "Embree 3 baseline: AoS ray streams, rtcIntersect1M / rtcOccluded1M (alias embree-stream)",
        embree3::<Stream>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-1",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect1 / rtcOccluded1 per ray",
        embree4::<Single>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-4",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect4 / rtcOccluded4 on groups of 4 consecutive rays",
        embree4::<Packets4>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-8",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect8 / rtcOccluded8 on groups of 8 consecutive rays",
        embree4::<Packets8>,
    ),
    #[cfg(embree4)]
    embree_entry(
        "embree4-16",
        AccelKind::Embree4,
        "Embree 4 baseline: rtcIntersect16 / rtcOccluded16 on groups of 16 consecutive rays",
        embree4::<Packets16>,
    ),
    TracerInfo {
        name: "obvhs",
        role: Role::Baseline,
        accel: AccelKind::Obvhs,
        params: &[],
        about: "single rays, obvhs 0.4 compressed 8-wide BVH and its own traversal; watertight triangles",
        parse: plain,
        make: |_, accel| Ok(Box::new(ObvhsTracer::new(accel.obvhs()?.clone()))),
        counts_internals: true,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: OBVHS_SOURCE,
        test_configs: DEFAULTS_ONLY,
        best: BaselineBest::Fixed(&[]),
    },
    #[cfg(tinybvh)]
    tinybvh_entry(
        "tinybvh-2",
        TinyLayout::Binary,
        "tinybvh 1.6.8 baseline: single rays, BVH (2-wide, 32-byte nodes) Intersect / IsOccluded; tinybvh's builders (builder = sah|sbvh, optimize = rounds of reinsertion); Möller–Trumbore triangles",
        |_, accel| Ok(Box::new(SingleTracer::new(accel.tinybvh(TinyLayout::Binary)?.clone()))),
        BaselineBest::Not,
    ),
    #[cfg(tinybvh)]
    tinybvh_entry(
        "tinybvh-4",
        TinyLayout::Wide4,
        "tinybvh 1.6.8 baseline: single rays, BVH4_CPU (4-wide SSE nodes, triangles 4 per leaf block) Intersect / IsOccluded; tinybvh's builders as tinybvh-2",
        |_, accel| Ok(Box::new(SingleTracer::new(accel.tinybvh(TinyLayout::Wide4)?.clone()))),
        BaselineBest::Not,
    ),
    #[cfg(tinybvh)]
    tinybvh_entry(
        "tinybvh-8",
        TinyLayout::Wide8,
        "tinybvh 1.6.8 baseline: single rays, BVH8_CPU (8-wide AVX2 + FMA nodes after Fuetterling et al. 2017) Intersect / IsOccluded; tinybvh's builders as tinybvh-2",
        |_, accel| Ok(Box::new(SingleTracer::new(accel.tinybvh(TinyLayout::Wide8)?.clone()))),
        // Its fastest single-ray layout over its highest-quality build (spatial splits, then
        // reinsertion: tiny_bvh.h's `BuildHQ` and `Optimize`).
        BaselineBest::Fixed(&[("builder", &["sbvh"]), ("optimize", &["25"])]),
    ),
    #[cfg(tinybvh)]
    TracerInfo {
        name: "tinybvh-256",
        params: TileConfig::PARAMS,
        about: "tinybvh 1.6.8 baseline: BVH::Intersect256Rays (after Overbeck et al. 2008: first-hit test, 4-plane frustum, first/last active ray) on 16×16 blocks of pinhole camera rays (sse = true: its SSE version); other rays and occlusion by single rays as tinybvh-2",
        parse: |params| TileConfig::from_params(params).map(TracerConfig::TinyTile),
        make: |config, accel| match *config {
            TracerConfig::TinyTile(c) => Ok(Box::new(TileTracer::new(
                accel.tinybvh(TinyLayout::Binary)?.clone(),
                c,
            )?)),
            _ => Err(other_family(config)),
        },
        role: Role::Baseline,
        accel: AccelKind::TinyBvh(TinyLayout::Binary),
        counts_internals: false,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: TINYBVH_SOURCE,
        test_configs: &[&[], &[("sse", "false")]],
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "grid-dda",
        role: Role::Paper,
        accel: AccelKind::Grid,
        params: &[],
        about: "single rays, uniform grid by 3D-DDA (Amanatides & Woo 1987), empty macrocells skipped; watertight triangles (robust = false: Möller–Trumbore)",
        parse: |params| Ok(TracerConfig::GridDda { robust: robust(params)? }),
        make: |config, accel| {
            let grid = accel.grid()?.clone();
            match *config {
                TracerConfig::GridDda { robust: true } => {
                    Ok(Box::new(GridDdaTracer::<Robust>::with_tests(grid)))
                }
                TracerConfig::GridDda { robust: false } => {
                    Ok(Box::new(GridDdaTracer::<Fast>::with_tests(grid)))
                }
                _ => Err(other_family(config)),
            }
        },
        counts_internals: true,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: GRID_DDA_SOURCE,
        test_configs: DEFAULTS_ONLY,
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "cgt",
        role: Role::Paper,
        accel: AccelKind::Grid,
        params: CgtConfig::PARAMS,
        about: "coherent grid traversal (Wald et al. 2006): n×n packets walk the uniform grid slice by slice in their frustum; per-packet mailboxing, SIMD frustum culling, macrocells; watertight triangles (robust = false: Möller–Trumbore)",
        parse: |params| CgtConfig::from_params(params).map(TracerConfig::Cgt),
        make: |config, accel| match *config {
            TracerConfig::Cgt(c) => Ok(Box::new(CgtTracer::new(accel.grid()?.clone(), c))),
            _ => Err(other_family(config)),
        },
        counts_internals: true,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: CGT_SOURCE,
        test_configs: &[&[], &[("packet", "8"), ("lanes", "8"), ("cull", "false")]],
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "packet",
        role: Role::Paper,
        accel: AccelKind::Bvh,
        params: PacketConfig::PARAMS,
        about: "large ray packets (Overbeck et al. 2008): n×n packets (packet ∈ 2,4,8,16,32) of L-lane SIMD rays (lanes ∈ 4,8,16) through the SAH BVH by masked, ranged, partition or ia (Wald et al. 2007 first hit + interval arithmetic) traversal, front to back by direction signs; frustum culling of boxes and triangles (shared-origin, shared-end-point or general frustum, from the data); exact closest hits (watertight, robust slabs per lane; robust = false: plain slabs, Möller–Trumbore)",
        parse: |params| {
            let config = PacketConfig::from_params(params)?;
            let width = config.width_from_params(params)?;
            Ok(TracerConfig::Packet { config, width })
        },
        make: |config, accel| match *config {
            TracerConfig::Packet { config, .. } => {
                Ok(Box::new(PacketTracer::new(accel.tree()?, config)))
            }
            _ => Err(other_family(config)),
        },
        counts_internals: true,
        motion_blur: true,
        chunk_rays: CHUNK_RAYS,
        source: PACKET_SOURCE,
        test_configs: &[
            &[],
            &[("traversal", "partition"), ("packet", "8"), ("lanes", "8")],
            &[("traversal", "ia"), ("packet", "32"), ("lanes", "16")],
            &[("traversal", "masked"), ("packet", "4"), ("lanes", "4"), ("frustum", "false")],
            &[("traversal", "ranged"), ("packet", "16"), ("frustum", "false"), ("width", "4")],
            &[("traversal", "ranged"), ("packet", "8"), ("lanes", "8"), ("width", "8")],
        ],
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "mft",
        role: Role::Paper,
        accel: AccelKind::Bvh,
        params: MftConfig::PARAMS,
        about: "multi-frusta tracing (Benthin & Wald 2009): light-visibility queries as blocks of shadow frusta (block points, ≤ 64) through the SAH BVH together, rays generated on demand at leaves, box culling for all frusta at once, plane and corner-ray triangle culling, occlusion bits, corner-ray recomputation (cr), frustum shrinking (fs) and leaf ray–box tests (leaf_rays); with primary = frusta, pinhole camera batches as blocks of 4×4-pixel primary frusta, their rays made on demand from the camera grid; other ray batches (and camera rays by default) by 4×4 packets; exact answers (watertight; robust = false: Möller–Trumbore, plain slabs)",
        parse: |params| MftConfig::from_params(params).map(TracerConfig::Mft),
        make: |config, accel| match *config {
            TracerConfig::Mft(c) => Ok(Box::new(MftTracer::new(accel.tree()?, c))),
            _ => Err(other_family(config)),
        },
        counts_internals: true,
        motion_blur: false,
        chunk_rays: CHUNK_RAYS,
        source: MFT_SOURCE,
        test_configs: &[
            &[],
            &[("cr", "false"), ("fs", "false"), ("leaf_rays", "false")],
            &[("fs", "false"), ("block", "64")],
            &[("width", "4"), ("primary", "frusta")],
            &[("width", "8"), ("block", "64"), ("primary", "frusta")],
        ],
        best: BaselineBest::Not,
    },
    TracerInfo {
        name: "stream",
        role: Role::Paper,
        accel: AccelKind::Bvh,
        params: StreamConfig::PARAMS,
        about: "stream filtering (Gribble & Ramani 2008): streams of S rays (stream = S or frame) through the SAH BVH; at each node a box filter tests N rays at a time (width ∈ 4,8,12,16,32,64) and partitions the stream in place, the rays that meet the box going on to the leaf or to both children, front to back; exact closest hits (watertight, robust slabs per lane; robust = false: plain slabs, Möller–Trumbore)",
        parse: |params| StreamConfig::from_params(params).map(TracerConfig::Stream),
        make: |config, accel| match *config {
            TracerConfig::Stream(c) => {
                Ok(Box::new(StreamTracer::over_static(accel.tree()?, c)?))
            }
            _ => Err(other_family(config)),
        },
        counts_internals: true,
        motion_blur: false,
        chunk_rays: 16 * CHUNK_RAYS,
        source: STREAM_SOURCE,
        test_configs: &[
            &[],
            &[("width", "12"), ("stream", "1024")],
            &[("width", "64"), ("stream", "frame")],
            &[("width", "4"), ("stream", "64"), ("single", "8"), ("single_tree", "4")],
        ],
        best: BaselineBest::Not,
    },
];

/// A tracer entry shows as its name (its functions have nothing to show).
impl std::fmt::Debug for TracerInfo {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

impl TracerInfo {
    /// The tracer `name` names, directly or through one of its `ALIASES`.
    pub fn find(name: &str) -> Result<&'static TracerInfo> {
        let canonical = canonical_name(name);
        if let Some(info) = TRACERS.iter().find(|t| t.name == canonical) {
            return Ok(info);
        }
        if let Some(hint) = missing_because(name) {
            return Err(Error::usage(format!("tracer {name:?}: {hint}")));
        }
        let known: Vec<&str> = TRACERS.iter().map(|t| t.name).collect();
        Err(Error::usage(format!(
            "unknown tracer {name:?} (known: {})",
            known.join(", ")
        )))
    }

    /// The tracer of `role` (the first, for a role several have): `Role::Reference` names the
    /// one tracer that generates secondary rays and reference images.
    pub fn of_role(role: Role) -> Result<&'static TracerInfo> {
        TRACERS
            .iter()
            .find(|t| t.role == role)
            .ok_or_else(|| Error::Runtime(format!("no tracer of role {role:?} in this build")))
    }

    /// `params` (the tracer's and its structure's) checked: no key the tracer or its structure
    /// does not read, and the tracer's own values parsed into its configuration.
    pub fn config(&self, params: &Params) -> Result<TracerConfig> {
        params.check_known(self.name, &self.accepts())?;
        (self.parse)(params)
    }

    /// The structure an instance with `params` (parsed into `config`) traverses: its kind and
    /// the parameters it is built with. A tracer over our BVH with a tree width of 4 or 8 walks
    /// the wide tree of that width (`AccelKind::Wide`), a structure of its own shared by every
    /// tracer of the same BVH parameters and width.
    pub fn structure(&self, config: &TracerConfig, params: &Params) -> (AccelKind, Params) {
        let own = params.subset(self.accel.params());
        match (self.accel, config.tree_width()) {
            (AccelKind::Bvh, width) if width > 2 => (AccelKind::Wide, own.with("width", width)),
            (kind, _) => (kind, own),
        }
    }

    /// Every parameter this tracer accepts: its own, its structure's, and `robust` for ours.
    pub fn accepts(&self) -> Vec<&'static str> {
        let robust = self.is_ours().then_some(ROBUST);
        self.params
            .iter()
            .chain(self.accel.params())
            .copied()
            .chain(robust)
            .collect()
    }

    /// Whether an instance in `config` (from `params`) runs robust, watertight tests: ours by
    /// `robust` (default true), Embree's by its scene's `robust` (default false), obvhs's always
    /// (watertight triangles), tinybvh's never (Möller–Trumbore).
    pub fn robust_tests(&self, config: &TracerConfig, params: &Params) -> Result<bool> {
        match (config.robust(), self.accel) {
            (Some(robust), _) => Ok(robust),
            (None, AccelKind::Obvhs) => Ok(true),
            (None, kind) if kind.is_embree() => Ok(EmbreeConfig::from_params(params)?.robust),
            (None, _) => Ok(false),
        }
    }

    /// `test_configs` as parameters.
    pub fn test_params(&self) -> Vec<Params> {
        let params = |settings: Settings| {
            let with = |p: Params, &(key, value): &(&str, &str)| p.with(key, value);
            settings.iter().fold(Params::new(), with)
        };
        self.test_configs.iter().map(|&c| params(c)).collect()
    }

    /// Whether it is one of our from-scratch tracers (not a library's).
    pub fn is_ours(&self) -> bool {
        self.role != Role::Baseline
    }
}

/// A tracer over `accel`, which must be of the tracer's `AccelKind` built with its parameters.
pub fn build_tracer(info: &TracerInfo, params: &Params, accel: &Accel) -> Result<Box<dyn Tracer>> {
    make_tracer(info, &info.config(params)?, accel)
}

/// A tracer over `accel`, which must be of the tracer's `AccelKind` built with its parameters;
/// `config` is what `info.config` returned.
pub fn make_tracer(
    info: &TracerInfo,
    config: &TracerConfig,
    accel: &Accel,
) -> Result<Box<dyn Tracer>> {
    if accel.is_moving() && !info.motion_blur {
        let movers: Vec<&str> = TRACERS
            .iter()
            .filter(|t| t.motion_blur)
            .map(|t| t.name)
            .collect();
        return Err(Error::usage(format!(
            "tracer {} has no motion blur (moving geometry needs one of {})",
            info.name,
            movers.join(", ")
        )));
    }
    Ok(Box::new(Registered {
        tracer: (info.make)(config, accel)?,
        chunk_rays: info.chunk_rays,
    }))
}

/// Builds tracer `name` with `params` over `mesh` (its own structure, built here).
pub fn tracer_for_mesh(name: &str, params: &Params, mesh: &Mesh) -> Result<Box<dyn Tracer>> {
    let info = TracerInfo::find(name)?;
    make_for_mesh(info, &info.config(params)?, params, mesh)
}

/// Builds tracer `info` in `config` (what `info.config(params)` returned) over `mesh` (its own
/// structure, built with `params`' structure parameters here).
pub fn make_for_mesh(
    info: &TracerInfo,
    config: &TracerConfig,
    params: &Params,
    mesh: &Mesh,
) -> Result<Box<dyn Tracer>> {
    let (kind, structure_params) = info.structure(config, params);
    let accel = kind.build(mesh, &structure_params)?;
    make_tracer(info, config, &accel)
}

/// Builds tracer `name` with `params` over `frame`'s geometry (its own structure, built here).
pub fn tracer_for_frame(name: &str, params: &Params, frame: &Frame) -> Result<Box<dyn Tracer>> {
    tracer_for_mesh(name, params, &frame.mesh)
}

/// The oracle verification compares against: Embree's single-ray call on a robust,
/// high-quality scene.
pub const ORACLE: &str = "embree3-1";

pub fn oracle_params() -> Params {
    Params::new().with("robust", "true").with("quality", "high")
}

/// A tracer as its registry entry made it: the algorithm, and the chunk size the entry asks for.
struct Registered {
    tracer: Box<dyn Tracer>,
    chunk_rays: usize,
}

impl Tracer for Registered {
    fn counts_internals(&self) -> bool {
        self.tracer.counts_internals()
    }
    fn answers_visibility_natively(&self) -> bool {
        self.tracer.answers_visibility_natively()
    }
    fn chunk_rays(&self) -> usize {
        self.chunk_rays
    }
    fn intersect(&self, rays: Rays<'_>, hits: &mut [Hit]) {
        self.tracer.intersect(rays, hits)
    }
    fn occluded(&self, rays: Rays<'_>, occluded: &mut [bool]) {
        self.tracer.occluded(rays, occluded)
    }
    fn intersect_counted(&self, rays: Rays<'_>, hits: &mut [Hit], counters: &mut Counters) {
        self.tracer.intersect_counted(rays, hits, counters)
    }
    fn occluded_counted(&self, rays: Rays<'_>, occluded: &mut [bool], counters: &mut Counters) {
        self.tracer.occluded_counted(rays, occluded, counters)
    }
    fn light_visibility(&self, query: VisibilityQuery<'_>, occluded: &mut [u64]) {
        self.tracer.light_visibility(query, occluded)
    }
    fn light_visibility_counted(
        &self,
        query: VisibilityQuery<'_>,
        occluded: &mut [u64],
        counters: &mut Counters,
    ) {
        self.tracer
            .light_visibility_counted(query, occluded, counters)
    }
    fn stage_closest(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<Hit> + '_>> {
        self.tracer.stage_closest(rays, chunks)
    }
    fn stage_occlusion(
        &self,
        rays: Rays<'_>,
        chunks: Vec<Range<usize>>,
    ) -> Option<Box<dyn StagedRays<bool> + '_>> {
        self.tracer.stage_occlusion(rays, chunks)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::{Ray, RayBatch, Triangle};
    use glam::Vec3;

    #[test]
    fn registry_builds_the_obvhs_tracer() {
        let mut mesh = Mesh::default();
        mesh.push(Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y), 0);
        let info = TracerInfo::find("obvhs").unwrap();
        assert_eq!(info.accel, AccelKind::Obvhs);
        assert_eq!(info.accepts(), vec!["quality"]);
        let params = Params::new().with("quality", "fast_build");
        let accel = info.accel.build(&mesh, &params).unwrap();
        let Accel::Obvhs(bvh) = &accel else {
            panic!("wrong structure")
        };
        assert_eq!(bvh.quality, crate::accel::ObvhsQuality::FastBuild);
        assert!(accel.build_seconds() > 0.0);
        let config = info.config(&params).unwrap();
        let tracer = make_tracer(info, &config, &accel).unwrap();
        let mut rays = RayBatch::new(RayKind::Primary);
        rays.push(
            Ray::new(Vec3::new(0.2, 0.3, 1.0), -Vec3::Z, 0.0, f32::INFINITY),
            0,
        );
        let mut hits = vec![Hit::MISS];
        tracer.intersect(rays.view(), &mut hits);
        assert_eq!((hits[0].prim, hits[0].t), (0, 1.0));
        assert!(
            (hits[0].u - 0.2).abs() < 1e-6 && (hits[0].v - 0.3).abs() < 1e-6,
            "{:?}",
            hits[0]
        );
        // The reference tracer's structure is refused.
        let bvh_accel = AccelKind::Bvh.build(&mesh, &Params::new()).unwrap();
        assert!(make_tracer(info, &config, &bvh_accel).is_err());
        assert!(info.config(&Params::new().with("leaf_size", 2)).is_err());
    }

    #[test]
    fn aliases_resolve_to_the_embree_3_tracers() {
        for (alias, canonical) in ALIASES {
            assert_eq!(TracerInfo::find(alias).unwrap().name, *canonical);
            assert_eq!(
                TracerInfo::find(canonical).unwrap().accel,
                AccelKind::Embree
            );
            assert!(
                TRACERS.iter().all(|t| t.name != *alias),
                "{alias} is only an alias"
            );
        }
        // `embree4` is Embree 3's rtcIntersect4, not Embree 4.
        assert_eq!(TracerInfo::find("embree4").unwrap().name, "embree3-4");
    }

    /// The optional baselines' tracers (Embree 4's, tinybvh's) exist exactly when the build has
    /// them, are baselines, and otherwise name the script that fetches them.
    #[test]
    fn optional_baselines_exist_exactly_when_they_were_built() {
        let optional = [
            (EMBREE4_TRACERS, EMBREE4_BUILT, ".ci/fetch-embree4"),
            (TINYBVH_TRACERS, TINYBVH_BUILT, ".ci/fetch-tinybvh"),
        ];
        for (names, built, fetch) in optional {
            for name in names {
                let found = TracerInfo::find(name);
                assert_eq!(found.is_ok(), built, "{name}");
                assert_eq!(not_built(name), !built, "{name}");
                match found {
                    Ok(info) => assert_eq!((info.name, info.role), (*name, Role::Baseline)),
                    Err(err) => {
                        assert!(matches!(err, Error::Usage(_)), "{err}");
                        assert!(err.to_string().contains(fetch), "{err}");
                    }
                }
            }
        }
        assert!(!not_built("embree3-16") && !not_built("no-such-tracer"));
    }

    fn triangle() -> Mesh {
        let mut mesh = Mesh::default();
        mesh.push(
            crate::geometry::Triangle {
                v: [glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
            },
            0,
        );
        mesh
    }

    #[test]
    fn one_reference_and_the_entries_know_what_their_tracers_count() {
        let reference: Vec<&str> = TRACERS
            .iter()
            .filter(|t| t.role == Role::Reference)
            .map(|t| t.name)
            .collect();
        assert_eq!(reference, ["reference"]);
        assert_eq!(
            TracerInfo::of_role(Role::Reference).unwrap().name,
            "reference"
        );
        for t in TRACERS {
            let config = t.config(&Params::new()).unwrap();
            let (kind, params) = t.structure(&config, &Params::new());
            let accel = kind.build(&triangle(), &params).unwrap();
            let tracer = make_tracer(t, &config, &accel).unwrap();
            assert_eq!(tracer.counts_internals(), t.counts_internals, "{}", t.name);
            assert_eq!(t.accel.is_embree(), is_embree(t.name), "{}", t.name);
            assert_eq!(role_of(t.name), Some(t.role), "{}", t.name);
            // Baselines are the production libraries: Embree's, obvhs and tinybvh.
            assert_eq!(
                t.role == Role::Baseline,
                t.accel.is_embree()
                    || t.accel == AccelKind::Obvhs
                    || TINYBVH_TRACERS.contains(&t.name),
                "{}",
                t.name
            );
        }
        assert_eq!(
            (role_of("no-such-tracer"), is_embree("no-such-tracer")),
            (None, false)
        );
    }

    #[test]
    fn a_configuration_checks_keys_and_values() {
        let packet = TracerInfo::find("packet").unwrap();
        let err = packet.config(&Params::new().with("depth", 2)).unwrap_err();
        assert!(
            err.to_string()
                .contains("unknown parameter \"depth\" for packet"),
            "{err}"
        );
        assert!(packet.config(&Params::new().with("lanes", 5)).is_err());
        // The structure's parameters are accepted (the structure reads them), not parsed here.
        let config = packet.config(&Params::new().with("leaf_size", 2).with("width", 4));
        assert!(matches!(
            config,
            Ok(TracerConfig::Packet {
                width: TreeWidth::Four,
                ..
            })
        ));
        let bvh = AccelKind::Bvh.build(&triangle(), &Params::new()).unwrap();
        let wrong = make_tracer(packet, &TracerConfig::Plain, &bvh);
        assert!(matches!(wrong, Err(Error::Runtime(_))));
    }

    /// `robust` is ours (default true) and Embree's structure parameter: every tracer of ours
    /// takes `false` into its configuration, and a baseline that is not Embree does not know it.
    #[test]
    fn robust_is_parsed_into_every_tracer_of_ours() {
        let fast = Params::new().with(ROBUST, false);
        let config = |name: &str, params: &Params| TracerInfo::find(name).unwrap().config(params);
        assert_eq!(
            config("reference", &Params::new()).unwrap(),
            TracerConfig::Reference { robust: true }
        );
        assert_eq!(
            config("reference", &fast).unwrap(),
            TracerConfig::Reference { robust: false }
        );
        assert_eq!(
            config("wide-single", &fast.clone().with("width", 4)).unwrap(),
            TracerConfig::WideSingle {
                width: wide_single::Width::Four,
                robust: false
            }
        );
        let robust_of = |config: TracerConfig| match config {
            TracerConfig::Packet { config, .. } => config.robust,
            TracerConfig::Stream(c) => c.robust,
            TracerConfig::Cgt(c) => c.robust,
            TracerConfig::Mft(c) => c.robust,
            TracerConfig::GridDda { robust } => robust,
            other => panic!("{other:?}"),
        };
        for name in ["packet", "stream", "cgt", "mft", "grid-dda"] {
            assert!(robust_of(config(name, &Params::new()).unwrap()), "{name}");
            assert!(!robust_of(config(name, &fast).unwrap()), "{name}");
        }
        assert!(config("embree3-1", &fast).is_ok());
        let err = config("obvhs", &fast).unwrap_err();
        assert!(
            err.to_string().contains("unknown parameter \"robust\""),
            "{err}"
        );
        let bad = config("reference", &Params::new().with(ROBUST, "maybe")).unwrap_err();
        assert!(matches!(bad, Error::Usage(_)), "{bad:?}");
    }

    #[test]
    fn names_are_unique_and_chunks_hold_whole_blocks() {
        for (i, t) in TRACERS.iter().enumerate() {
            assert!(TRACERS[..i].iter().all(|u| u.name != t.name), "{}", t.name);
            assert!(t.chunk_rays > 0 && t.chunk_rays % 1024 == 0, "{}", t.name);
        }
    }
}
