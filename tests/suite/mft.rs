//! The multi-frusta tracer's native light-visibility answer beside the reference tracer's shadow
//! rays, over its block sizes and tree widths (every tracer's bits against Embree's are in
//! visibility.rs).

use raylab::tracers::Params;

use crate::visibility::{scenes, visibility};

/// The multi-frusta tracer answers natively (its rays made on demand inside frusta); the reference
/// tracer answers by tracing the same sample rays as ordinary shadow rays: the bits must be equal.
#[test]
fn mft_bits_equal_the_reference_tracers_shadow_rays() {
    for (name, scene) in scenes() {
        let (expected, rays) = visibility(&scene, "reference", &Params::new());
        for (block, width) in [(4, 2), (16, 2), (64, 2), (16, 4), (16, 8)] {
            let params = Params::new().with("block", block).with("width", width);
            let (got, _) = visibility(&scene, "mft", &params);
            assert_eq!(
                got, expected,
                "{name}: mft block {block} width {width} ({rays} rays)"
            );
        }
    }
}
