//! Golden files: text outputs compared with the blessed copies in `tests/golden/`
//! (numbers within a relative tolerance of 1e-12). Re-bless with
//! `cargo xtask golden --bless` and review the diff.

mod common;

use multires::mesh::HalfedgeMesh;
use multires::mesh::shapes::{self, CellKind};

#[test]
fn topology_of_procedural_shapes() {
    let mut text = String::new();
    for (name, soup) in [
        ("tetrahedron", shapes::tetrahedron()),
        ("cube", shapes::cube()),
        ("icosahedron", shapes::icosahedron()),
        ("grid-mixed-4x3", shapes::grid(4, 3, CellKind::Mixed)),
        ("torus-quads-8x5", shapes::torus(8, 5, CellKind::Quads)),
    ] {
        let stats = HalfedgeMesh::from_soup(&soup).unwrap().topology_stats();
        text.push_str(&format!("{name} {}\n", serde_json::to_string(&stats).unwrap()));
    }
    common::check_golden("shapes-topology.txt", &text);
}
