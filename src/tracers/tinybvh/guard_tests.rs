//! Every call raylab makes into tinybvh through its shim — the build of each layout by each
//! builder, `Intersect` and `IsOccluded` of `BVH`, `BVH4_CPU` and `BVH8_CPU`, and
//! `Intersect256Rays` with and without SSE — with its vertices, rays, flags or packet flush
//! against a protected page (ending at one, and starting after one): a read or write past them
//! faults here (`guard_page`). The answers are checked against the binary layout's single rays.
//!
//! tinybvh picks its SIMD paths when the shim is compiled (`-march=native`: SSE4.2, AVX, AVX2 +
//! FMA; it has no AVX-512 code), not at run time, so there is no lower ISA to force here: an
//! AVX-512 machine runs the AVX2 paths an AVX2 machine runs.

use std::time::Instant;

use super::tile::{order, PACKET};
use crate::accel::tinybvh::ffi::TinyRay;
use crate::accel::tinybvh::TinyBuilder;
use crate::accel::{TinyBvh, TinyBvhConfig, TinyLayout};
use crate::guard_page::{self, Guarded, Placement};

/// An 8 × 8 grid of unit squares in the plane z = 0, two triangles each, as tinybvh's vertices.
fn grid() -> Vec<[f32; 4]> {
    let mut vertices = Vec::new();
    for j in 0..8 {
        for i in 0..8 {
            let (x, y) = (i as f32, j as f32);
            let corner = |dx: f32, dy: f32| [x + dx, y + dy, 0.0, 0.0];
            vertices.extend([corner(0.0, 0.0), corner(1.0, 0.0), corner(1.0, 1.0)]);
            vertices.extend([corner(0.0, 0.0), corner(1.0, 1.0), corner(0.0, 1.0)]);
        }
    }
    vertices
}

/// 37 rays down onto the grid from z = 2, some beside it; every fourth ends above it.
fn rays() -> Vec<TinyRay> {
    (0..37)
        .map(|i| {
            let (x, y) = (-1.3 + 0.29 * i as f32, 0.37 + 0.21 * i as f32);
            let far = if i % 4 == 3 { 1.0 } else { f32::INFINITY };
            TinyRay::new([x, y, 2.0], [0.0, 0.0, -1.0], far)
        })
        .collect()
}

/// 256 rays from (4, 4, 6) through a 16 × 16 block over the grid, in `Intersect256Rays`'s order
/// and mirrored left to right (`tile::mirrored`: forward −z × up +y points right).
fn packet() -> Vec<TinyRay> {
    let mut packet = vec![TinyRay::new([0.0; 3], [0.0, 0.0, -1.0], f32::INFINITY); PACKET];
    for dy in 0..16 {
        for dx in 0..16 {
            let x = 4.0 + 5.0 * (0.5 - (dx as f32 + 0.5) / 16.0);
            // Off by 0.13 in y: no ray meets a diagonal, where two triangles tie.
            let y = 4.13 + 5.0 * (0.5 - (dy as f32 + 0.5) / 16.0);
            packet[order(dx, dy)] = TinyRay::new([4.0, 4.0, 6.0], [x - 4.0, y - 4.0, -6.0], 1e30);
        }
    }
    packet
}

/// (t, prim) of each ray's hit, `None` for a miss: traced one by one through `tree`.
fn hits(tree: &TinyBvh, rays: &mut [TinyRay]) -> Vec<Option<(f32, u32)>> {
    let far: Vec<f32> = rays.iter().map(|r| r.t).collect();
    tree.intersect(rays);
    rays.iter()
        .zip(far)
        .map(|(r, far)| (r.t < far).then_some((r.t, r.prim)))
        .collect()
}

#[test]
fn tinybvh_reads_and_writes_only_the_buffers_raylab_hands_it() {
    let vertices = grid();
    let config = |builder| TinyBvhConfig {
        builder,
        optimize: 0,
    };
    let binary = TinyBvh::build_from(
        &vertices,
        TinyLayout::Binary,
        config(TinyBuilder::Sah),
        1.0,
        Instant::now(),
    )
    .unwrap();
    let single = hits(&binary, &mut rays());
    let block = hits(&binary, &mut packet());
    assert!(single.iter().flatten().count() > 10, "rays hit the grid");
    assert!(
        block.iter().all(Option::is_some),
        "the block lies on the grid"
    );
    for layout in [TinyLayout::Binary, TinyLayout::Wide4, TinyLayout::Wide8] {
        for builder in [TinyBuilder::Sah, TinyBuilder::Sbvh] {
            for placement in Placement::BOTH {
                let what = format!("{} by {builder:?}, {placement:?}", layout.class());
                let mut guarded = Guarded::new(vertices.clone(), placement);
                let tree = guard_page::call(&format!("the build of {what}"), || {
                    TinyBvh::build_from(
                        guarded.as_mut_slice(),
                        layout,
                        config(builder),
                        1.0,
                        Instant::now(),
                    )
                })
                .unwrap();
                drop(guarded);

                let mut closest = Guarded::new(rays(), placement);
                let got = guard_page::call(&format!("Intersect of {what}"), || {
                    hits(&tree, closest.as_mut_slice())
                });
                for (i, (g, want)) in got.iter().zip(&single).enumerate() {
                    let same = match (g, want) {
                        (Some(g), Some(w)) => (g.0 - w.0).abs() < 1e-4,
                        (g, w) => g.is_none() && w.is_none(),
                    };
                    assert!(same, "{what}: ray {i} {g:?}, not {want:?}");
                }

                let mut shadows = Guarded::new(rays(), placement);
                let mut flags = Guarded::new(vec![7u8; single.len()], placement);
                guard_page::call(&format!("IsOccluded of {what}"), || {
                    tree.occluded(shadows.as_mut_slice(), flags.as_mut_slice())
                });
                let want: Vec<u8> = single.iter().map(|h| u8::from(h.is_some())).collect();
                assert_eq!(flags.as_mut_slice(), &want[..], "{what}");

                if layout == TinyLayout::Binary {
                    for sse in [false, true] {
                        let mut rays = Guarded::new(packet(), placement);
                        let block_rays: &mut [TinyRay; PACKET] =
                            rays.as_mut_slice().try_into().unwrap();
                        let traced = guard_page::call(
                            &format!("Intersect256Rays (sse = {sse}) of {what}"),
                            || tree.intersect256(block_rays, sse),
                        );
                        assert!(traced, "{what}");
                        for (i, (r, want)) in rays.as_mut_slice().iter().zip(&block).enumerate() {
                            let want = want.map(|w| w.1);
                            assert_eq!(Some(r.prim), want, "{what}, sse = {sse}: ray {i}");
                        }
                    }
                }
            }
        }
    }
}
