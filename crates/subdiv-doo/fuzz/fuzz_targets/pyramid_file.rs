//! Reading a damaged Doo-Sabin pyramid file never panics, and whatever loads
//! reconstructs and compresses without panicking.
//!
//! Random bytes rarely get past the format's header and length prefixes, so most
//! inputs start from a valid file (a small shape refined and decomposed under either
//! boundary rule, details nudged) and damage it: bytes overwritten, a range cut out, or the file truncated.

#![no_main]

use arbitrary::{Arbitrary, Unstructured};
use libfuzzer_sys::fuzz_target;
use mesh_topo::HalfedgeMesh;
use mesh_topo::shapes::{self, CellKind};
use subdiv_doo::pyramid::{DecomposeOptions, DooPyramid, decompose};
use subdiv_doo::{BoundaryRule, DooOptions, FaceRule, subdivide};

fn valid_file(u: &mut Unstructured<'_>) -> arbitrary::Result<Option<Vec<u8>>> {
    let base = match u.int_in_range(0..=3)? {
        0 => shapes::cube(),
        1 => shapes::tetrahedron(),
        2 => shapes::torus(3, 4, CellKind::Mixed).unwrap(),
        _ => shapes::grid(3, 2, CellKind::Quads).unwrap(),
    };
    let rule = *u.choose(&[FaceRule::DooSabin, FaceRule::Simple, FaceRule::CENTROID_HALF])?;
    let levels = u.int_in_range(1..=2)?;
    let boundary = if bool::arbitrary(u)? { BoundaryRule::Chaikin } else { BoundaryRule::Shrink };
    let Ok(mesh) = HalfedgeMesh::from_soup(&base) else { return Ok(None) };
    let Ok(fine) = subdivide(&mesh, &DooOptions::new(rule, levels).with_boundary(boundary)) else { return Ok(None) };
    let Ok(mut fine) = fine.to_mesh() else { return Ok(None) };
    if let Some(p) = fine.positions_mut().first_mut() {
        p.x += f64::from(i8::arbitrary(u)?) / 64.0;
    }
    let Ok(decomposition) = decompose(&fine, &DecomposeOptions::levels(rule, levels).with_boundary(boundary)) else { return Ok(None) };
    Ok(decomposition.pyramid.to_bytes().ok())
}

fuzz_target!(|data: &[u8]| {
    let mut u = Unstructured::new(data);
    let make = |u: &mut Unstructured<'_>| -> arbitrary::Result<Vec<u8>> {
        if u8::arbitrary(u)? % 8 == 0 {
            return Ok(u.bytes(u.len())?.to_vec());
        }
        let Some(mut bytes) = valid_file(u)? else { return Ok(Vec::new()) };
        for _ in 0..u.int_in_range(0..=3)? {
            match u.int_in_range(0..=2)? {
                0 => {
                    let at = u.int_in_range(0..=bytes.len() - 1)?;
                    bytes[at] = u8::arbitrary(u)?;
                }
                1 => {
                    let from = u.int_in_range(0..=bytes.len() - 1)?;
                    let to = u.int_in_range(from..=bytes.len())?;
                    bytes.drain(from..to);
                }
                _ => {
                    let keep = u.int_in_range(0..=bytes.len())?;
                    bytes.truncate(keep);
                }
            }
            if bytes.is_empty() {
                break;
            }
        }
        Ok(bytes)
    };
    let Ok(bytes) = make(&mut u) else { return };
    if let Ok(pyramid) = DooPyramid::from_bytes(&bytes) {
        for level in 0..=pyramid.level_count() {
            let _ = pyramid.reconstruct(level, None);
            let _ = pyramid.reconstruct(level, Some(0.5));
        }
        let _ = pyramid.rate_distortion(&[0.0, 0.25, 1.0]);
        if let Ok(prepared) = pyramid.prepare() {
            let _ = prepared.reconstruct(pyramid.level_count(), Some(0.1));
        }
    }
});
