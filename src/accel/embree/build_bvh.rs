//! Our binary BVH built by Embree 3's own builder (`rtcBuildBVH`, `builder = "embree"`), so that
//! our tracers can walk a tree of Embree's quality: the gap to Embree then splits into tree quality
//! (our builder against Embree's, same tracer) and traversal (same tree, our kernel against
//! Embree's).
//!
//! Settings: `RTC_BUILD_QUALITY_HIGH` with a split callback, which is Embree's spatial-split SAH
//! builder (its SBVH, `rtcBuildBVHSpatialSAH`), room for 1.2 references per triangle (Embree's own
//! default, `max_spatial_split_replications`), branching factor 2 (our binary layout, so the wide
//! collapse works unchanged), and our SAH constants: traversal 1, intersection 1 per triangle
//! (`sahBlockSize` 1), `minLeafSize` 1, `maxLeafSize` = `leaf_size`, `maxDepth` from `max_depth`.
//! `builder = "embree-blocks"` takes the leaf policy of Embree's own triangle scenes instead
//! (`sahBlockSize` 4, `minLeafSize` 4: leaves priced in blocks of 4 triangles, a node of 4 or fewer
//! never split), so the tree Embree's kernel walks can be walked by ours too (issue 45).
//! A straddling triangle is split by our SBVH's own splitter (`spatial_split::split_reference`), so
//! each part keeps the box of the part of the triangle on its side, as in our spatial splits.
//!
//! Embree calls the callbacks from its build threads: nodes and leaves go into its thread-local
//! allocator (freed with the `RTCBVH`), as its `bvh_builder` tutorial does, and are laid out in our
//! order afterwards (children adjacent, leaves' triangles copied in tree order).

use std::ffi::{c_uint, c_void};
use std::mem::{align_of, size_of};
use std::ptr;
use std::time::Instant;

use glam::Vec3;

use super::api::Embree3;
use super::ffi::{
    self, RTCBounds, RTCBuildArguments, RTCBuildFlags, RTCBuildPrimitive, RTCBuildQuality,
    RTCThreadLocalAllocator, RTCBVH,
};
use super::Device;
use crate::accel::bvh::{Bvh, BvhBuilder, BvhConfig, BvhNode};
use crate::accel::presplit::Reference;
use crate::accel::spatial_split::split_reference;
use crate::error::{Error, Result};
use crate::geometry::{Aabb, Triangle};

/// References Embree's spatial splits may make per triangle, in all (`max_spatial_split_replications`
/// in Embree's `common/state.cpp`).
const SPLIT_REPLICATIONS: f64 = 1.2;

/// A node as the callbacks make it, in Embree's allocator. A leaf's `count` references follow it
/// in memory (the size is a multiple of 32, `RTCBuildPrimitive`'s alignment).
#[repr(C, align(32))]
struct Made {
    leaf: bool,
    count: usize,
    children: [*const Made; 2],
    bounds: [RTCBounds; 2],
}

impl Made {
    /// The references of a leaf.
    ///
    /// # Safety
    /// `self` is a leaf made by `create_leaf`, whose allocation is still alive.
    unsafe fn references(&self) -> &[RTCBuildPrimitive] {
        let first = (self as *const Made).add(1) as *const RTCBuildPrimitive;
        std::slice::from_raw_parts(first, self.count)
    }
}

/// What the split callback reads (shared by Embree's threads, read only).
struct Context<'a> {
    triangles: &'a [Triangle],
}

fn aabb(b: &RTCBounds) -> Aabb {
    Aabb::new(
        Vec3::new(b.lower_x, b.lower_y, b.lower_z),
        Vec3::new(b.upper_x, b.upper_y, b.upper_z),
    )
}

fn rtc_bounds(b: Aabb) -> RTCBounds {
    RTCBounds {
        lower_x: b.min.x,
        lower_y: b.min.y,
        lower_z: b.min.z,
        align0: 0.0,
        upper_x: b.max.x,
        upper_y: b.max.y,
        upper_z: b.max.z,
        align1: 0.0,
    }
}

fn primitive_box(p: &RTCBuildPrimitive) -> Aabb {
    Aabb::new(
        Vec3::new(p.lower_x, p.lower_y, p.lower_z),
        Vec3::new(p.upper_x, p.upper_y, p.upper_z),
    )
}

/// Allocates `bytes` for a `Made` in Embree's thread-local allocator.
///
/// # Safety
/// `allocator` is the one Embree handed to the callback.
unsafe fn allocate(allocator: RTCThreadLocalAllocator, bytes: usize, made: Made) -> *mut Made {
    let p = ffi::rtcThreadLocalAlloc(allocator, bytes, align_of::<Made>()) as *mut Made;
    if !p.is_null() {
        p.write(made);
    }
    p
}

unsafe extern "C" fn create_node(
    allocator: RTCThreadLocalAllocator,
    _child_count: c_uint,
    _user: *mut c_void,
) -> *mut c_void {
    let made = Made {
        leaf: false,
        count: 0,
        children: [ptr::null(); 2],
        bounds: [rtc_bounds(Aabb::EMPTY); 2],
    };
    allocate(allocator, size_of::<Made>(), made) as *mut c_void
}

unsafe extern "C" fn set_node_children(
    node: *mut c_void,
    children: *mut *mut c_void,
    child_count: c_uint,
    _user: *mut c_void,
) {
    let node = &mut *(node as *mut Made);
    // A branching factor of 2 gives two children; more would be caught as a missing child.
    for k in 0..(child_count as usize).min(2) {
        node.children[k] = *children.add(k) as *const Made;
    }
    node.count = child_count as usize;
}

unsafe extern "C" fn set_node_bounds(
    node: *mut c_void,
    bounds: *mut *const RTCBounds,
    child_count: c_uint,
    _user: *mut c_void,
) {
    let node = &mut *(node as *mut Made);
    for k in 0..(child_count as usize).min(2) {
        node.bounds[k] = **bounds.add(k);
    }
}

unsafe extern "C" fn create_leaf(
    allocator: RTCThreadLocalAllocator,
    primitives: *const RTCBuildPrimitive,
    count: usize,
    _user: *mut c_void,
) -> *mut c_void {
    let made = Made {
        leaf: true,
        count,
        children: [ptr::null(); 2],
        bounds: [rtc_bounds(Aabb::EMPTY); 2],
    };
    let bytes = size_of::<Made>() + count * size_of::<RTCBuildPrimitive>();
    let leaf = allocate(allocator, bytes, made);
    if !leaf.is_null() {
        // Embree reuses its primitive array after the build: the leaf keeps its own copy.
        let first = leaf.add(1) as *mut RTCBuildPrimitive;
        ptr::copy_nonoverlapping(primitives, first, count);
    }
    leaf as *mut c_void
}

/// Embree's spatial split of one reference (a triangle's part, its box in `primitive`) at
/// `position` on `dimension`: the boxes of the triangle's parts on either side, within that box.
unsafe extern "C" fn split_primitive(
    primitive: *const RTCBuildPrimitive,
    dimension: c_uint,
    position: f32,
    left: *mut RTCBounds,
    right: *mut RTCBounds,
    user: *mut c_void,
) {
    let context = &*(user as *const Context);
    let primitive = &*primitive;
    let bounds = primitive_box(primitive);
    let (l, r) = match context.triangles.get(primitive.primID as usize) {
        Some(tri) => split_reference(tri, &bounds, dimension as usize, position),
        // Never: every primID is an index we gave. Empty boxes make Embree drop the split.
        None => (Aabb::EMPTY, Aabb::EMPTY),
    };
    *left = rtc_bounds(l);
    *right = rtc_bounds(r);
}

/// Releases the `RTCBVH` (and the nodes in its allocator) however the build ends.
struct BvhHandle(RTCBVH);

impl Drop for BvhHandle {
    fn drop(&mut self) {
        // SAFETY: made by rtcNewBVH, released once.
        unsafe { ffi::rtcReleaseBVH(self.0) };
    }
}

/// Our BVH over `triangles` built by Embree's builder with `config`'s leaf size and depth cap
/// (`config.builder` is `Embree`; the other parameters are not Embree's to use).
pub fn build_bvh(triangles: &[Triangle], config: BvhConfig) -> Result<Bvh> {
    let start = Instant::now();
    let n = triangles.len();
    if n == 0 {
        // What our builder makes of nothing: an empty root.
        let root = BvhNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        };
        return Ok(Bvh::from_leaf_order(
            vec![root],
            vec![0],
            &[],
            triangles,
            None,
            config,
            start,
        ));
    }
    if n > u32::MAX as usize {
        return Err(Error::runtime(format!(
            "Embree's BVH builder takes at most {} triangles (got {n})",
            u32::MAX
        )));
    }
    let capacity = ((n as f64 * SPLIT_REPLICATIONS).ceil() as usize).max(n + 1);
    let mut primitives = vec![RTCBuildPrimitive::default(); capacity];
    build_in(
        &*Device::<Embree3>::shared()?,
        triangles,
        config,
        &mut primitives,
        start,
    )
}

/// `build_bvh` on `device`, with `primitives` as Embree's primitive array: its length is the
/// capacity Embree may fill with split references (more than the triangles).
fn build_in(
    device: &Device<Embree3>,
    triangles: &[Triangle],
    config: BvhConfig,
    primitives: &mut [RTCBuildPrimitive],
    start: Instant,
) -> Result<Bvh> {
    let n = triangles.len();
    let capacity = primitives.len();
    let mut root_bounds = Aabb::EMPTY;
    for (i, (p, tri)) in primitives.iter_mut().zip(triangles).enumerate() {
        let b = tri.bounds();
        root_bounds = root_bounds.union(b);
        *p = RTCBuildPrimitive {
            lower_x: b.min.x,
            lower_y: b.min.y,
            lower_z: b.min.z,
            geomID: 0,
            upper_x: b.max.x,
            upper_y: b.max.y,
            upper_z: b.max.z,
            primID: i as u32,
        };
    }
    let context = Context { triangles };
    // Leaves priced per triangle (ours) or per block of 4, never split at 4 or fewer (Embree's).
    let block = match config.builder {
        BvhBuilder::EmbreeBlocks => BvhConfig::EMBREE_BLOCK,
        _ => 1,
    };
    // SAFETY: a valid device.
    let handle = BvhHandle(unsafe { ffi::rtcNewBVH(device.raw()) });
    device.check("creating a BVH for rtcBuildBVH")?;
    let arguments = RTCBuildArguments {
        byteSize: size_of::<RTCBuildArguments>(),
        buildQuality: RTCBuildQuality::RTC_BUILD_QUALITY_HIGH,
        buildFlags: RTCBuildFlags::RTC_BUILD_FLAG_NONE,
        maxBranchingFactor: 2,
        // Embree counts the root as depth 1, we count it as 0.
        maxDepth: (config.max_depth + 1) as c_uint,
        sahBlockSize: block as c_uint,
        minLeafSize: block as c_uint,
        maxLeafSize: config.max_leaf_size as c_uint,
        traversalCost: 1.0,
        intersectionCost: 1.0,
        bvh: handle.0,
        primitives: primitives.as_mut_ptr(),
        primitiveCount: n,
        primitiveArrayCapacity: capacity,
        createNode: Some(create_node),
        setNodeChildren: Some(set_node_children),
        setNodeBounds: Some(set_node_bounds),
        createLeaf: Some(create_leaf),
        splitPrimitive: Some(split_primitive),
        buildProgress: None,
        userPtr: &context as *const Context as *mut c_void,
    };
    // SAFETY: the arguments point at live data (primitives with room for `capacity`, the context)
    // for the whole call; the callbacks keep to the contracts above.
    let root = unsafe { ffi::rtcBuildBVH(&arguments) } as *const Made;
    device.check(&format!(
        "building a BVH of {n} triangles with rtcBuildBVH (max_depth = {})",
        config.max_depth
    ))?;
    if root.is_null() {
        return Err(Error::runtime(
            "Embree's rtcBuildBVH returned no tree and reported no error",
        ));
    }
    // SAFETY: `root` and everything under it live in `handle`'s allocator until it drops.
    let (nodes, depth, order) = unsafe { lay_out(root, root_bounds)? };
    drop(handle);
    let max_depth = depth.iter().copied().max().unwrap_or(0) as usize;
    if max_depth > config.max_depth.min(BvhConfig::DEPTH_LIMIT) {
        return Err(Error::runtime(format!(
            "Embree's builder made a tree of depth {max_depth}, deeper than max_depth = {}",
            config.max_depth
        )));
    }
    Ok(Bvh::from_leaf_order(
        nodes, depth, &order, triangles, None, config, start,
    ))
}

/// Our layout of Embree's tree: nodes depth first, left child first, the two children of a node
/// adjacent; leaves take their references in that order (as our builder's work list does).
///
/// # Safety
/// `root` is the tree `rtcBuildBVH` returned, its allocator still alive.
unsafe fn lay_out(
    root: *const Made,
    root_bounds: Aabb,
) -> Result<(Vec<BvhNode>, Vec<u8>, Vec<Reference>)> {
    let broken = |what: &str| Error::runtime(format!("Embree's BVH builder made {what}"));
    let mut nodes = vec![BvhNode {
        bounds: root_bounds,
        first: 0,
        count: 0,
    }];
    let mut depth = vec![0u8];
    let mut order = Vec::new();
    let mut pending = vec![(0usize, root)];
    while let Some((index, made)) = pending.pop() {
        let made = &*made;
        if made.leaf {
            if made.count == 0 {
                return Err(broken("an empty leaf"));
            }
            nodes[index].first = order.len() as u32;
            nodes[index].count = made.count as u32;
            order.extend(made.references().iter().map(|p| Reference {
                bounds: primitive_box(p),
                prim: p.primID,
            }));
            continue;
        }
        if made.count != 2 || made.children.iter().any(|c| c.is_null()) {
            return Err(broken(&format!("a node of {} children", made.count)));
        }
        if depth[index] as usize >= BvhConfig::DEPTH_LIMIT {
            return Err(broken(&format!(
                "a tree deeper than {}",
                BvhConfig::DEPTH_LIMIT
            )));
        }
        let child = nodes.len();
        for bounds in &made.bounds {
            nodes.push(BvhNode {
                bounds: aabb(bounds),
                first: 0,
                count: 0,
            });
            depth.push(depth[index] + 1);
        }
        nodes[index].first = child as u32;
        pending.push((child + 1, made.children[1]));
        pending.push((child, made.children[0]));
    }
    Ok((nodes, depth, order))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::bvh_validity;
    use crate::accel::wide_bvh::WideBvh;
    use crate::geometry::{RayBoxTest, WatertightRay};
    use crate::params::Params;
    use crate::random::SplitMix64;
    use crate::test_util::with_slivers;

    fn embree(max_leaf_size: usize) -> BvhConfig {
        BvhConfig {
            builder: BvhBuilder::Embree,
            max_leaf_size,
            ..BvhConfig::default()
        }
    }

    /// Small random triangles, and long diagonal slivers across them whose boxes overlap
    /// everything (where spatial splits pay).
    fn slivers_over_small_triangles(seed: u64) -> Vec<Triangle> {
        let mut rng = SplitMix64::new(seed);
        with_slivers(
            (0..2000)
                .map(|_| {
                    let p = rng.vec3(0.0, 10.0);
                    Triangle::new(p, p + rng.vec3(0.0, 0.5), p + rng.vec3(0.0, 0.5))
                })
                .collect(),
        )
    }

    /// Our layout's invariants, and every sampled point of every triangle in a leaf of it.
    fn check_tree(tris: &[Triangle], bvh: &Bvh) {
        if let Err(broken) = bvh_validity::check(bvh, tris) {
            panic!("{broken}");
        }
        assert!(bvh
            .nodes
            .iter()
            .all(|n| !n.is_leaf() || n.count as usize <= bvh.config.max_leaf_size));
    }

    fn closest_in_tree(bvh: &Bvh, origin: Vec3, dir: Vec3) -> Option<f32> {
        let (boxes, ray) = (
            RayBoxTest::new(origin, dir),
            WatertightRay::new(origin, dir),
        );
        let mut best: Option<f32> = None;
        let mut stack = vec![Bvh::ROOT];
        while let Some(i) = stack.pop() {
            let node = &bvh.nodes[i];
            let tmax = best.unwrap_or(f32::INFINITY);
            if boxes.hit(&node.bounds, 0.0, tmax).is_none() {
                continue;
            }
            if node.is_leaf() {
                for k in node.first..node.first + node.count {
                    let tmax = best.unwrap_or(f32::INFINITY);
                    if let Some((t, _, _)) = ray.intersect(&bvh.triangles[k as usize], 0.0, tmax) {
                        best = Some(t);
                    }
                }
            } else {
                stack.extend([node.first as usize, node.first as usize + 1]);
            }
        }
        best
    }

    #[test]
    fn embree_builds_our_layout_with_spatial_splits_and_finds_every_closest_hit() {
        let tris = slivers_over_small_triangles(3);
        let bvh = build_bvh(&tris, embree(4)).unwrap();
        check_tree(&tris, &bvh);
        assert!(
            bvh.triangles.len() > tris.len(),
            "Embree's SBVH split the slivers"
        );
        assert!(
            bvh.triangles.len() as f64 <= SPLIT_REPLICATIONS * tris.len() as f64 + 1.0,
            "{} references",
            bvh.triangles.len()
        );
        // Brute force against the tree on random rays.
        let mut rng = SplitMix64::new(5);
        let mut hits = 0;
        for _ in 0..3000 {
            let origin = rng.vec3(-2.0, 12.0);
            let dir = rng.vec3(0.0, 10.0) - origin;
            let ray = WatertightRay::new(origin, dir);
            let brute = tris
                .iter()
                .filter_map(|t| ray.intersect(t, 0.0, f32::INFINITY).map(|h| h.0))
                .min_by(f32::total_cmp);
            assert_eq!(
                closest_in_tree(&bvh, origin, dir),
                brute,
                "ray from {origin:?}"
            );
            hits += usize::from(brute.is_some());
        }
        assert!(hits > 1000, "only {hits} rays hit");
        // The wide collapse takes it as it takes ours.
        let wide = WideBvh::<8>::collapse(&bvh);
        assert!(!wide.is_empty());
    }

    /// rtcBuildBVH fills the primitive array up to its capacity with split references: given an
    /// array flush against a protected page (ending at it, and starting after one), on the
    /// machine's ISA and on lower ones, it reads and writes only inside, and makes the same tree.
    #[test]
    fn the_builder_keeps_to_its_primitive_array_on_every_isa() {
        use crate::guard_page::{self, Guarded, Placement};
        let tris = slivers_over_small_triangles(3);
        let unguarded = build_bvh(&tris, embree(4)).unwrap();
        let capacity =
            ((tris.len() as f64 * SPLIT_REPLICATIONS).ceil() as usize).max(tris.len() + 1);
        for isa in crate::accel::embree::test_isas() {
            let device = Device::<Embree3>::with_config(isa).unwrap();
            for placement in Placement::BOTH {
                let what = format!("rtcBuildBVH at {isa:?}, {placement:?}");
                let mut primitives =
                    Guarded::new(vec![RTCBuildPrimitive::default(); capacity], placement);
                let bvh = guard_page::call(&what, || {
                    build_in(
                        &device,
                        &tris,
                        embree(4),
                        primitives.as_mut_slice(),
                        Instant::now(),
                    )
                })
                .unwrap();
                check_tree(&tris, &bvh);
                assert!(
                    bvh.triangles.len() > tris.len(),
                    "{what}: no split references"
                );
                assert_eq!(bvh.nodes.len(), unguarded.nodes.len(), "{what}");
            }
        }
    }

    #[test]
    fn embree_tree_quality_is_close_to_our_sbvh_and_beats_plain_sah_on_slivers() {
        let tris = slivers_over_small_triangles(9);
        let ours = |presplit: f32, spatial: f32| {
            Bvh::build(
                &tris,
                BvhConfig {
                    presplit,
                    spatial,
                    bins: 32,
                    ..BvhConfig::default()
                },
            )
        };
        let theirs = build_bvh(&tris, embree(4)).unwrap();
        let (plain, sbvh) = (ours(0.0, 0.0), ours(0.0, 1e-5));
        assert!(
            theirs.sah_cost() < 0.9 * plain.sah_cost(),
            "Embree {} against plain SAH {}",
            theirs.sah_cost(),
            plain.sah_cost()
        );
        // Two SBVHs with the same cost constants: within a quarter of each other.
        let ratio = theirs.sah_cost() / sbvh.sah_cost();
        assert!((0.75..1.25).contains(&ratio), "Embree / ours = {ratio}");
        // Deterministic: the same tree twice.
        let again = build_bvh(&tris, embree(4)).unwrap();
        assert_eq!(again.nodes, theirs.nodes);
        assert_eq!(again.prim_ids, theirs.prim_ids);
    }

    #[test]
    fn leaf_size_and_depth_cap_are_kept_and_a_too_small_cap_is_an_error() {
        let tris = slivers_over_small_triangles(4);
        for leaf in [1, 2, 8] {
            let bvh = build_bvh(&tris, embree(leaf)).unwrap();
            check_tree(&tris, &bvh);
        }
        let capped = BvhConfig {
            max_depth: 16,
            ..embree(4)
        };
        let bvh = build_bvh(&tris, capped).unwrap();
        check_tree(&tris, &bvh);
        assert!(bvh.max_depth() <= 16, "depth {}", bvh.max_depth());
        // 2040 triangles in leaves of 4 need depth 9 at least: 4 levels cannot hold them.
        let err = build_bvh(
            &tris,
            BvhConfig {
                max_depth: 4,
                ..embree(4)
            },
        )
        .unwrap_err();
        assert_eq!(err.exit_code(), 1);
        assert!(err.to_string().contains("depth"), "{err}");
    }

    /// Embree's own leaf policy: no interior node holds 4 or fewer triangle references (such a
    /// node is a leaf), the leaves stay within `leaf_size`, and the tree is valid; our policy on
    /// the same mesh does split small nodes, so the test tells the two apart.
    #[test]
    fn embree_blocks_never_split_four_or_fewer() {
        let tris = slivers_over_small_triangles(8);
        let interior_with_few = |bvh: &Bvh| {
            // References under each node, children before parents (children follow parents).
            let mut under = vec![0usize; bvh.nodes.len()];
            for i in (0..bvh.nodes.len()).rev() {
                let n = &bvh.nodes[i];
                under[i] = if n.is_leaf() {
                    n.count as usize
                } else {
                    under[n.first as usize] + under[n.first as usize + 1]
                };
            }
            (0..bvh.nodes.len())
                .filter(|&i| !bvh.nodes[i].is_leaf() && under[i] <= BvhConfig::EMBREE_BLOCK)
                .count()
        };
        let blocks = BvhConfig {
            builder: BvhBuilder::EmbreeBlocks,
            max_leaf_size: 28,
            ..BvhConfig::default()
        };
        let bvh = build_bvh(&tris, blocks).unwrap();
        check_tree(&tris, &bvh);
        assert_eq!(interior_with_few(&bvh), 0);
        assert!(interior_with_few(&build_bvh(&tris, embree(28)).unwrap()) > 0);
        let err = BvhConfig::from_params(
            &Params::new()
                .with("builder", "embree-blocks")
                .with("leaf_size", 3),
        )
        .unwrap_err();
        assert_eq!(err.exit_code(), 2, "{err}");
    }

    #[test]
    fn tiny_and_empty_meshes() {
        assert!(build_bvh(&[], embree(4)).unwrap().is_empty());
        let one = [Triangle::new(Vec3::ZERO, Vec3::X, Vec3::Y)];
        let bvh = build_bvh(&one, embree(4)).unwrap();
        assert_eq!(bvh.nodes.len(), 1);
        assert!(bvh.nodes[0].is_leaf());
        assert_eq!(bvh.prim_ids, vec![0]);
    }

    #[test]
    fn parameters_the_embree_builder_does_not_read_are_usage_errors() {
        let embree = || Params::new().with("builder", "embree");
        let c =
            BvhConfig::from_params(&embree().with("leaf_size", 8).with("max_depth", 30)).unwrap();
        assert_eq!(
            (c.builder, c.max_leaf_size, c.max_depth),
            (BvhBuilder::Embree, 8, 30)
        );
        for (key, value) in [
            ("bins", "32"),
            ("presplit", "0"),
            ("spatial", "1e-5"),
            ("leaf_size", "33"),
        ] {
            let err = BvhConfig::from_params(&embree().with(key, value)).unwrap_err();
            assert_eq!(err.exit_code(), 2, "{key} = {value}: {err}");
            assert!(err.to_string().contains(key), "{err}");
        }
        let err = BvhConfig::from_params(&Params::new().with("builder", "sah")).unwrap_err();
        assert_eq!(err.exit_code(), 2);
        assert_eq!(
            BvhConfig::from_params(&Params::new()).unwrap().builder,
            BvhBuilder::Raylab
        );
        assert_eq!(
            c.for_moving().unwrap_err().exit_code(),
            2,
            "no motion blur from Embree's builder"
        );
    }
}
