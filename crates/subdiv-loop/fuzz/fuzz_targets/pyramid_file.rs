//! Reading arbitrary bytes as a Loop pyramid file never panics, and whatever loads
//! reconstructs without panicking.

#![no_main]

use libfuzzer_sys::fuzz_target;
use subdiv_loop::pyramid::{LoopPyramid, PYRAMID_MAGIC, PYRAMID_VERSION};

fuzz_target!(|data: &[u8]| {
    // Most inputs get a valid header so that the payload decoder is exercised.
    let mut bytes = Vec::with_capacity(data.len() + 12);
    if data.first().is_some_and(|b| b % 4 != 0) {
        bytes.extend_from_slice(&PYRAMID_MAGIC);
        bytes.extend_from_slice(&PYRAMID_VERSION.to_le_bytes());
    }
    bytes.extend_from_slice(data.get(1..).unwrap_or_default());
    if let Ok(pyramid) = LoopPyramid::from_bytes(&bytes) {
        for level in 0..=pyramid.level_count() {
            let _ = pyramid.reconstruct(level);
        }
        let _ = pyramid.compressed(0.5).map(|p| p.reconstruct(p.level_count()));
    }
});
